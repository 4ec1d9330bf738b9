#pragma once
// Vector arithmetic, Snell's law and the Fresnel amplitudes shared by the lens tracer and the
// polarization ray tracer, so that both follow one path bit for bit. Internal to src/optics.
#include <array>
#include <cmath>
#include <optional>

#include "polrig/vec3.h"

namespace polrig {

namespace optics_detail {

using vec3::add;
using vec3::cross;
using vec3::dot;
using vec3::mul;
using vec3::norm;
using vec3::sub;
using vec3::unit;
// The part of v perpendicular to the unit vector k.
inline Vec3 reject(const Vec3& v, const Vec3& k) { return sub(v, mul(k, dot(v, k))); }

// Snell's law in vector form; n is the unit normal on the side the ray comes from. Nothing on
// total internal reflection.
inline std::optional<Vec3> snell(const Vec3& i, const Vec3& n, double n1, double n2) {
  const double eta = n1 / n2, cos_i = -dot(n, i);
  const double k = 1 - eta * eta * (1 - cos_i * cos_i);
  if (k < 0) return std::nullopt;
  return unit(add(mul(i, eta), mul(n, eta * cos_i - std::sqrt(k))));
}

// Fresnel amplitude reflection coefficients from n1 into n2 at incidence cos θ_i; r_s = r_p = 1
// (nothing transmitted) at and beyond the critical angle.
struct FresnelR {
  double s = 1, p = 1;
};
inline FresnelR fresnel_r(double n1, double n2, double cos_i) {
  const double sin_t2 = (n1 / n2) * (n1 / n2) * (1 - cos_i * cos_i);
  if (sin_t2 >= 1) return {};
  const double cos_t = std::sqrt(1 - sin_t2);
  return {(n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t),
          (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t)};
}

}  // namespace optics_detail
}  // namespace polrig
