#include "polrig/geometry/schedule.h"

#include <cmath>

namespace polrig {

std::vector<double> Schedule::table_angles_deg() const {
  if (!angles_deg.empty()) return angles_deg;
  // Count first, then compute each angle from its index: no accumulated rounding, and the end
  // point is included when (stop − start)/step is an integer up to rounding.
  const long n = static_cast<long>(std::floor((stop_deg - start_deg) / step_deg + 1e-9)) + 1;
  std::vector<double> out;
  out.reserve(static_cast<std::size_t>(n));
  for (long i = 0; i < n; ++i) out.push_back(start_deg + static_cast<double>(i) * step_deg);
  return out;
}

}  // namespace polrig
