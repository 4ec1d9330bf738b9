// Highway's Log (hwy/contrib/math) over an array, dispatched at run time to the best target of
// the CPU (its own FMA on AVX2/AVX-512): for the library comparison in bench_vector_log.cpp.
#include <cstddef>

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "bench_vector_log_hwy.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep

#include <hwy/contrib/math/math-inl.h>
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace polrig_bench {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

void LogArray(const double* x, double* y, std::size_t n) {
  const hn::ScalableTag<double> d;
  const std::size_t lanes = hn::Lanes(d);
  std::size_t i = 0;
  for (; i + lanes <= n; i += lanes) hn::StoreU(hn::Log(d, hn::LoadU(d, x + i)), d, y + i);
  const hn::CappedTag<double, 1> d1;
  for (; i < n; ++i) hn::StoreU(hn::Log(d1, hn::LoadU(d1, x + i)), d1, y + i);
}

}  // namespace HWY_NAMESPACE
}  // namespace polrig_bench
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace polrig_bench {
HWY_EXPORT(LogArray);
void highway_log(const double* x, double* y, std::size_t n) { HWY_DYNAMIC_DISPATCH(LogArray)(x, y, n); }
}  // namespace polrig_bench
#endif
