#include "polrig/ins/allan.h"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace polrig {

std::vector<AllanPoint> allan_deviation(std::span<const double> rate, double dt_s, long min_clusters) {
  if (!(dt_s > 0) || min_clusters < 1)
    throw std::invalid_argument(fmt::format("Allan deviation: Δt {} s must be > 0 and min_clusters {} ≥ 1",
                                            dt_s, min_clusters));
  const long N = static_cast<long>(rate.size());
  // θ relative to the series' mean rate: the second differences cancel it, and θ stays small.
  double mean = 0;
  for (double y : rate) mean += y;
  mean = N > 0 ? mean / static_cast<double>(N) : 0.0;
  std::vector<double> theta(static_cast<std::size_t>(N) + 1, 0.0);
  for (long k = 0; k < N; ++k) theta[k + 1] = theta[k] + (rate[k] - mean) * dt_s;
  std::vector<AllanPoint> out;
  for (long m = 1; N - 2 * m + 1 >= min_clusters; m *= 2) {
    const long terms = N - 2 * m + 1;
    double sum = 0;
    for (long k = 0; k < terms; ++k) {
      const double d = theta[k + 2 * m] - 2 * theta[k + m] + theta[k];
      sum += d * d;
    }
    const double tau = static_cast<double>(m) * dt_s;
    out.push_back({tau, std::sqrt(sum / (2 * tau * tau * static_cast<double>(terms))), terms});
  }
  return out;
}

}  // namespace polrig
