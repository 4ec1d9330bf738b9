// Google Benchmark cases for polrig. Speed is reported as ratios against references measured in
// the same run (bench/README.md): a bare loop of the same number of log10 calls that one CS
// study must make, so the ratio says how close the study is to its arithmetic floor.
#include <cmath>
#include <vector>

#include <benchmark/benchmark.h>

#include "polrig/rig/rig.h"
#include "polrig/sim/simulate.h"
#include "polrig/study/cs.h"
#include "polrig/study/sweep.h"

namespace {
using namespace polrig;

// Reference: 3 pairs × 360 angles of log10, the transcendental floor of one CS study.
void BM_Reference_Log10_1080(benchmark::State& state) {
  std::vector<double> x(1080);
  for (std::size_t k = 0; k < x.size(); ++k) x[k] = 1.0 + 1e-3 * static_cast<double>(k);
  for (auto _ : state) {
    double s = 0.0;
    for (double v : x) s += std::log10(v);
    benchmark::DoNotOptimize(s);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Reference_Log10_1080);

// One CS study summary (one sweep grid point): 360 table angles, three pairs.
void BM_CsSummary(benchmark::State& state) {
  const Rig rig;
  const CsTurn turn(360);
  std::vector<double> scratch;
  for (auto _ : state) benchmark::DoNotOptimize(cs_summary(rig, turn, scratch));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_CsSummary);

// The full CS study with its deviation curves, as `polrig study cs` computes it.
void BM_CsStudy(benchmark::State& state) {
  const Rig rig;
  const CsTurn turn(360);
  for (auto _ : state) benchmark::DoNotOptimize(cs_study(rig, turn));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_CsStudy);

// A sweep of 20,000 grid points on all cores: items/s is grid points per second.
void BM_Sweep_20k(benchmark::State& state) {
  const Rig rig;
  const CsTurn turn(360);
  const std::vector<GridAxis> axes{GridAxis::parse("eccentricity.L_S=0.001:1:200"),
                                   GridAxis::parse("eccentricity.L_IS=0.001:1:100")};
  for (auto _ : state) benchmark::DoNotOptimize(sweep(rig, axes, turn));
  state.SetItemsProcessed(state.iterations() * 20000);
}
BENCHMARK(BM_Sweep_20k)->Unit(benchmark::kMillisecond)->UseRealTime();

// `polrig simulate` on the default rig: 37 stops × 40 samples × 3 pairs.
void BM_Simulate_DefaultRig(benchmark::State& state) {
  const Rig rig;
  for (auto _ : state) benchmark::DoNotOptimize(simulate(rig, false));
  state.SetItemsProcessed(state.iterations() * 37);
}
BENCHMARK(BM_Simulate_DefaultRig)->UseRealTime();

}  // namespace
