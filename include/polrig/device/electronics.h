#pragma once
// The sensor's electronics after the photodiodes: log amplifiers, the ADC and electrical noise.
#include <cstdint>

#include "polrig/random.h"  // the noise streams

namespace polrig {

struct Electronics {
  double volts_per_decade = 0.5;  // log-amplifier scale: the "0.5" of Eq. 1
  int adc_bits = 16;              // signed converter: counts in ±(2^(bits−1) − 1)
  double vref_V = 0.6;            // ADC reference voltage
  double noise_sigma_V = 1.0e-4;  // Gaussian noise added to each pair voltage per sample
};

// Eq. 3: count = round_half_up(V / Vref · 2^(bits−1)), clamped to ±(2^(bits−1) − 1).
// "Round half up" rounds exact half counts towards +∞ (2.5 → 3, −2.5 → −2).
std::int32_t adc_count(double volts, const Electronics& e);
double adc_volts(std::int32_t count, const Electronics& e);
inline double adc_quantize(double volts, const Electronics& e) {
  return adc_volts(adc_count(volts, e), e);
}

}  // namespace polrig
