#pragma once
// Counter-based random numbers: each value is a pure function of (seed, counters), so results
// are reproducible whatever thread draws them and in whatever order. std::normal_distribution
// is not specified bit-for-bit across libraries, so it is not used. SplitMix64 mixes the
// counters; Box–Muller turns two 53-bit uniforms into a normal deviate.
#include <cstdint>

namespace polrig {

// A uniform deviate in (0, 1].
double uniform_unit(std::uint64_t seed, std::uint64_t a, std::uint64_t b, std::uint64_t c);

// A standard normal deviate; the noise of (stop, channel, sample) under a rig's seed.
double standard_normal(std::uint64_t seed, std::uint64_t stop, std::uint64_t channel,
                       std::uint64_t sample);

// An independent seed for sub-experiment `index` (a Monte-Carlo trial) of `seed`.
std::uint64_t derive_seed(std::uint64_t seed, std::uint64_t index);

}  // namespace polrig
