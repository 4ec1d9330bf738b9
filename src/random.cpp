#include "polrig/random.h"

#include <cmath>
#include <numbers>

namespace polrig {
namespace {

using detail::splitmix64;

std::uint64_t mix(std::uint64_t seed, std::uint64_t a, std::uint64_t b, std::uint64_t c) {
  std::uint64_t h = splitmix64(seed);
  h = splitmix64(h ^ a);
  h = splitmix64(h ^ (b + 0x632BE59BD9B4E019ull));
  return splitmix64(h ^ (c + 0x8CB92BA72F3D8DD7ull));
}

// (0, 1]: never 0, so log() is finite.
double unit_interval(std::uint64_t bits) {
  return static_cast<double>((bits >> 11) + 1) * 0x1.0p-53;
}

}  // namespace

double standard_normal(std::uint64_t seed, std::uint64_t stop, std::uint64_t channel,
                       std::uint64_t sample) {
  const std::uint64_t h = mix(seed, stop, channel, sample);
  const double u1 = unit_interval(h);
  const double u2 = unit_interval(splitmix64(h));
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

std::uint64_t derive_seed(std::uint64_t seed, std::uint64_t index) {
  return splitmix64(splitmix64(seed ^ 0xD1B54A32D192ED03ull) + index);
}

}  // namespace polrig
