#pragma once
// The library comparison of vectorised natural logarithms (bench_vector_log*.cpp): each case
// takes 1080 logarithms (3 pairs × 360 table angles, one CS study's count) of ratios in the range
// the CS study produces, into an output array.
#include <cstddef>
#include <vector>

namespace polrig_bench {

inline std::vector<double> study_like_ratios() {
  std::vector<double> x(1080);
  // E_j/E_h of an eccentric rig stays within a few per cent of 1 (docs/validation.md).
  for (std::size_t k = 0; k < x.size(); ++k) x[k] = 0.95 + 1e-4 * static_cast<double>(k);
  return x;
}

// Defined in bench_vector_log_hwy.cpp (Highway's dynamic dispatch: the best target of this CPU).
void highway_log(const double* x, double* y, std::size_t n);
// Defined in bench_vector_log_avx2.cpp (compiled with -mavx2 -mno-fma): call only when the CPU
// has AVX2.
bool eigen_avx2_log(const double* x, double* y, std::size_t n);
bool xsimd_avx2_log(const double* x, double* y, std::size_t n);

}  // namespace polrig_bench
