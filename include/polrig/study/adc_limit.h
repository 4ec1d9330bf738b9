#pragma once
// The accuracy limit that the ADC alone sets (spec §2, paper §2.4 and Fig. 6): an ideal sensor
// (theory parameters, uniform light, no noise) whose voltages pass through Eq. 3.
#include <array>
#include <vector>

#include "polrig/device/electronics.h"

namespace polrig {

struct AdcLimit {
  double d;
  double vmax_mV;    // largest pair voltage over θ (unquantized)
  double limit_deg;  // max |θ12 − θ| over θ ∈ [0°, 180°) in `step_deg` steps, quantized voltages
};

AdcLimit adc_accuracy_limit(double d, const Electronics& e,
                            const std::array<double, 6>& film_axis_deg, double step_deg = 0.1);

// The θ12 error curve behind one limit (paper Fig. 5): θ and θ12 − θ in degrees.
struct AdcErrorCurve {
  std::vector<double> theta_deg, error_deg;
};
AdcErrorCurve adc_error_curve(double d, const Electronics& e,
                              const std::array<double, 6>& film_axis_deg, double step_deg = 0.1);

}  // namespace polrig
