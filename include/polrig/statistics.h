#pragma once
// The two summaries of a sample that polrig reports, computed in two passes (no cancellation).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>

namespace polrig {

struct MeanAndSpread {
  double mean = 0;
  double sd = 0;
};

// Sums in one fixed interleaved order, the same on every CPU and for every vector width: eight
// partial sums s_j = Σ_{k ≡ j (mod 8)} x_k, each in index order, then
//   ((s_0 + s_4) + (s_2 + s_6)) + ((s_1 + s_5) + (s_3 + s_7)).
// The eight chains are independent (an AVX-512 register holds them, two AVX2 registers or eight
// scalars), so adds overlap instead of waiting for each other; the error bound is a sequential
// sum's with n/8 + 3 in place of n − 1 terms.
inline constexpr int kSumLanes = 8;
inline double combine_lanes(const double (&s)[kSumLanes]) {
  return ((s[0] + s[4]) + (s[2] + s[6])) + ((s[1] + s[5]) + (s[3] + s[7]));
}
inline double interleaved_sum(std::span<const double> x) {
  double s[kSumLanes] = {};
  for (std::size_t k = 0; k < x.size(); ++k) s[k % kSumLanes] += x[k];
  return combine_lanes(s);
}

// Mean and population standard deviation (divide by n): BSD and ASD over a turn. Both sums in
// interleaved_sum's order (src/study/cs.cpp sums six curves side by side in the same order).
inline MeanAndSpread mean_and_population_sd(std::span<const double> x) {
  const double mean = interleaved_sum(x) / static_cast<double>(x.size());
  double s[kSumLanes] = {};
  for (std::size_t k = 0; k < x.size(); ++k) s[k % kSumLanes] += (x[k] - mean) * (x[k] - mean);
  return {mean, std::sqrt(combine_lanes(s) / static_cast<double>(x.size()))};
}

// Mean of independent estimates (batches, quasi-random shifts) and its standard error: the
// sample standard deviation (n − 1) over √n; 0 for a single estimate.
inline MeanAndSpread mean_and_standard_error(std::span<const double> x) {
  const double n = static_cast<double>(x.size());
  const double mean = mean_and_population_sd(x).mean;
  if (x.size() < 2) return {mean, 0.0};
  double ss = 0;
  for (double v : x) ss += (v - mean) * (v - mean);
  return {mean, std::sqrt(ss / (n - 1) / n)};
}

// The q-quantile of a sorted sample by linear interpolation between order statistics (type 7, as
// R's and NumPy's default); NaN for an empty sample.
inline double quantile_of_sorted(std::span<const double> sorted, double q) {
  if (sorted.empty()) return std::nan("");
  const double pos = q * static_cast<double>(sorted.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (pos - static_cast<double>(lo)) * (sorted[hi] - sorted[lo]);
}

// The p-quantile of χ²(n)/n from the normal quantile z_p, by Wilson and Hilferty's cube-root
// normal approximation (against the tables: < 0.8 % relative in the 2.5 % tail at n = 10, < 0.05 %
// for n ≥ 40; the 97.5 % tail < 1e-4 from n = 10).
inline double chi2_mean_quantile(double n, double z_p) {
  const double a = 2.0 / (9.0 * n);
  const double c = 1 - a + z_p * std::sqrt(a);
  return c * c * c;
}
inline constexpr double kNormalQuantile975 = 1.959963984540054;

}  // namespace polrig
