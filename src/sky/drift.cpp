#include "polrig/sky/drift.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "polrig/units.h"

namespace polrig {

std::string_view drift_mode_name(DriftMode m) {
  switch (m) {
    case DriftMode::None: return "none";
    case DriftMode::Angle: return "angle";
    case DriftMode::PerStop: return "per-stop";
    case DriftMode::Linear: return "linear";
  }
  return "?";
}

std::optional<DriftMode> parse_drift_mode(std::string_view name) {
  for (DriftMode m : {DriftMode::None, DriftMode::Angle, DriftMode::PerStop, DriftMode::Linear})
    if (drift_mode_name(m) == name) return m;
  return std::nullopt;
}

double zenith_dop(const SunPosition& sun, const MaxDegree& P_max) {
  const double c = std::cos(deg2rad(sun.zenith_deg));
  return P_max.at(sun.elevation_deg) * (1.0 - c * c) / (1.0 + c * c);
}

namespace {
// A_s(t) − A_s(t_0) in (−180°, 180°]: the azimuth wraps at north.
double azimuth_change_deg(double a, double a0) {
  double d = std::fmod(a - a0, 360.0);
  if (d > 180.0) d -= 360.0;
  if (d <= -180.0) d += 360.0;
  return d;
}
}  // namespace

SkyDrift drift_from_sun(const std::vector<double>& t_s, const std::vector<double>& A,
                        const std::vector<double>& dop, DriftMode mode) {
  if (t_s.size() != A.size() || t_s.size() != dop.size())
    throw std::invalid_argument("drift_from_sun: one azimuth and one DoP per stop time");
  SkyDrift out;
  if (mode == DriftMode::None || t_s.empty()) return out;
  for (std::size_t k = 0; k < t_s.size(); ++k)
    if (!(std::isfinite(t_s[k]) && std::isfinite(A[k]) && std::isfinite(dop[k])))
      throw std::invalid_argument("drift_from_sun: a stop time, azimuth or DoP is not finite");
  const auto [lo, hi] = std::minmax_element(t_s.begin(), t_s.end());
  const std::size_t first = static_cast<std::size_t>(lo - t_s.begin());
  const std::size_t last = static_cast<std::size_t>(hi - t_s.begin());
  const double total = azimuth_change_deg(A[last], A[first]);
  const double span = t_s[last] - t_s[first];
  const bool with_d = mode == DriftMode::PerStop || mode == DriftMode::Linear;
  if (with_d && !(dop[first] > 0.0))
    throw std::invalid_argument("drift_from_sun: the zenith is unpolarized at the first stop");
  const double total_ratio = dop[last] / dop[first] - 1.0;
  for (std::size_t k = 0; k < t_s.size(); ++k) {
    const double f = span > 0.0 ? (t_s[k] - t_s[first]) / span : 0.0;
    const double drift = mode == DriftMode::Linear ? total * f : azimuth_change_deg(A[k], A[first]);
    out.dtheta_deg.push_back(-drift);  // sensor frame: the E-vector turns against θ (header)
    if (mode == DriftMode::PerStop) out.d_ratio.push_back(dop[k] / dop[first]);
    if (mode == DriftMode::Linear) out.d_ratio.push_back(1.0 + total_ratio * f);
  }
  return out;
}

SkyDrift drift_corrections(const std::vector<UtcTime>& times, const Site& site,
                           const SunSettings& settings, const MaxDegree& P_max, DriftMode mode) {
  std::vector<double> t, A, dop;
  if (mode != DriftMode::None)
    for (const UtcTime& u : times) {
      const SunPosition sun = sun_position(u, site, settings);
      t.push_back(u.unix_s - times.front().unix_s);
      A.push_back(sun.azimuth_deg);
      dop.push_back(zenith_dop(sun, P_max));
    }
  return drift_from_sun(t, A, dop, mode);
}

}  // namespace polrig
