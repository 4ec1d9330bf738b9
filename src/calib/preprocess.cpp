#include "polrig/calib/preprocess.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "polrig/device/sensor.h"
#include "polrig/units.h"

namespace polrig {

std::vector<CsPoint> central_symmetry_points(const std::vector<StopVoltages>& stops,
                                             double tol_deg) {
  std::vector<CsPoint> points;
  std::vector<bool> paired(stops.size(), false);
  for (std::size_t a = 0; a < stops.size(); ++a)
    for (std::size_t b = a + 1; b < stops.size(); ++b) {
      double gap = std::fmod(stops[b].theta_R_deg - stops[a].theta_R_deg - 180.0, 360.0);
      if (gap > 180.0) gap -= 360.0;
      if (gap < -180.0) gap += 360.0;
      if (std::abs(gap) > tol_deg) continue;
      CsPoint p{stops[a].theta_R_deg, {}, a, b};
      for (int i = 0; i < 3; ++i) p.V[i] = 0.5 * (stops[a].V[i] + stops[b].V[i]);
      points.push_back(p);
      paired[a] = paired[b] = true;
    }
  for (std::size_t s = 0; s < stops.size(); ++s)
    if (!paired[s])
      throw CalibrationError(fmt::format(
          "{} (theta_R = {}°) has no partner 180° away; central symmetry needs every stop "
          "paired (the section method does not)",
          stops[s].label, stops[s].theta_R_deg));
  return points;
}

double eq15_slope(const FitParams& p, double v_dec, int i, double theta_deg) {
  // θ enters Eq. 15 only as 2θ + α_m, so ∂V/∂θ = 2·(∂V/∂α_j + ∂V/∂α_h); the gradient is per
  // degree of α, the slope per radian of θ.
  const FitParams::Vector g = eq15_gradient(p, v_dec, i, theta_deg);
  return 2.0 * (g(FitParams::alpha_index(pair_j(i))) + g(FitParams::alpha_index(pair_h(i)))) / deg2rad(1.0);
}

std::vector<Observation> select_noncontinuous(const std::vector<Observation>& data,
                                              const FitParams& model, double v_dec,
                                              const NoncontinuousRule& rule) {
  std::vector<Observation> kept;
  for (int i = 0; i < 3; ++i) {
    std::vector<std::pair<double, std::size_t>> slope;  // (|dV/dθ|, index)
    for (std::size_t n = 0; n < data.size(); ++n)
      if (data[n].pair == i)
        slope.emplace_back(std::abs(eq15_slope(model, v_dec, i, data[n].theta_deg)), n);
    if (slope.empty()) continue;
    // Steepest first; ties by index, so the choice is deterministic.
    std::stable_sort(slope.begin(), slope.end(),
                     [](const auto& a, const auto& b) { return a.first > b.first; });
    const double threshold = rule.min_relative_slope * slope.front().first;
    std::vector<std::size_t> chosen;
    for (std::size_t r = 0; r < slope.size(); ++r)
      if (slope[r].first >= threshold || static_cast<int>(r) < rule.min_points)
        chosen.push_back(slope[r].second);
    std::sort(chosen.begin(), chosen.end());
    for (std::size_t n : chosen) kept.push_back(data[n]);
  }
  return kept;
}

}  // namespace polrig
