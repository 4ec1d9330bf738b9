// Berry's sky (include/polrig/sky/berry.h).
#include "polrig/sky/berry.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "polrig/units.h"

namespace polrig {

namespace {

using Complex = std::complex<double>;

// The view v as ζ = p/q, p = v_x + i·v_y, q = 1 + v_z (finite at the nadir, where q = 0).
struct Homogeneous {
  Complex p;
  double q;
};
Homogeneous stereographic(const Vec3& v) { return {{v[0], v[1]}, 1 + v[2]}; }

Vec3 direction(double zenith_angle, double cos_phi, double sin_phi) {
  const double st = std::sin(zenith_angle);
  return {st * cos_phi, st * sin_phi, std::cos(zenith_angle)};
}

}  // namespace

BerryField::BerryField(const Vec3& s, const BerryDistances& d) {
  for (const auto& [name, value] : {std::pair{"Babinet", d.babinet_deg}, {"Brewster", d.brewster_deg}})
    if (!(value >= 0 && value < 90))
      throw std::invalid_argument(fmt::format("Berry's sky: the {} distance {}° is outside [0°, 90°)", name, value));
  const double theta_s = std::acos(std::clamp(s[2], -1.0, 1.0));
  if (theta_s / kDeg + d.brewster_deg >= 179)
    throw std::invalid_argument(fmt::format(
        "Berry's sky: Brewster's point ({}° below a sun {}° below the zenith) reaches the nadir", d.brewster_deg,
        theta_s / kDeg));
  const double rho = std::sqrt(s[0] * s[0] + s[1] * s[1]);
  const double cos_phi = rho > 0 ? s[0] / rho : 1, sin_phi = rho > 0 ? s[1] / rho : 0;  // φ_s = 0 at the zenith
  const Complex meridian{cos_phi, sin_phi};
  const double theta_Ba = theta_s - d.babinet_deg * kDeg, theta_Br = theta_s + d.brewster_deg * kDeg;
  // ζ_p = tan(θ_p/2)·e^{iφ_s}: a negative tangent puts Babinet over the zenith, on the antisun's side.
  zeta_Ba_ = std::tan(theta_Ba / 2) * meridian;
  zeta_Br_ = std::tan(theta_Br / 2) * meridian;
  norm_ = 1 / ((1 + std::norm(zeta_Ba_)) * (1 + std::norm(zeta_Br_)));
  const Vec3 Ba = direction(theta_Ba, cos_phi, sin_phi), Br = direction(theta_Br, cos_phi, sin_phi);
  points_ = {Ba, Br, vec3::mul(Br, -1), vec3::mul(Ba, -1)};
}

Complex BerryField::w(const Vec3& v) const {
  // With ζ = p/q: (1 + |ζ|²)² = 4/q², so
  //   w·e^{−2iφ_s} = −(p − ζ_Ba q)(p − ζ_Br q)(q + ζ_Ba* p)(q + ζ_Br* p) / (q² (1 + |ζ_Ba|²)(1 + |ζ_Br|²)).
  const auto [p, q] = stereographic(v);
  const Complex n = (p - zeta_Ba_ * q) * (p - zeta_Br_ * q) * (q + std::conj(zeta_Ba_) * p) * (q + std::conj(zeta_Br_) * p);
  return -n * (norm_ / (q * q));
}

BerryField::Polarization BerryField::at(const Vec3& v) const {
  Polarization out;
  // sin α·sin β from the points' directions: exact at the nadir too, where ζ is infinite.
  out.w_abs = std::min(1.0, vec3::norm(vec3::cross(points_[0], v)) * vec3::norm(vec3::cross(points_[1], v)));
  const auto [p, q] = stereographic(v);
  if (q < 1e-9) return out;  // the nadir: the plane's direction is undefined there
  const Complex wv = w(v);
  const double a = std::abs(wv);
  if (!(a > 0)) return out;
  // e^{iψ}, ψ = ½ arg w̃ (either root: an E-vector is an axis).
  const Complex c = std::sqrt(wv / a);
  // The plane's unit directions x̂, ŷ at ζ = X + iY carried onto the sphere (the inverse
  // projection's columns, (1 − X² + Y², −2XY, −2X) and (−2XY, 1 + X² − Y², −2Y)), times q².
  const double px = p.real(), py = p.imag();
  const Vec3 dX{q * q - px * px + py * py, -2 * px * py, -2 * px * q};
  const Vec3 dY{-2 * px * py, q * q + px * px - py * py, -2 * py * q};
  const Vec3 e = vec3::add(vec3::mul(dX, c.real()), vec3::mul(dY, c.imag()));
  out.e_vector = vec3::mul(e, 1 / vec3::norm(e));
  return out;
}

double berry_dop(double w_abs, double P_max) { return P_max * w_abs / (2 - w_abs); }

}  // namespace polrig
