#include "polrig/calib/stop_corrections.h"

#include <stdexcept>

#include <fmt/format.h>

#include "polrig/sky/sky.h"

namespace polrig {

StopTimes drift_stop_times(const DriftRequest& request, const Rig& rig) {
  StopTimes times{request.utc, "the utc column"};
  // A time-dependent source's rig (the sky) carries the first stop's time.
  if (times.utc.empty() && rig.light->has(Source::kTimeDependent) && !request.t_s.empty()) {
    const UtcTime t0 = parse_utc(rig.source.sky.first_stop_utc);
    for (double t : request.t_s) times.utc.push_back(t0.plus_seconds(t));
    times.from = "the rig's sky.first_stop_utc + t_s";
  }
  if (times.utc.empty())
    throw std::invalid_argument(fmt::format("{}: {}", request.drift_option, request.times_missing));
  return times;
}

StopCorrections sun_drift_corrections(const DriftRequest& request, const StopTimes& times,
                                      const std::optional<Site>& site_given,
                                      const std::string& site_given_from, const Rig& rig) {
  if (request.mode == DriftMode::None) return {};
  const bool sky_rig = rig.light->has(Source::kTimeDependent);
  Site site;
  std::string site_from;
  if (site_given) {
    site = *site_given;
    site_from = site_given_from;
  } else if (sky_rig) {
    site = rig.source.sky.sky.site;
    site_from = fmt::format("the rig's site {},{}", site.lat_deg, site.lon_deg);
  } else {
    throw std::invalid_argument(fmt::format("{} needs {} (the sun's position)", request.drift_option,
                                            request.site_option));
  }
  // The d ratio does not depend on a constant P_max; a sky rig's P_max(h_s) table enters it. A
  // sky rig's sun (refraction, UT1 − UTC) is the one its simulation saw; otherwise geometric.
  const Sky sky = sky_rig ? rig.source.sky.resolved_sky() : Sky{};
  const MaxDegree P_max = sky_rig ? sky.model.P_max : MaxDegree{};
  const SunSettings sun = sky_rig ? sky.sun : SunSettings{};
  SkyDrift d;
  try {
    d = drift_corrections(times.utc, site, sun, P_max, request.mode);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(
        fmt::format("{} on {}: {}", request.drift_option, request.origin, e.what()));
  }
  return {d.dtheta_deg, d.d_ratio,
          fmt::format("{} (stop times from {}, the sun from ERFA at {}{})",
                      drift_mode_name(request.mode), times.from, site_from,
                      request.mode == DriftMode::Linear
                          ? ", interpolated between the first and last stop" : "")};
}

StopCorrections sun_drift_corrections(const DriftRequest& request, const std::optional<Site>& site,
                                      const std::string& site_from, const Rig& rig) {
  if (request.mode == DriftMode::None) return {};
  return sun_drift_corrections(request, drift_stop_times(request, rig), site, site_from, rig);
}

}  // namespace polrig
