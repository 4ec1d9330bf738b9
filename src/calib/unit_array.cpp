#include "polrig/calib/unit_array.h"

#include <cmath>
#include <limits>
#include <numbers>

#include "polrig/calib/angles.h"
#include "polrig/device/sensor.h"
#include "polrig/sky/sensor_view.h"
#include "polrig/units.h"

namespace polrig {

namespace {

double axial_rad(double a) {
  a = std::fmod(a, std::numbers::pi);
  if (a < 0) a += std::numbers::pi;
  if (a >= std::numbers::pi) a -= std::numbers::pi;
  return a;
}

struct UnitView {
  Vec3 X, Y, Z;  // the unit's true axes in n
  SkyLight light;
};

std::vector<UnitView> views(const UnitArrayTruth& truth, const Vec3& s, const SkyModel& model, const Axes3& C_bn) {
  std::vector<UnitView> out;
  for (const Axes3& C_mb : truth.actual) {
    const Axes3 C_mn = vec3::compose(C_bn, C_mb);
    UnitView v{C_mn[0], C_mn[1], C_mn[2], sky_light(s, C_mn[2], model)};
    out.push_back(v);
  }
  return out;
}

// Spec §1.3: θ_meas = atan2(e·(k × X), e·X), k = −Z.
double spec_angle_rad(const UnitView& v) {
  const Vec3 k = vec3::mul(v.Z, -1.0);
  return axial_rad(std::atan2(vec3::dot(v.light.e_vector, vec3::cross(k, v.X)), vec3::dot(v.light.e_vector, v.X)));
}

}  // namespace

std::vector<UnitSample> read_units_truth(const UnitArrayTruth& truth, const Sky& sky, UtcTime t,
                                         const Axes3& C_bn) {
  std::vector<UnitSample> out;
  for (const UnitView& v : views(truth, sun_direction_enu(sun_position(t, sky.site, sky.sun)), sky.model, C_bn)) {
    UnitSample u;
    u.true_aop_rad = u.aop_rad = spec_angle_rad(v);
    u.true_dop = u.dop = v.light.dop;
    u.view_enu = v.Z;
    out.push_back(u);
  }
  return out;
}

std::vector<UnitSample> read_units(const Rig& rig, const UnitArrayTruth& truth, const Sky& sky, UtcTime t,
                                   const Axes3& C_bn, std::uint64_t seed, std::uint64_t sample_index) {
  return read_units(rig, truth, sun_direction_enu(sun_position(t, sky.site, sky.sun)), sky.model, C_bn, seed,
                    sample_index);
}

std::vector<UnitSample> read_units(const Rig& rig, const UnitArrayTruth& truth, const Vec3& sun_enu,
                                   const SkyModel& sky_model, const Axes3& C_bn, std::uint64_t seed,
                                   std::uint64_t sample_index) {
  const CalibrationParams& device = rig.device.truth;
  const CalibrationParams model = rig.units.apply == "theory" ? rig.device.theory() : device;
  const Electronics& el = rig.electronics;
  const int samples = rig.schedule.samples_per_stop;
  const std::array<double, 6> E{1, 1, 1, 1, 1, 1};  // the sky at infinity: equal irradiance
  std::vector<UnitSample> out;
  std::uint64_t unit = 0;
  for (const UnitView& v : views(truth, sun_enu, sky_model, C_bn)) {
    UnitSample u;
    u.true_aop_rad = spec_angle_rad(v);
    u.true_dop = v.light.dop;
    u.view_enu = v.Z;
    // The chain's angle: polrig's sensor frame (X towards Y), as the sky source gives it.
    const double theta_deg = wrap_axis_deg(rad2deg(sensor_frame_angle_rad(v.light.e_vector, v.X, v.Y)));
    const std::array<double, 3> V0 = pair_voltages(device, el, E, theta_deg, v.light.dop);
    for (std::size_t i = 0; i < 3; ++i) {
      double sum = 0;
      const NormalStream noise(seed, sample_index, 3 * unit + i);
      for (int k = 0; k < samples; ++k)
        sum += adc_quantize(V0[i] + el.noise_sigma_V * noise(static_cast<std::uint64_t>(k)), el);
      u.V[i] = sum / samples;
    }
    const MeasuredAngles m = measured_angles(model, el, u.V);
    u.problem = m.problem;
    if (m.problem.empty()) {
      u.aop_rad = axial_rad(-deg2rad(m.angles.theta_sec_deg));
      u.dop = m.d;
    } else {
      u.aop_rad = u.dop = std::numeric_limits<double>::quiet_NaN();
    }
    out.push_back(u);
    ++unit;
  }
  return out;
}

std::vector<UnitSample> read_units(const Rig& rig, const Sky& sky, UtcTime t, const Axes3& C_bn,
                                   std::uint64_t seed, std::uint64_t sample_index) {
  return read_units(rig, unit_array_truth(rig.units, rig.seed), sky, t, C_bn, seed, sample_index);
}

}  // namespace polrig
