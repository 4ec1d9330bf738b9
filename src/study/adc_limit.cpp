#include "polrig/study/adc_limit.h"

#include <algorithm>
#include <cmath>

#include "polrig/calib/angles.h"
#include "polrig/device/sensor.h"
#include "polrig/units.h"

namespace polrig {

AdcErrorCurve adc_error_curve(double d, const Electronics& e,
                              const std::array<double, 6>& film_axis_deg, double step_deg) {
  const CalibrationParams theory = CalibrationParams::theory(film_axis_deg);
  const std::array<double, 6> uniform{1, 1, 1, 1, 1, 1};
  AdcErrorCurve curve;
  const int n = static_cast<int>(std::llround(180.0 / step_deg));
  for (int k = 0; k < n; ++k) {
    const double theta = k * step_deg;
    std::array<double, 3> V = pair_voltages(theory, e, uniform, theta, d);
    for (double& v : V) v = adc_quantize(v, e);
    const PairAngle t12 = pair_angle(theory, e, V, 0, 1);
    curve.theta_deg.push_back(theta);
    curve.error_deg.push_back(axis_difference_deg(t12.theta_deg, theta));
  }
  return curve;
}

AdcLimit adc_accuracy_limit(double d, const Electronics& e,
                            const std::array<double, 6>& film_axis_deg, double step_deg) {
  const AdcErrorCurve curve = adc_error_curve(d, e, film_axis_deg, step_deg);
  const CalibrationParams theory = CalibrationParams::theory(film_axis_deg);
  const std::array<double, 6> uniform{1, 1, 1, 1, 1, 1};
  double vmax = 0.0, limit = 0.0;
  for (std::size_t k = 0; k < curve.theta_deg.size(); ++k) {
    for (double v : pair_voltages(theory, e, uniform, curve.theta_deg[k], d))
      vmax = std::max(vmax, std::abs(v));
    limit = std::max(limit, std::abs(curve.error_deg[k]));
  }
  return {d, vmax * 1e3, limit};
}

}  // namespace polrig
