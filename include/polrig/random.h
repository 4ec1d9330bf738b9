#pragma once
// Counter-based random numbers: each value is a pure function of (seed, counters), so results
// are reproducible whatever thread draws them and in whatever order. std::normal_distribution
// is not specified bit-for-bit across libraries, so it is not used. SplitMix64 mixes the
// counters; Box–Muller turns two 53-bit uniforms into a normal deviate.
#include <cstdint>

namespace polrig {

namespace detail {
constexpr std::uint64_t splitmix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}
// The part of a draw's hash that depends on (seed, a, b); the draw c is then
// splitmix64(prefix ^ (c + kDrawOffset)).
constexpr std::uint64_t stream_prefix(std::uint64_t seed, std::uint64_t a, std::uint64_t b) {
  return splitmix64(splitmix64(splitmix64(seed) ^ a) ^ (b + 0x632BE59BD9B4E019ull));
}
constexpr std::uint64_t kDrawOffset = 0x8CB92BA72F3D8DD7ull;
}  // namespace detail

// The uniform deviates uniform_unit(seed, a, b, c) for c = 0, 1, 2 …, with the part of the hash
// that depends on (seed, a, b) computed once: a photon's stream in the sphere tracer.
class UniformStream {
 public:
  constexpr UniformStream(std::uint64_t seed, std::uint64_t a, std::uint64_t b)
      : prefix_(detail::stream_prefix(seed, a, b)) {}
  // (0, 1]: never 0, so log() is finite.
  constexpr double operator()(std::uint64_t c) const {
    const std::uint64_t bits = detail::splitmix64(prefix_ ^ (c + detail::kDrawOffset));
    return static_cast<double>((bits >> 11) + 1) * 0x1.0p-53;
  }

 private:
  std::uint64_t prefix_;
};

// A uniform deviate in (0, 1].
inline double uniform_unit(std::uint64_t seed, std::uint64_t a, std::uint64_t b, std::uint64_t c) {
  return UniformStream(seed, a, b)(c);
}

// The standard normal deviates of (stop, channel) under a seed for sample = 0, 1, 2 …, with the
// part of the hash that depends on (seed, stop, channel) computed once: a sensor's samples of one
// reading. Box–Muller on two uniforms in (0, 1].
class NormalStream {
 public:
  constexpr NormalStream(std::uint64_t seed, std::uint64_t stop, std::uint64_t channel)
      : prefix_(detail::stream_prefix(seed, stop, channel)) {}
  double operator()(std::uint64_t sample) const;

 private:
  std::uint64_t prefix_;
};

// A standard normal deviate; the noise of (stop, channel, sample) under a rig's seed:
// NormalStream(seed, stop, channel)(sample).
double standard_normal(std::uint64_t seed, std::uint64_t stop, std::uint64_t channel,
                       std::uint64_t sample);

// An independent seed for sub-experiment `index` (a Monte-Carlo trial) of `seed`.
std::uint64_t derive_seed(std::uint64_t seed, std::uint64_t index);

}  // namespace polrig
