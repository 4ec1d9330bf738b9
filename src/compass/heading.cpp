#include "polrig/compass/heading.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "polrig/units.h"

namespace polrig {

namespace {

// Active right-hand rotations about x, y, z by an angle with cosine c and sine s.
Vec3 rot_x(const Vec3& w, double c, double s) { return {w[0], c * w[1] - s * w[2], s * w[1] + c * w[2]}; }
Vec3 rot_y(const Vec3& w, double c, double s) { return {c * w[0] + s * w[2], w[1], -s * w[0] + c * w[2]}; }
Vec3 rot_z(const Vec3& w, double c, double s) { return {c * w[0] - s * w[1], s * w[0] + c * w[1], w[2]}; }

}  // namespace

std::string_view heading_status_name(HeadingStatus s) {
  switch (s) {
    case HeadingStatus::Ok: return "ok";
    case HeadingStatus::Clamped: return "clamped";
    case HeadingStatus::SunNearZenithOrVerticalE: return "sun-near-zenith-or-vertical-e";
    case HeadingStatus::Inconsistent: return "inconsistent";
  }
  return "?";
}

double wrap_heading_deg(double deg) {
  double w = std::fmod(deg, 360.0);
  if (w < 0.0) w += 360.0;
  if (w >= 360.0) w -= 360.0;
  return w;
}

double heading_difference_deg(double a, double b) {
  double d = std::fmod(a - b, 360.0);
  if (d < -180.0) d += 360.0;
  if (d >= 180.0) d -= 360.0;
  return d;
}

Vec3 body_to_enu(const Vec3& v_b, double heading_deg, const Tilt& tilt) {
  const double g = deg2rad(tilt.roll_deg), l = deg2rad(tilt.pitch_deg), h = deg2rad(heading_deg);
  // C_b^n = Rz(−H)·Rx(λ)·Ry(γ)
  return rot_z(rot_x(rot_y(v_b, std::cos(g), std::sin(g)), std::cos(l), std::sin(l)), std::cos(h),
               -std::sin(h));
}

Vec3 enu_to_body(const Vec3& v_n, double heading_deg, const Tilt& tilt) {
  const double g = deg2rad(tilt.roll_deg), l = deg2rad(tilt.pitch_deg), h = deg2rad(heading_deg);
  // C_n^b = Ry(−γ)·Rx(−λ)·Rz(H)
  return rot_y(rot_x(rot_z(v_n, std::cos(h), std::sin(h)), std::cos(l), -std::sin(l)), std::cos(g),
               -std::sin(g));
}

void check_sun_enu(const Vec3& s) {
  const double n = vec3::norm(s);
  if (!(std::abs(n - 1.0) <= 1e-9))
    throw std::invalid_argument(fmt::format(
        "sun_enu ({}, {}, {}) has length {}: expected the unit vector to the sun (|‖s‖ − 1| ≤ 1e-9)",
        s[0], s[1], s[2], n));
}

HeadingSolution solve_heading(const Vec3& s, double aop_body_deg, const Tilt& tilt,
                              std::optional<double> prior_deg, const HeadingSettings& settings) {
  check_sun_enu(s);
  HeadingSolution r;
  const double th = deg2rad(aop_body_deg);
  const double g = deg2rad(tilt.roll_deg), l = deg2rad(tilt.pitch_deg);
  // u = Rx(λ)·Ry(γ)·e_b, e_b = (cos θ_b, sin θ_b, 0)
  const Vec3 u = rot_x(rot_y({std::cos(th), std::sin(th), 0.0}, std::cos(g), std::sin(g)),
                       std::cos(l), std::sin(l));
  r.a = u[0] * s[0] + u[1] * s[1];
  r.b = u[1] * s[0] - u[0] * s[1];
  r.c = -u[2] * s[2];
  const double R = std::hypot(r.a, r.b);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  if (!(R >= settings.min_horizontal)) {
    r.status = HeadingStatus::SunNearZenithOrVerticalE;
    r.heading_deg = r.heading_alt_deg = r.sun_forward = nan;
    return r;
  }
  double q = r.c / R;
  if (std::abs(q) > 1.0) {
    if (std::abs(q) - 1.0 > settings.tangent_tolerance) {
      r.status = HeadingStatus::Inconsistent;
      r.heading_deg = r.heading_alt_deg = r.sun_forward = nan;
      return r;
    }
    r.status = HeadingStatus::Clamped;
    q = std::copysign(1.0, q);
  }
  const double phi = rad2deg(std::atan2(r.b, r.a)), delta = rad2deg(std::acos(q));
  const double roots[2] = {wrap_heading_deg(phi + delta), wrap_heading_deg(phi - delta)};
  const double forward[2] = {enu_to_body(s, roots[0], tilt)[1], enu_to_body(s, roots[1], tilt)[1]};
  int pick = 0;
  if (prior_deg) {
    r.from_prior = true;
    pick = std::abs(heading_difference_deg(roots[1], *prior_deg)) <
                   std::abs(heading_difference_deg(roots[0], *prior_deg))
               ? 1 : 0;
  } else {
    pick = forward[1] > forward[0] ? 1 : 0;
  }
  r.heading_deg = roots[pick];
  r.heading_alt_deg = roots[1 - pick];
  r.sun_forward = forward[pick];
  return r;
}

double aop_body_deg(const Vec3& e_enu, double heading_deg, const Tilt& tilt) {
  const Vec3 e_b = enu_to_body(e_enu, heading_deg, tilt);
  return wrap_axis_deg(rad2deg(std::atan2(e_b[1], e_b[0])));
}

}  // namespace polrig
