#include "polrig/geometry/schedule.h"

#include <cmath>

namespace polrig {

std::vector<double> Schedule::table_angles_deg() const {
  if (!angles_deg.empty()) return angles_deg;
  if (count > 0) {
    std::vector<double> out(static_cast<std::size_t>(count));
    for (int k = 0; k < count; ++k) out[static_cast<std::size_t>(k)] = start_deg + static_cast<double>(k) * step_deg;
    return out;
  }
  // Count first, then compute each angle from its index: no accumulated rounding, and the end
  // point is included when (stop − start)/step is an integer up to rounding.
  const long n = static_cast<long>(std::floor((stop_deg - start_deg) / step_deg + 1e-9)) + 1;
  std::vector<double> out;
  out.reserve(static_cast<std::size_t>(n));
  for (long i = 0; i < n; ++i) out.push_back(start_deg + static_cast<double>(i) * step_deg);
  return out;
}

std::vector<double> Schedule::stop_times_s() const {
  const std::vector<double> angles = table_angles_deg();
  std::vector<double> t(angles.size(), 0.0);
  double turning = 0;  // Σ |Δθ|/speed, summed in stop order
  for (std::size_t k = 1; k < angles.size(); ++k) {
    turning += std::abs(angles[k] - angles[k - 1]) / speed_deg_s;
    t[k] = turning + static_cast<double>(k) * dwell_s;
  }
  return t;
}

}  // namespace polrig
