// Eigen's and xsimd's AVX2 logarithms, this file alone compiled with -mavx2 -mno-fma
// -ffp-contract=off (bench/CMakeLists.txt), called only when the CPU has AVX2 (asked by the
// caller, in baseline code). Eigen is used
// through its Packet4d functions, which exist in no other file, so that no inline function
// compiled here for AVX2 can stand in for the baseline build's own.
#include <cstddef>

#include <Eigen/Core>
#include <xsimd/xsimd.hpp>

#include "vector_log_cases.h"

namespace polrig_bench {

bool eigen_avx2_log(const double* x, double* y, std::size_t n) {
  using Eigen::internal::Packet4d;
  for (std::size_t i = 0; i + 4 <= n; i += 4)
    Eigen::internal::pstoreu(y + i, Eigen::internal::plog(Eigen::internal::ploadu<Packet4d>(x + i)));
  return true;
}

bool xsimd_avx2_log(const double* x, double* y, std::size_t n) {
  using batch = xsimd::batch<double, xsimd::avx2>;
  for (std::size_t i = 0; i + batch::size <= n; i += batch::size)
    xsimd::log(batch::load_unaligned(x + i)).store_unaligned(y + i);
  return true;
}

}  // namespace polrig_bench
