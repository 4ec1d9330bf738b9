#pragma once
// The sky as a Source (source.model: sky): the six-photodiode sensor on its turntable under a
// single-scattering Rayleigh sky (sky/sensor_view.h). Time-dependent: the stop's time is
// sky.first_stop_utc + the schedule's stop time. All six channels see the same light (the sky is
// at infinity: no parallax, no eccentricity bias), E_m = E_0·radiance. The polarization is the
// sky's: θ in the sensor frame, d = the sky's DoP along the sensor's axis. The rig's device.d is
// the sky's d at the first stop (rig_degree_of_polarization: io/rig_yaml sets it, or refuses a
// file's other value), the d_a that calibrate decouples with.
#include "polrig/source/source.h"

namespace polrig {

class SkySource final : public Source {
 public:
  std::string_view kind() const override { return "sky"; }
  unsigned flags() const override { return kTimeDependent | kUniformReference | kStokesAlongViews; }
  // The sky along each view (ENU) at the stop's time (the sun computed once): S0 = E0·radiance,
  // e = s × v/|s × v|, d = P(γ) (sky/rayleigh.h); the axes the mount's (sky/sensor_view.h).
  std::unique_ptr<const LightAlongViews> light_along_views(const SourceView& rig,
                                                           const SourcePose& pose) const override;
  Polarization polarization(const SourceView& rig, const SourcePose& pose) const override;
  void irradiance(const SourceView& rig, const SourcePose& pose, std::span<double> E) const override;
  std::array<double, 6> ideal_irradiance(const SourceView& rig, const SourcePose& pose) const override;
  // The sky's d along the sensor's axis at the first stop (the table turns about that axis, so
  // θ_R does not change it).
  std::optional<double> rig_degree_of_polarization(const SourceView& rig) const override;
};

}  // namespace polrig
