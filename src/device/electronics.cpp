#include "polrig/device/electronics.h"

#include <cmath>
#include <stdexcept>

namespace polrig {

std::int32_t adc_count(double volts, const Electronics& e) {
  if (!std::isfinite(volts)) throw std::domain_error("the ADC was given a non-finite voltage");
  const double full_scale = std::ldexp(1.0, e.adc_bits - 1);
  const double max_count = full_scale - 1.0;
  double count = std::floor(volts / e.vref_V * full_scale + 0.5);
  if (count > max_count) count = max_count;
  if (count < -max_count) count = -max_count;
  return static_cast<std::int32_t>(count);
}

double adc_volts(std::int32_t count, const Electronics& e) {
  return static_cast<double>(count) * e.vref_V / std::ldexp(1.0, e.adc_bits - 1);
}

}  // namespace polrig
