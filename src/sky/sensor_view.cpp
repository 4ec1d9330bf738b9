#include "polrig/sky/sensor_view.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "polrig/quadrature.h"
#include "polrig/units.h"

namespace polrig {

namespace {

struct Frame {
  Vec3 x, y, z;
};

// [X_s Y_s Z_s] in ENU (header): the level frame at azimuth mount_deg, tilted by pitch about its
// x and roll about its y, then turned by the table about the tilted z (clockwise from above).
Frame sensor_frame(const SkyMount& m, double theta_R_deg) {
  const double a = deg2rad(m.mount_deg);
  const Vec3 x0{std::sin(a), std::cos(a), 0}, y0{-std::cos(a), std::sin(a), 0}, z0{0, 0, 1};
  // Rx(pitch): y → y·cos p + z·sin p, z → −y·sin p + z·cos p.
  const double p = deg2rad(m.pitch_deg), r = deg2rad(m.roll_deg), t = deg2rad(-theta_R_deg);
  const Vec3 y1 = vec3::add(vec3::mul(y0, std::cos(p)), vec3::mul(z0, std::sin(p)));
  const Vec3 z1 = vec3::add(vec3::mul(y0, -std::sin(p)), vec3::mul(z0, std::cos(p)));
  // Ry(roll): x → x·cos r − z·sin r, z → x·sin r + z·cos r.
  const Vec3 x2 = vec3::sub(vec3::mul(x0, std::cos(r)), vec3::mul(z1, std::sin(r)));
  const Vec3 z2 = vec3::add(vec3::mul(x0, std::sin(r)), vec3::mul(z1, std::cos(r)));
  // Rz(t): x → x·cos t + y·sin t, y → −x·sin t + y·cos t.
  return {vec3::add(vec3::mul(x2, std::cos(t)), vec3::mul(y1, std::sin(t))),
          vec3::add(vec3::mul(x2, -std::sin(t)), vec3::mul(y1, std::cos(t))), z2};
}

// The E-vector's doubled angle in the sensor frame, weighted: (L·P·cos 2ψ, L·P·sin 2ψ, L).
struct Stokes3 {
  double Q = 0, U = 0, I = 0;
};
Stokes3 seen_along(const Vec3& s, const Vec3& v, const Frame& f, const SkyModel& model) {
  const SkyLight light = sky_light(s, v, model);  // along the sun's line P = 0 and e = 0
  const double psi = sensor_frame_angle_rad(light.e_vector, f.x, f.y);
  const double lp = light.radiance * light.dop;
  return {lp * std::cos(2 * psi), lp * std::sin(2 * psi), light.radiance};
}

}  // namespace

SensorAxesEnu sensor_axes_enu(const SkyMount& mount, double theta_R_deg) {
  const Frame f = sensor_frame(mount, theta_R_deg);
  return {f.x, f.y, f.z};
}

double sensor_frame_angle_rad(const Vec3& e, const Vec3& X_s, const Vec3& Y_s) {
  return std::atan2(vec3::dot(e, Y_s), vec3::dot(e, X_s));
}

SkyView sky_seen(const SunPosition& sun, const SkyModel& model, const SkyMount& mount,
                 double theta_R_deg) {
  const Frame f = sensor_frame(mount, theta_R_deg);
  const Vec3 s = sun_direction_enu(sun);
  Stokes3 sum;
  if (!mount.cone) {
    sum = seen_along(s, f.z, f, model);
  } else {
    // The cone ρ ≤ ρ_max around Z_s, uniform in solid angle: u = (1 − cos ρ)/(1 − cos ρ_max) by
    // 4-point Gauss–Legendre, 8 azimuths (exact for the sky's quadratic variation across 0.74°).
    // Each ray's E-vector is projected onto the sensor plane: the films are perpendicular to
    // Z_s, and at ρ ≤ 0.74° the projection changes ψ by O(ρ²) ≈ 1.7e-4 rad at most.
    const QuadratureRule q = gauss_legendre_01(4);
    const double c_max = std::cos(deg2rad(mount.field_half_angle_deg));
    constexpr int kAzimuths = 8;
    for (std::size_t i = 0; i < q.x.size(); ++i) {
      const double c = 1.0 - q.x[i] * (1.0 - c_max), sn = std::sqrt(std::max(0.0, 1.0 - c * c));
      for (int k = 0; k < kAzimuths; ++k) {
        const double phi = 2.0 * std::numbers::pi * (k + 0.5) / kAzimuths;
        const Vec3 v = vec3::unit(vec3::add(
            vec3::mul(f.z, c),
            vec3::add(vec3::mul(f.x, sn * std::cos(phi)), vec3::mul(f.y, sn * std::sin(phi)))));
        const Stokes3 one = seen_along(s, v, f, model);
        const double w = q.w[i] / kAzimuths;
        sum.Q += w * one.Q, sum.U += w * one.U, sum.I += w * one.I;
      }
    }
  }
  SkyView out;
  double theta = rad2deg(0.5 * std::atan2(sum.U, sum.Q));
  if (theta < 0) theta += 180.0;
  if (theta >= 180.0) theta -= 180.0;
  out.theta_deg = theta;
  out.d = sum.I > 0 ? std::hypot(sum.Q, sum.U) / sum.I : 0.0;
  out.E_Wm2 = mount.E0_Wm2 * sum.I;
  return out;
}

SkyView sky_seen(const Sky& sky, const SkyMount& mount, double theta_R_deg, double t_s) {
  const SunPosition sun =
      sun_position(sky.first_stop.plus_seconds(t_s + mount.time_offset_s), sky.site, sky.sun);
  return sky_seen(sun, sky.model, mount, theta_R_deg);
}

}  // namespace polrig
