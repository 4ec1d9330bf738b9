#include "polrig/device/params.h"

#include <cmath>

namespace polrig {
namespace {
double wrap_pm180(double deg) {
  double w = std::fmod(deg, 360.0);
  if (w <= -180.0) w += 360.0;
  if (w > 180.0) w -= 360.0;
  return w;
}
}  // namespace

CalibrationParams CalibrationParams::theory(const std::array<double, 6>& film_axis_deg) {
  CalibrationParams p;
  for (int m = 0; m < 6; ++m) {
    const bool is_h = (m % 2) == 1;  // second channel of a pair enters Eq. 15 with a minus sign
    p.alpha_deg[m] = wrap_pm180((is_h ? 180.0 : 0.0) - 2.0 * film_axis_deg[m]);
  }
  return p;
}

CalibrationParams CalibrationParams::wang2019_indoor() {
  CalibrationParams p;
  p.alpha_deg = {0.7554, 0.5500, -117.6462, -116.5699, 123.0730, 120.6994};
  p.k_mV = {-10.1519, 7.9230, -9.4542};
  p.kv = {1.0224, 1.0081, 1.0183};
  p.kd = {-0.0438, -0.0365, -0.0457, -0.0492, -0.0555, -0.0166};
  return p;
}

}  // namespace polrig
