#include "polrig/source/sky_source.h"

namespace polrig {

namespace {
SkyView seen(const SourceView& rig, const SourcePose& pose) {
  const SkySettings& s = rig.settings.sky;
  return sky_seen(s.resolved_sky(), s.resolved_mount(), pose.theta_R_deg, pose.t_s);
}
}  // namespace

Polarization SkySource::polarization(const SourceView& rig, const SourcePose& pose) const {
  const SkyView v = seen(rig, pose);
  return {v.theta_deg, v.d};
}

void SkySource::irradiance(const SourceView& rig, const SourcePose& pose, std::span<double> E) const {
  const double e = seen(rig, pose).E_Wm2;
  for (std::size_t m = 0; m < 6; ++m) E[m] = e;
}

std::array<double, 6> SkySource::ideal_irradiance(const SourceView& rig, const SourcePose& pose) const {
  const double e = seen(rig, pose).E_Wm2;
  return {e, e, e, e, e, e};
}

std::optional<double> SkySource::rig_degree_of_polarization(const SourceView& rig) const {
  return seen(rig, {0.0, 0.0}).d;
}

}  // namespace polrig
