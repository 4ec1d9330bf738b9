#include "polrig/device/sensor.h"

#include <cmath>

#include "polrig/units.h"

namespace polrig {

double channel_response(const CalibrationParams& p, int m, double theta_deg, double d) {
  const double sign = (m % 2 == 0) ? 1.0 : -1.0;
  const double c = (1.0 + p.kd[m]) * d;
  return 1.0 + sign * c * std::cos(deg2rad(2.0 * theta_deg + p.alpha_deg[m]));
}

double film_axis_from_alpha_deg(const CalibrationParams& p, int m) {
  const bool is_h = (m % 2) == 1;
  return 0.5 * ((is_h ? 180.0 : 0.0) - p.alpha_deg[m]);
}

double pair_voltage(const CalibrationParams& p, const Electronics& e, int i, double E_j,
                    double E_h, double theta_deg, double d) {
  const double ratio = (E_j * channel_response(p, pair_j(i), theta_deg, d)) /
                       (E_h * channel_response(p, pair_h(i), theta_deg, d));
  return p.kv[i] * e.volts_per_decade * std::log10(ratio) + p.k_mV[i] * 1e-3;
}

std::array<double, 3> pair_voltages(const CalibrationParams& p, const Electronics& e,
                                    const std::array<double, 6>& E, double theta_deg, double d) {
  std::array<double, 3> v;
  for (int i = 0; i < 3; ++i)
    v[i] = pair_voltage(p, e, i, E[pair_j(i)], E[pair_h(i)], theta_deg, d);
  return v;
}


}  // namespace polrig
