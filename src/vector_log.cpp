// Vectorised logarithms for the CS study (1080 a grid point at 360 steps: the sweep's hot loop).
//
// Highway (libhwy-dev), chosen over Eigen's array log, xsimd and SLEEF by measurement
// (bench/bench_vector_log.cpp, docs/validation.md): its Log is the cheapest polynomial of the four
// and its run-time dispatch lets one baseline x86-64 build use AVX2 where the CPU has it. The
// results must not depend on the CPU (sweeps are bit-identical for any thread or MPI rank count,
// and ranks may run on different machines), so every compiled path does the same IEEE operations
// lane by lane:
//  - no fused multiply-add anywhere: HWY_DISABLE_BMI2_FMA makes the AVX2 target's MulAdd a
//    multiply then an add, as on SSSE3, SSE4 and the baseline (HWY_SCALAR), and this file is compiled with
//    -ffp-contract=off so the compiler fuses nothing either; the AVX-512 targets, whose MulAdd
//    is always fused, are not compiled;
//  - whole vectors only (a tail is padded into one), since Highway's 128-bit MulAdd on the AVX2
//    target would be fused;
// and tests/test_vector_log.cpp checks that the paths this CPU can run agree bit for bit.
#include "polrig/vector_log.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>

#ifndef HWY_DISABLE_BMI2_FMA
#define HWY_DISABLE_BMI2_FMA
#endif
#undef HWY_DISABLED_TARGETS
#define HWY_DISABLED_TARGETS (HWY_AVX3 | HWY_AVX3_DL)

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "vector_log.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/contrib/math/math-inl.h>
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace polrig {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// The lanes of y (in a vector) where x is not positive and finite (what Highway's Log is meant
// for) take std::log's exact special value of x instead.
template <class D, class V>
void special_values(D d, V x, double* y, std::size_t lanes) {
  HWY_ALIGN double xs[hn::MaxLanes(d)];
  hn::Store(x, d, xs);
  for (std::size_t k = 0; k < lanes; ++k)
    if (!(xs[k] > 0.0 && xs[k] <= std::numeric_limits<double>::max())) y[k] = std::log(xs[k]);
}

// y[i] = ln x[i], also in place (x == y: each vector is read before its logarithms are stored).
void LogArray(const double* x, double* y, std::size_t n) {
  const hn::ScalableTag<double> d;
  const std::size_t lanes = hn::Lanes(d);
  const auto zero = hn::Zero(d);
  const auto largest = hn::Set(d, std::numeric_limits<double>::max());
  std::size_t i = 0;
  for (; i + lanes <= n; i += lanes) {
    const auto v = hn::LoadU(d, x + i);
    hn::StoreU(hn::Log(d, v), d, y + i);
    if (HWY_UNLIKELY(!hn::AllTrue(d, hn::And(hn::Gt(v, zero), hn::Le(v, largest))))) special_values(d, v, y + i, lanes);
  }
  if (i < n) {  // the tail, padded with ones into a whole vector
    HWY_ALIGN double tail[hn::MaxLanes(d)];
    for (std::size_t k = 0; k < lanes; ++k) tail[k] = i + k < n ? x[i + k] : 1.0;
    const auto v = hn::Load(d, tail);
    hn::Store(hn::Log(d, v), d, tail);
    special_values(d, v, tail, lanes);
    for (std::size_t k = 0; i + k < n; ++k) y[i + k] = tail[k];
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace polrig
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace polrig {

HWY_EXPORT(LogArray);

namespace {
std::atomic<bool> baseline_only{false};
}  // namespace

bool avx2_paths() {
  static const bool cpu_has_avx2 = __builtin_cpu_supports("avx2");
  return cpu_has_avx2 && !baseline_only.load(std::memory_order_relaxed);
}

void set_baseline_paths_only(bool on) { baseline_only.store(on); }

void log_array(const double* x, double* y, std::size_t n) {
#if HWY_TARGETS & HWY_SCALAR
  if (baseline_only.load(std::memory_order_relaxed)) return N_SCALAR::LogArray(x, y, n);
#endif
  HWY_DYNAMIC_DISPATCH(LogArray)(x, y, n);
}

std::vector<LogArrayPath> log_array_paths() {
  std::vector<LogArrayPath> paths;
  const std::int64_t cpu = hwy::SupportedTargets();
  const auto add = [&](std::int64_t target, void (*f)(const double*, double*, std::size_t)) {
    if (cpu & target) paths.push_back({hwy::TargetName(target), f});
  };
#if HWY_TARGETS & HWY_AVX2
  add(HWY_AVX2, &N_AVX2::LogArray);
#endif
#if HWY_TARGETS & HWY_SSE4
  add(HWY_SSE4, &N_SSE4::LogArray);
#endif
#if HWY_TARGETS & HWY_SSSE3
  add(HWY_SSSE3, &N_SSSE3::LogArray);
#endif
#if HWY_TARGETS & HWY_EMU128
  add(HWY_EMU128, &N_EMU128::LogArray);
#endif
#if HWY_TARGETS & HWY_SCALAR
  add(HWY_SCALAR, &N_SCALAR::LogArray);  // the baseline build's own: any x86-64
#endif
  (void)add;
  return paths;
}

}  // namespace polrig
#endif
