// Positioning from the sun's zenith angle (compass/positioning, W16 Eq. 17): one fix over W16's static
// hour at 1 Hz (3601 sightings, noise-free zenith angles from the full ERFA ephemeris, a prior
// 100 km away), with both roots (the target: < 50 ms) and the chosen root alone; as
// references measured in the same run, what one re-linearization costs (a SunTrack at a site and
// its δ, GHA at every sighting) and one evaluation of the closed form (one acos per sighting).
//   build/bench/polrig_bench --benchmark_filter=Positioning
#include <cmath>
#include <vector>

#include <benchmark/benchmark.h>

#include "polrig/compass/positioning.h"
#include "polrig/sky/sun.h"

namespace {
using namespace polrig;

const Site kSite{28.221, 112.992, 0};
const Site kPrior{28.9, 113.6, 0};

const std::vector<ZenithSighting>& w16_hour() {
  static const std::vector<ZenithSighting> z = [] {
    const UtcTime t0 = parse_utc("2015-12-16T05:37:00Z");
    std::vector<ZenithSighting> v;
    for (int k = 0; k <= 3600; ++k) v.push_back({t0.plus_seconds(k), sun_position(t0.plus_seconds(k), kSite).zenith_deg, 1});
    return v;
  }();
  return z;
}

void BM_Positioning_FixW16HourBothRoots(benchmark::State& state) {
  const auto& z = w16_hour();
  for (auto _ : state) benchmark::DoNotOptimize(fix_position(z, kPrior));
}
BENCHMARK(BM_Positioning_FixW16HourBothRoots)->Unit(benchmark::kMillisecond);

void BM_Positioning_FixW16HourOneRoot(benchmark::State& state) {
  const auto& z = w16_hour();
  PositionOptions o;
  o.second_root = false;
  for (auto _ : state) benchmark::DoNotOptimize(fix_position(z, kPrior, o));
}
BENCHMARK(BM_Positioning_FixW16HourOneRoot)->Unit(benchmark::kMillisecond);

// Reference: one re-linearization's ephemeris (the fit builds three per root).
void BM_Positioning_RefOneSunTrackAt3601(benchmark::State& state) {
  const auto& z = w16_hour();
  for (auto _ : state) {
    const SunTrack track(z.front().utc, z.back().utc, kPrior);
    double acc = 0;
    for (const ZenithSighting& s : z) acc += track.hour_angle_at(s.utc).sin_dec;
    benchmark::DoNotOptimize(acc);
  }
}
BENCHMARK(BM_Positioning_RefOneSunTrackAt3601)->Unit(benchmark::kMillisecond);

// Reference: the closed form once over the hour (zenith_model: one acos, sin/cos per sighting).
void BM_Positioning_RefClosedForm3601(benchmark::State& state) {
  std::vector<double> dec(3601), gha(3601);
  for (std::size_t k = 0; k < dec.size(); ++k) {
    dec[k] = -0.4066;
    gha[k] = 4.63 + 7.29e-5 * static_cast<double>(k);
  }
  for (auto _ : state) {
    double acc = 0;
    for (std::size_t k = 0; k < dec.size(); ++k) acc += zenith_model(dec[k], gha[k], 0.4926, 1.972).zenith_rad;
    benchmark::DoNotOptimize(acc);
  }
}
BENCHMARK(BM_Positioning_RefClosedForm3601)->Unit(benchmark::kMillisecond);

}  // namespace
