#include "polrig/random.h"

#include <cmath>
#include <numbers>

namespace polrig {
namespace {

using detail::splitmix64;

// (0, 1]: never 0, so log() is finite.
double unit_interval(std::uint64_t bits) {
  return static_cast<double>((bits >> 11) + 1) * 0x1.0p-53;
}

}  // namespace

double NormalStream::operator()(std::uint64_t sample) const {
  const std::uint64_t h = splitmix64(prefix_ ^ (sample + detail::kDrawOffset));
  const double u1 = unit_interval(h);
  const double u2 = unit_interval(splitmix64(h));
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

double standard_normal(std::uint64_t seed, std::uint64_t stop, std::uint64_t channel,
                       std::uint64_t sample) {
  return NormalStream(seed, stop, channel)(sample);
}

std::uint64_t derive_seed(std::uint64_t seed, std::uint64_t index) {
  return splitmix64(splitmix64(seed ^ 0xD1B54A32D192ED03ull) + index);
}

}  // namespace polrig
