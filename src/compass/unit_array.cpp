#include "polrig/compass/unit_array.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>

#include "polrig/compass/heading.h"

namespace polrig {

Vec3 unit_e_vector(double aop_rad) { return {std::cos(aop_rad), -std::sin(aop_rad), 0.0}; }

double unit_aop_rad(const Vec3& e_m) {
  double phi = std::atan2(-e_m[1], e_m[0]);
  if (phi < 0) phi += std::numbers::pi;
  if (phi >= std::numbers::pi) phi -= std::numbers::pi;
  return phi;
}

std::string_view unit_sun_status_name(UnitSunStatus s) {
  switch (s) {
    case UnitSunStatus::Ok: return "ok";
    case UnitSunStatus::Degenerate: return "degenerate";
    case UnitSunStatus::TooFewUnits: return "too-few-units";
  }
  return "?";
}

UnitSun sun_from_units(std::span<const UnitReading> readings, std::span<const UnitMount> mounts,
                       const UnitSunSettings& settings) {
  if (readings.size() != mounts.size())
    throw std::invalid_argument(fmt::format("sun_from_units: {} readings for {} units", readings.size(),
                                            mounts.size()));
  UnitSun out;
  // Eq. 4: the two highest DoPs (ties: the lower index first).
  for (std::size_t k = 0; k < readings.size(); ++k) {
    const UnitReading& r = readings[k];
    if (!std::isfinite(r.aop_rad) || !std::isfinite(r.dop) || !(r.dop > 0)) continue;
    const int ki = static_cast<int>(k);
    if (out.i < 0 || r.dop > readings[static_cast<std::size_t>(out.i)].dop) {
      out.j = out.i;
      out.i = ki;
    } else if (out.j < 0 || r.dop > readings[static_cast<std::size_t>(out.j)].dop) {
      out.j = ki;
    }
  }
  if (out.j < 0) return out;  // TooFewUnits
  const auto e_b = [&](int k) {
    const auto u = static_cast<std::size_t>(k);
    return vec3::apply(mounts[u].C_mb, unit_e_vector(readings[u].aop_rad));  // Eqs. 3, 5
  };
  out.E_i = e_b(out.i);
  out.E_j = e_b(out.j);
  const Vec3 c = vec3::cross(out.E_i, out.E_j);
  const double n = vec3::norm(c);
  // |E_i|, |E_j| are 1 to rounding: the sine of the angle between them is |E_i × E_j|.
  out.angle_rad = std::asin(std::min(1.0, n));
  if (!(out.angle_rad >= settings.min_angle_deg * (std::numbers::pi / 180.0))) {
    out.status = UnitSunStatus::Degenerate;
    return out;
  }
  out.s_b = vec3::mul(c, (c[2] < 0 ? -1.0 : 1.0) / n);  // Eq. 6, Ω: s_z > 0
  out.azimuth_rad = std::atan2(out.s_b[1], out.s_b[0]);  // Eq. 7
  out.elevation_rad = std::asin(std::clamp(out.s_b[2], -1.0, 1.0));  // Eq. 8
  out.status = UnitSunStatus::Ok;
  return out;
}

UnitSunNav sun_in_nav(const Vec3& s_b, const Axes3& C_bn) {
  UnitSunNav out;
  out.s_n = vec3::apply(C_bn, s_b);
  out.elevation_rad = std::asin(std::clamp(out.s_n[2], -1.0, 1.0));
  return out;
}

Axes3 body_axes_enu(double heading_deg, double roll_deg, double pitch_deg) {
  const Tilt t{roll_deg, pitch_deg};
  return {body_to_enu({1, 0, 0}, heading_deg, t), body_to_enu({0, 1, 0}, heading_deg, t),
          body_to_enu({0, 0, 1}, heading_deg, t)};
}

double body_azimuth_clockwise_rad(const Vec3& s_b) {
  double a = std::atan2(s_b[0], s_b[1]);
  if (a < 0) a += 2.0 * std::numbers::pi;
  return a;
}

}  // namespace polrig
