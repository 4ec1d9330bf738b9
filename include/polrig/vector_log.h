#pragma once
// Natural logarithms of arrays, vectorised, with results that are bit for bit the same on every
// x86-64 CPU and for every code path (src/vector_log.cpp says how and why this library).
#include <cstddef>
#include <string>
#include <vector>

namespace polrig {

// y[i] = ln x[i] for i in [0, n); x and y are the same array or do not overlap. Within 2 ulp of the exact value
// for every positive finite x, subnormals included (Highway's bound; 0.94 ulp is the largest
// error tests/test_vector_log.cpp finds); 0, negatives, inf and NaN give what std::log gives.
void log_array(const double* x, double* y, std::size_t n);

// Whether the CS study's AVX2 code paths run (src/study/cs.cpp, src/source/cos4_port.cpp): the
// CPU has AVX2 and set_baseline_paths_only is off. Those paths do the same IEEE operations in the
// same order as the baseline x86-64 ones, on more values at a time: the same bits.
bool avx2_paths();
// For tests: from now on, only the baseline x86-64 paths run (log_array's too), or the best again.
void set_baseline_paths_only(bool on);

// Every code path of log_array that this CPU can run, by name (for the test that they agree bit
// for bit); log_array runs the first.
struct LogArrayPath {
  std::string name;
  void (*log_array)(const double* x, double* y, std::size_t n);
};
std::vector<LogArrayPath> log_array_paths();

}  // namespace polrig
