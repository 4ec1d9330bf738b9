// Vectorised logarithms for the CS study (1080 a grid point at 360 steps: the sweep's hot loop).
//
// Highway (libhwy-dev), chosen over Eigen's array log, xsimd and SLEEF by measurement
// (bench/bench_vector_log.cpp, docs/validation.md): its Log is the cheapest polynomial of the four
// and its run-time dispatch lets one baseline x86-64 build use AVX2 or AVX-512 where the CPU has
// them. The results must not depend on the CPU (sweeps are bit-identical for any thread or MPI rank
// count, and ranks may run on different machines), so every compiled path does the same IEEE
// operations lane by lane:
//  - no fused multiply-add anywhere: SameBitsLog below is Highway's Log (hwy/contrib/math,
//    impl::Log<double>, musl's log.c) with each MulAdd written as Add(Mul(·,·),·) and each MulSub
//    as Sub(Mul(·,·),·) (Highway's MulAdd is always fused on the AVX-512 targets), and this file is
//    compiled with -ffp-contract=off so that the compiler fuses nothing either (tests/check_no_fma.sh
//    reads the generated code); the other operations (integer adds and shifts on the bits, an exact
//    int64 → double conversion of the exponent, one division) are exact or correctly rounded on
//    every target;
//  - AVX3_DL (and later AVX-512 targets) are not compiled: AVX3 already gives the 8 lanes;
// and tests/test_vector_log.cpp checks that the paths this CPU can run agree bit for bit. The
// polynomial and its operation order are Highway's, so the AVX2, SSE4 and baseline results are
// the bits of the earlier version (which used Highway's Log with HWY_DISABLE_BMI2_FMA).
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
#ifdef HWY_AVX3_ZEN4
#define HWY_DISABLED_TARGETS (HWY_AVX3_DL | HWY_AVX3_ZEN4)
#else
#define HWY_DISABLED_TARGETS (HWY_AVX3_DL)
#endif

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "vector_log.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace polrig {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// ln x for positive finite x (subnormals included), Highway's impl::Log<double> without fused
// operations: within 2 ulp (Highway's bound; test_vector_log measures 0.94).
template <class D, class V>
HWY_INLINE V SameBitsLog(D d, V x) {
  const hn::RebindToSigned<D> di;
  const hn::RebindToUnsigned<D> du;
  using VI = hn::Vec<decltype(di)>;
  const V kLn2Hi = hn::Set(d, 0.693147180369123816490), kLn2Lo = hn::Set(d, 1.90821492927058770002e-10);
  const V kOne = hn::Set(d, 1.0), kMinNormal = hn::Set(d, 2.2250738585072014e-308);
  const V kScale = hn::Set(d, 1.8014398509481984e+16);  // 2^54: a subnormal x scaled to a normal one
  const VI kLowerBits = hn::Set(di, 0xFFFFFFFFLL), kMagic = hn::Set(di, 0x3FE6A09E00000000LL);
  const VI kExpMask = hn::Set(di, 0x3FF0000000000000LL), kExpScale = hn::Set(di, -54LL);
  const VI kManMask = hn::Set(di, 0xFFFFF00000000LL);
  // x = 2^e·y with y in [√2/2, √2).
  const auto is_denormal = hn::Lt(x, kMinNormal);
  x = hn::IfThenElse(is_denormal, hn::Mul(x, kScale), x);
  const VI exp_bits = hn::Add(hn::BitCast(di, x), hn::Sub(kExpMask, kMagic));
  const VI exp_scale = hn::BitCast(di, hn::IfThenElseZero(is_denormal, hn::BitCast(d, kExpScale)));
  const VI log2p1 = hn::Sub(hn::BitCast(di, hn::ShiftRight<52>(hn::BitCast(du, exp_bits))), hn::Set(di, 0x3FF));
  const V exp = hn::ConvertTo(d, hn::Add(exp_scale, log2p1));
  const V y = hn::Or(hn::And(x, hn::BitCast(d, kLowerBits)), hn::BitCast(d, hn::Add(hn::And(exp_bits, kManMask), kMagic)));
  // ln y = 2 atanh z, z = (y − 1)/(y + 1): musl's polynomial in z², evaluated as Highway's
  // LogPoly, MulAdd(a, b, c) → a·b + c.
  const V ym1 = hn::Sub(y, kOne);
  const V z = hn::Div(ym1, hn::Add(y, kOne));
  const V z2 = hn::Mul(z, z), z4 = hn::Mul(z2, z2);
  const auto mul_add = [](V a, V b, V c) { return hn::Add(hn::Mul(a, b), c); };
  const V k0 = hn::Set(d, 0.6666666666666735130), k1 = hn::Set(d, 0.3999999999940941908);
  const V k2 = hn::Set(d, 0.2857142874366239149), k3 = hn::Set(d, 0.2222219843214978396);
  const V k4 = hn::Set(d, 0.1818357216161805012), k5 = hn::Set(d, 0.1531383769920937332);
  const V k6 = hn::Set(d, 0.1479819860511658591);
  const V poly = mul_add(mul_add(mul_add(mul_add(k6, z4, k4), z4, k2), z4, k0), z2,
                         hn::Mul(mul_add(mul_add(k5, z4, k3), z4, k1), z4));
  // e·ln2_hi − ((z·(y − 1 − poly) − e·ln2_lo) − (y − 1)), MulSub(a, b, c) → a·b − c.
  const V inner = hn::Sub(hn::Mul(z, hn::Sub(ym1, poly)), hn::Mul(exp, kLn2Lo));
  return hn::Sub(hn::Mul(exp, kLn2Hi), hn::Sub(inner, ym1));
}

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
    hn::StoreU(SameBitsLog(d, v), d, y + i);
    if (HWY_UNLIKELY(!hn::AllTrue(d, hn::And(hn::Gt(v, zero), hn::Le(v, largest))))) special_values(d, v, y + i, lanes);
  }
  if (i < n) {  // the tail, padded with ones into a whole vector
    HWY_ALIGN double tail[hn::MaxLanes(d)];
    for (std::size_t k = 0; k < lanes; ++k) tail[k] = i + k < n ? x[i + k] : 1.0;
    const auto v = hn::Load(d, tail);
    hn::Store(SameBitsLog(d, v), d, tail);
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
std::atomic<SimdPaths> widest_allowed{SimdPaths::Avx512};

SimdPaths cpu_paths() {
  static const SimdPaths cpu = __builtin_cpu_supports("avx512f") ? SimdPaths::Avx512
                               : __builtin_cpu_supports("avx2")  ? SimdPaths::Avx2
                                                                 : SimdPaths::Baseline;
  return cpu;
}
}  // namespace

SimdPaths simd_paths() { return std::min(cpu_paths(), widest_allowed.load(std::memory_order_relaxed)); }
bool avx2_paths() { return simd_paths() >= SimdPaths::Avx2; }
bool avx512_paths() { return simd_paths() >= SimdPaths::Avx512; }
void set_widest_paths(SimdPaths w) { widest_allowed.store(w); }
void set_baseline_paths_only(bool on) { set_widest_paths(on ? SimdPaths::Baseline : SimdPaths::Avx512); }

void log_array(const double* x, double* y, std::size_t n) {
  switch (simd_paths()) {
    case SimdPaths::Baseline:
#if HWY_TARGETS & HWY_SCALAR
      return N_SCALAR::LogArray(x, y, n);
#else
      break;
#endif
    case SimdPaths::Avx2:
#if HWY_TARGETS & HWY_AVX2
      return N_AVX2::LogArray(x, y, n);
#else
      break;
#endif
    case SimdPaths::Avx512: break;
  }
  HWY_DYNAMIC_DISPATCH(LogArray)(x, y, n);
}

std::vector<LogArrayPath> log_array_paths() {
  std::vector<LogArrayPath> paths;
  const std::int64_t cpu = hwy::SupportedTargets();
  const auto add = [&](std::int64_t target, void (*f)(const double*, double*, std::size_t)) {
    if (cpu & target) paths.push_back({hwy::TargetName(target), f});
  };
#if HWY_TARGETS & HWY_AVX3
  add(HWY_AVX3, &N_AVX3::LogArray);
#endif
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
