#include "polrig/calib/model.h"

#include <cmath>
#include <limits>
#include <numbers>

#include "polrig/device/sensor.h"
#include "polrig/units.h"

namespace polrig {

FitParams::Vector FitParams::vector() const {
  Vector x;
  for (int m = 0; m < 6; ++m) x(alpha_index(m)) = alpha_deg[m], x(c_index(m)) = c[m];
  for (int i = 0; i < 3; ++i) x(k_index(i)) = k_mV[i], x(kv_index(i)) = kv[i];
  return x;
}

FitParams FitParams::from_vector(const Vector& x) {
  FitParams p;
  for (int m = 0; m < 6; ++m) p.alpha_deg[m] = x(alpha_index(m)), p.c[m] = x(c_index(m));
  for (int i = 0; i < 3; ++i) p.k_mV[i] = x(k_index(i)), p.kv[i] = x(kv_index(i));
  return p;
}

FitParams FitParams::coupled(const CalibrationParams& q, double d) {
  FitParams p;
  p.alpha_deg = q.alpha_deg;
  p.k_mV = q.k_mV;
  p.kv = q.kv;
  for (int m = 0; m < 6; ++m) p.c[m] = (1.0 + q.kd[m]) * d;
  return p;
}

CalibrationParams FitParams::decoupled(double d_a) const {
  CalibrationParams q;
  q.alpha_deg = alpha_deg;
  q.k_mV = k_mV;
  q.kv = kv;
  for (int m = 0; m < 6; ++m) q.kd[m] = c[m] / d_a - 1.0;
  return q;
}

// r·c is exactly c when r = 1, so a source with a constant d fits bit for bit as before.
double eq15_voltage(const FitParams& p, double v_dec, int i, double theta_deg, double r) {
  const int j = pair_j(i), h = pair_h(i);
  const double num = 1.0 + r * p.c[j] * std::cos(deg2rad(2.0 * theta_deg + p.alpha_deg[j]));
  const double den = 1.0 - r * p.c[h] * std::cos(deg2rad(2.0 * theta_deg + p.alpha_deg[h]));
  if (!(num > 0.0 && den > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  return p.kv[i] * v_dec * std::log10(num / den) + p.k_mV[i] * 1e-3;
}

FitParams::Vector eq15_gradient(const FitParams& p, double v_dec, int i, double theta_deg,
                                double r) {
  const int j = pair_j(i), h = pair_h(i);
  const double xj = deg2rad(2.0 * theta_deg + p.alpha_deg[j]);
  const double xh = deg2rad(2.0 * theta_deg + p.alpha_deg[h]);
  const double num = 1.0 + r * p.c[j] * std::cos(xj);
  const double den = 1.0 - r * p.c[h] * std::cos(xh);
  const double g = p.kv[i] * v_dec / std::numbers::ln10;  // d(kv·v·log10 u)/du = g/u
  FitParams::Vector grad = FitParams::Vector::Zero();
  grad(FitParams::alpha_index(j)) = g * (-(r * p.c[j]) * std::sin(xj)) / num * deg2rad(1.0);
  grad(FitParams::alpha_index(h)) = -g * (r * p.c[h] * std::sin(xh)) / den * deg2rad(1.0);
  grad(FitParams::c_index(j)) = g * (r * std::cos(xj)) / num;
  grad(FitParams::c_index(h)) = g * (r * std::cos(xh)) / den;
  grad(FitParams::k_index(i)) = 1e-3;
  grad(FitParams::kv_index(i)) = v_dec * std::log10(num / den);
  return grad;
}

}  // namespace polrig
