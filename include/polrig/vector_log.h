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

// The widest code paths polrig's vectorised loops run (log_array, src/study/cs.cpp,
// src/source/cos4_port.cpp, and AVX2 for src/sim/dofp_frames.cpp and the four-camera fusion): the
// CPU's best, capped by set_widest_paths. Every path does the same IEEE operations in the same
// order as the baseline x86-64 one, on more values at a time: the same bits.
enum class SimdPaths { Baseline, Avx2, Avx512 };
SimdPaths simd_paths();
bool avx2_paths();    // simd_paths() ≥ Avx2 (the CPU has AVX2)
bool avx512_paths();  // simd_paths() ≥ Avx512 (the CPU has AVX-512F)
// For tests: from now on no path wider than `widest` runs (log_array's too), or the CPU's best
// again with Avx512. set_baseline_paths_only(on) is set_widest_paths(on ? Baseline : Avx512).
void set_widest_paths(SimdPaths widest);
void set_baseline_paths_only(bool on);

// Every code path of log_array that this CPU can run, by name (for the test that they agree bit
// for bit); log_array runs the first.
struct LogArrayPath {
  std::string name;
  void (*log_array)(const double* x, double* y, std::size_t n);
};
std::vector<LogArrayPath> log_array_paths();

}  // namespace polrig
