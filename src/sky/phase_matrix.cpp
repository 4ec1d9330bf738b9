// Scattering and meridian-frame phase matrices (spec skies.md §2).
#include "polrig/sky/phase_matrix.h"

#include <cmath>

namespace polrig {

Eigen::Matrix4d ScatteringElements::matrix() const {
  Eigen::Matrix4d P;
  P << a1, b1, 0, 0,  //
      b1, a2, 0, 0,   //
      0, 0, a3, b2,   //
      0, 0, -b2, a4;
  return P;
}

ScatteringElements rayleigh_elements(double c, double rho) {
  const double Delta = (1 - rho) / (1 + rho / 2), Delta_prime = (1 - 2 * rho) / (1 - rho);
  const double a = 0.75 * Delta;
  ScatteringElements e;
  e.a2 = a * (1 + c * c);
  e.a1 = e.a2 + (1 - Delta);
  e.b1 = -a * (1 - c * c);
  e.a3 = a * 2 * c;
  e.a4 = a * 2 * c * Delta_prime;
  return e;
}

Direction direction(double mu, double phi) {
  const double s = std::sqrt(std::max(0.0, 1 - mu * mu)), cp = std::cos(phi), sp = std::sin(phi);
  return {{s * cp, s * sp, mu}, {mu * cp, mu * sp, -s}, {-sp, cp, 0}};
}

Eigen::Matrix4d stokes_rotation(double psi) {
  const double c = std::cos(2 * psi), s = std::sin(2 * psi);
  Eigen::Matrix4d L = Eigen::Matrix4d::Identity();
  L(1, 1) = c, L(1, 2) = s, L(2, 1) = -s, L(2, 2) = c;
  return L;
}

Eigen::Matrix4d phase_matrix(const Direction& in, const Direction& out, const ScatteringElements& P) {
  // r: the normal of the scattering plane; l = r × k lies in it, so (l, r, k) is right-handed.
  Vec3 n = vec3::cross(in.k, out.k);
  const double sin_theta = vec3::norm(n);
  const Vec3 r = sin_theta > 1e-12 ? vec3::mul(n, 1 / sin_theta) : in.e_phi;
  const Vec3 l_in = vec3::cross(r, in.k), l_out = vec3::cross(r, out.k);
  const double psi_in = std::atan2(vec3::dot(l_in, in.e_phi), vec3::dot(l_in, in.e_theta));
  const double psi_out = std::atan2(vec3::dot(out.e_theta, r), vec3::dot(out.e_theta, l_out));
  return stokes_rotation(psi_out) * P.matrix() * stokes_rotation(psi_in);
}

}  // namespace polrig
