// The sky's Google Benchmark cases: sun positions per second (exact ERFA place and the
// interpolated SunTrack), sky_light calls per second and sky-map pixels per second.
//   build/bench/polrig_bench --benchmark_filter='Sky'
#include <cstdint>
#include <vector>

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include "polrig/sky/sky.h"
#include "polrig/sky/sky_map.h"
#include "polrig/sky/sun_rows.h"
#include "polrig/sky/vector_rt.h"
#include "polrig/sky/vector_rt_sky.h"

namespace {
using namespace polrig;

// Times spread over one day (distinct for every call, so nothing is cached).
UtcTime day_time(std::uint64_t k) { return {1542326400.0 + static_cast<double>(k % 86400) + 0.37}; }

void BM_Sky_SunPositionExact(benchmark::State& state) {
  const Site site;
  std::uint64_t k = 0;
  for (auto _ : state) benchmark::DoNotOptimize(sun_position(day_time(k++ * 7919), site));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Sky_SunPositionExact);

void BM_Sky_SunTrackInterpolated(benchmark::State& state) {
  const Site site;
  SunSettings settings;
  settings.refraction = state.range(0) != 0;
  const SunTrack track(day_time(0), day_time(86399), site, settings);
  std::uint64_t k = 0;
  for (auto _ : state) benchmark::DoNotOptimize(track.at(day_time(k++ * 7919)));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Sky_SunTrackInterpolated)->Arg(0)->Arg(1);

void BM_Sky_SkyLight(benchmark::State& state) {
  const SkyModel model{MaxDegree{}, static_cast<SkyRadiance>(state.range(0))};
  const Vec3 s = vec3::unit({-0.6, -0.3, 0.2});
  std::vector<Vec3> views;
  for (int i = 0; i < 1024; ++i)
    views.push_back(vec3::unit({std::cos(i * 0.1), std::sin(i * 0.1), 0.1 + (i % 37) * 0.05}));
  std::size_t k = 0;
  for (auto _ : state) benchmark::DoNotOptimize(sky_light(s, views[k++ & 1023], model));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Sky_SkyLight)->Arg(0)->Arg(1)->Arg(2);  // uniform, rayleigh, cie-clear

// One 1024 × 1024 map (its pixels per second), on range(0) threads.
void BM_Sky_Map1024(benchmark::State& state) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                            static_cast<std::size_t>(state.range(0)));
  const Sky sky;
  for (auto _ : state) benchmark::DoNotOptimize(sky_map(sky, 1024));
  state.SetItemsProcessed(state.iterations() * 1024 * 1024);
}
BENCHMARK(BM_Sky_Map1024)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

// One exact polarized Rayleigh solve (default 32 streams, sun at 60° zenith) at τ = range(0)/100,
// with range(1) views off the quadrature carried through the doublings. The bound is
// "well under 10 ms" on one core.
void BM_Sky_VectorRtSolve(benchmark::State& state) {
  VectorRtSettings s;
  s.tau_rayleigh = static_cast<double>(state.range(0)) / 100;
  std::vector<double> views;
  for (int k = 0; k < state.range(1); ++k) views.push_back((k + 0.5) / static_cast<double>(state.range(1)));
  for (auto _ : state) benchmark::DoNotOptimize(solve_vector_rt(s, 0.5, views));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Sky_VectorRtSolve)->Args({25, 0})->Args({100, 0})->Args({25, 16})->Unit(benchmark::kMillisecond);

// `sky table`'s work for 200,000 views under one fixed sun (sky_along: one SunSky, then every
// row), on one thread: range(0) = 0 the single-scattering sky (the reference), 1 the vector-RT
// sky (its grid solves made before the timing: the steady state of a process that has asked for
// this sun once). The bound: within 3× of the reference.
void BM_Sky_Table200k(benchmark::State& state) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
  SkyModel model;
  if (state.range(0) == 1) {
    model.kind = SkyKind::VectorRt;
    model.vector_rt = vector_rt_sky({});
  }
  std::vector<SkyQuery> q(200000);
  for (std::size_t i = 0; i < q.size(); ++i) {
    q[i].sun = fixed_sun(151.5, 33.3);
    q[i].view_az_deg = static_cast<double>((i * 7919) % 36000) / 100;
    q[i].view_el_deg = static_cast<double>(i % 9000) / 100;
  }
  benchmark::DoNotOptimize(sky_along(std::span(q).first(10), model));  // the grid's solves
  for (auto _ : state) benchmark::DoNotOptimize(sky_along(q, model));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(q.size()));
}
BENCHMARK(BM_Sky_Table200k)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
