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

namespace {
class SkyViews final : public LightAlongViews {
 public:
  SkyViews(const Vec3& sun, const SkyModel& model, double E0) : sky_(sun, model), E0_(E0) {}
  void along(std::span<const Vec3> views, std::span<ViewLight> out) const override {
    for (std::size_t i = 0; i < views.size(); ++i) {
      const SkyRay l = sky_.along(views[i]);
      out[i] = {E0_ * l.radiance, l.e_vector, l.dop};
    }
  }

 private:
  SunSky sky_;
  double E0_;
};
}  // namespace

std::unique_ptr<const LightAlongViews> SkySource::light_along_views(const SourceView& rig,
                                                                   const SourcePose& pose) const {
  const SkySettings& s = rig.settings.sky;
  const Sky sky = s.resolved_sky();
  const SkyMount mount = s.resolved_mount();
  const SunPosition sun = sun_position(sky.first_stop.plus_seconds(pose.t_s + mount.time_offset_s), sky.site, sky.sun);
  auto light = std::make_unique<SkyViews>(sun_direction_enu(sun), sky.model, mount.E0_Wm2);
  const SensorAxesEnu a = sensor_axes_enu(mount, pose.theta_R_deg);
  light->axes = {a.x, a.y, a.z};
  return light;
}

std::optional<double> SkySource::rig_degree_of_polarization(const SourceView& rig) const {
  return seen(rig, {0.0, 0.0}).d;
}

}  // namespace polrig
