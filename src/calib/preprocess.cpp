#include "polrig/calib/preprocess.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <tuple>
#include <numbers>

#include <fmt/format.h>

#include "polrig/device/sensor.h"
#include "polrig/units.h"

namespace polrig {

namespace {
// One table angle: the rows measured there (several when a stop was repeated), averaged.
struct TableStop {
  double theta_R_deg;
  std::array<double, 3> V;
  std::size_t first;  // the stop's first row
};

// Rows with the same θ_R become one stop whose V is their mean (summed in file order).
std::vector<TableStop> merge_repeated_stops(const std::vector<StopVoltages>& stops,
                                            std::vector<std::size_t>& stop_of_row) {
  std::vector<std::size_t> order(stops.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return stops[a].theta_R_deg < stops[b].theta_R_deg;
  });
  std::vector<TableStop> merged;
  stop_of_row.assign(stops.size(), 0);
  for (std::size_t begin = 0; begin < order.size();) {
    std::size_t end = begin + 1;
    while (end < order.size() && stops[order[end]].theta_R_deg == stops[order[begin]].theta_R_deg) ++end;
    TableStop t{stops[order[begin]].theta_R_deg, stops[order[begin]].V, order[begin]};
    if (end - begin > 1) {
      t.V = {0, 0, 0};
      for (std::size_t k = begin; k < end; ++k)
        for (int i = 0; i < 3; ++i) t.V[i] += stops[order[k]].V[i];
      for (int i = 0; i < 3; ++i) t.V[i] /= static_cast<double>(end - begin);
    }
    for (std::size_t k = begin; k < end; ++k) stop_of_row[order[k]] = merged.size();
    merged.push_back(t);
    begin = end;
  }
  return merged;
}

// θ_R,b − θ_R,a − 180° wrapped to [−180°, 180°]: zero for stops 180° apart.
double cs_gap_deg(double theta_a, double theta_b) {
  double gap = std::fmod(theta_b - theta_a - 180.0, 360.0);
  if (gap > 180.0) gap -= 360.0;
  if (gap < -180.0) gap += 360.0;
  return gap;
}
}  // namespace

std::vector<CsPoint> central_symmetry_points(const std::vector<StopVoltages>& stops,
                                             double tol_deg) {
  std::vector<std::size_t> stop_of_row;
  const std::vector<TableStop> table = merge_repeated_stops(stops, stop_of_row);

  // The stops sorted by their angle in [0°, 360°): the partners of a stop at w lie in a window
  // around w + 180°, found by binary search. The window is wider than tol_deg by the rounding
  // of the wrapped angles; each candidate is then judged by the exact rule (cs_gap_deg).
  std::vector<std::pair<double, std::size_t>> wrapped;  // (angle in [0, 360), index in table)
  double largest = 360.0;
  for (std::size_t t = 0; t < table.size(); ++t) {
    double w = std::fmod(table[t].theta_R_deg, 360.0);
    if (w < 0.0) w += 360.0;
    if (w >= 360.0) w -= 360.0;
    wrapped.emplace_back(w, t);
    largest = std::max(largest, std::abs(table[t].theta_R_deg));
  }
  std::sort(wrapped.begin(), wrapped.end());
  const double window = tol_deg + 1e-9 + 16.0 * std::numeric_limits<double>::epsilon() * largest;

  std::vector<std::pair<std::size_t, std::size_t>> pairs;  // (a, b) into table, first row of a < b
  const auto consider = [&](std::size_t a, double lo, double hi) {
    auto it = std::lower_bound(wrapped.begin(), wrapped.end(), std::make_pair(lo, std::size_t{0}));
    for (; it != wrapped.end() && it->first <= hi; ++it) {
      const std::size_t b = it->second;
      if (table[a].first < table[b].first &&
          std::abs(cs_gap_deg(table[a].theta_R_deg, table[b].theta_R_deg)) <= tol_deg)
        pairs.emplace_back(a, b);
    }
  };
  for (const auto& [w, a] : wrapped) {
    if (window >= 90.0) {  // a tolerance this wide: every stop is a candidate
      consider(a, 0.0, 360.0);
      continue;
    }
    const double target = w < 180.0 ? w + 180.0 : w - 180.0;
    consider(a, std::max(0.0, target - window), std::min(360.0, target + window));
    if (target - window < 0.0) consider(a, target - window + 360.0, 360.0);
    if (target + window > 360.0) consider(a, 0.0, target + window - 360.0);
  }
  std::sort(pairs.begin(), pairs.end(), [&](const auto& x, const auto& y) {
    return std::tie(table[x.first].first, table[x.second].first) <
           std::tie(table[y.first].first, table[y.second].first);
  });
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());

  std::vector<CsPoint> points;
  std::vector<bool> paired(table.size(), false);
  for (const auto& [a, b] : pairs) {
    CsPoint p{table[a].theta_R_deg, {}, table[a].first, table[b].first};
    for (int i = 0; i < 3; ++i) p.V[i] = 0.5 * (table[a].V[i] + table[b].V[i]);
    points.push_back(p);
    paired[a] = paired[b] = true;
  }
  for (std::size_t s = 0; s < stops.size(); ++s)
    if (!paired[stop_of_row[s]])
      throw CalibrationError(fmt::format(
          "{} (theta_R = {}°) has no partner 180° away; central symmetry needs every stop "
          "paired (the section method does not)",
          stops[s].label, stops[s].theta_R_deg));
  return points;
}

double eq15_slope(const FitParams& p, double v_dec, int i, double theta_deg, double d_ratio) {
  // θ enters Eq. 15 only as 2θ + α_m, so ∂V/∂θ = 2·(∂V/∂α_j + ∂V/∂α_h); the gradient is per
  // degree of α, the slope per radian of θ.
  const FitParams::Vector g = eq15_gradient(p, v_dec, i, theta_deg, d_ratio);
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
        slope.emplace_back(std::abs(eq15_slope(model, v_dec, i, data[n].theta_deg, data[n].d_ratio)), n);
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
