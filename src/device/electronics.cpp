#include "polrig/device/electronics.h"

#include <cmath>
#include <numbers>

namespace polrig {

std::int32_t adc_count(double volts, const Electronics& e) {
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

namespace {
constexpr std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}
// A uniform deviate in (0, 1]: never 0, so log() below is finite.
double unit_interval(std::uint64_t bits) {
  return static_cast<double>((bits >> 11) + 1) * 0x1.0p-53;
}
}  // namespace

double standard_normal(std::uint64_t seed, std::uint64_t stop, std::uint64_t channel,
                       std::uint64_t sample) {
  std::uint64_t h = splitmix64(seed);
  h = splitmix64(h ^ stop);
  h = splitmix64(h ^ (channel + 0x632BE59BD9B4E019ull));
  h = splitmix64(h ^ (sample + 0x8CB92BA72F3D8DD7ull));
  const double u1 = unit_interval(h);
  const double u2 = unit_interval(splitmix64(h));
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

}  // namespace polrig
