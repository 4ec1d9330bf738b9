#include "polrig/optics/polarized_ray.h"

#include <cmath>
#include <stdexcept>

#include "polrig/units.h"
#include "ray_math.h"

namespace polrig {

using namespace optics_detail;

PolarizedRay unpolarized_ray(const Vec3& k, double S0) {
  int i = 0;
  for (int j = 1; j < 3; ++j)
    if (std::abs(k[j]) < std::abs(k[i])) i = j;
  Vec3 e{0, 0, 0};
  e[i] = 1;
  return {k, unit(reject(e, k)), unpolarized(S0)};
}

void set_frame(PolarizedRay& ray, const Vec3& u) {
  const Vec3 x = reject(u, ray.k);
  if (!(norm(x) > 1e-12 * norm(u))) throw std::invalid_argument("set_frame: u is parallel to k");
  const Vec3 y_hat = cross(ray.k, ray.x_hat);
  const double alpha = std::atan2(dot(x, y_hat), dot(x, ray.x_hat));
  ray.S = frame_rotation(rad2deg(alpha)) * ray.S;
  ray.x_hat = unit(x);
}

void pass_sheet_polarizer(PolarizedRay& ray, const Vec3& film_normal, const Vec3& axis,
                          double tau_M, double tau_m) {
  const Vec3 m = cross(film_normal, axis);  // absorption axis
  set_frame(ray, cross(ray.k, m));          // x_hat = e_t, the ordinary wave
  ray.S = diattenuator(tau_M, tau_m) * ray.S;
}

bool refract(PolarizedRay& ray, const Vec3& normal, double n1, double n2) {
  const Vec3 n = dot(normal, ray.k) > 0 ? mul(normal, -1.0) : normal;  // facing the incoming ray
  const auto k_out = snell(ray.k, n, n1, n2);
  if (!k_out) return false;
  const Vec3 s = cross(ray.k, n);
  if (norm(s) > 1e-9) set_frame(ray, s);
  const FresnelR r = fresnel_r(n1, n2, -dot(n, ray.k));
  ray.S = diattenuator(1 - r.s * r.s, 1 - r.p * r.p) * ray.S;
  ray.k = *k_out;
  ray.x_hat = unit(reject(ray.x_hat, ray.k));  // s is ⊥ k_out too; this only removes rounding
  return true;
}

SheetPolarizerPair::SheetPolarizerPair(const Vec3& film_normal, const Vec3& axis1, double tau_M1,
                                       double tau_m1, const Vec3& axis2, double tau_M2, double tau_m2)
    : m1_(cross(film_normal, axis1)), m2_(cross(film_normal, axis2)),
      aa_(0.25 * (tau_M1 + tau_m1) * (tau_M2 + tau_m2)), bb_(0.25 * (tau_M1 - tau_m1) * (tau_M2 - tau_m2)) {}

double SheetPolarizerPair::transmittance(const Vec3& k) const {
  const Vec3 e1 = cross(k, m1_), e2 = cross(k, m2_);
  const double c = dot(e1, e2);
  // cos 2χ = 2cos²χ − 1 with cos²χ = (e1·e2)²/(|e1|²|e2|²): no square roots.
  return aa_ + bb_ * (2 * c * c / (dot(e1, e1) * dot(e2, e2)) - 1);
}

MuellerMatrix diattenuator(double T_x, double T_y) {
  const double a = 0.5 * (T_x + T_y), b = 0.5 * (T_x - T_y), c = std::sqrt(T_x * T_y);
  MuellerMatrix m;
  m << a, b, 0, 0,
       b, a, 0, 0,
       0, 0, c, 0,
       0, 0, 0, c;
  return m;
}

}  // namespace polrig
