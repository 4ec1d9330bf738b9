// Z21's system (study/navigation.h): a 20-minute run of rigs/zhang2021-static.yaml at 100 Hz with
// 1 Hz compass readings, each mode alone and all three (the target for all three: < 0.2 s),
// the dataset's simulation, and as a reference measured in the same run the strapdown mechanization
// alone over the same 120000 samples (ins/mechanization.h: no filter, no sun).
//   build/bench/polrig_bench --benchmark_filter=Navigation
#include <string>

#include <benchmark/benchmark.h>

#include "polrig/io/rig_yaml.h"
#include "polrig/ins/mechanization.h"
#include "polrig/study/navigation.h"

namespace {
using namespace polrig;

const Rig& z21_rig() {
  static const Rig rig = load_rig(std::string(POLRIG_SOURCE_DIR) + "/rigs/zhang2021-static.yaml").rig;
  return rig;
}

const NavigationDataset& z21_run() {
  static const NavigationDataset d = simulate_navigation(z21_rig());
  return d;
}

void navigate_modes(benchmark::State& state, std::vector<NavigationMode> modes) {
  const NavigationDataset& d = z21_run();
  NavigationOptions o;
  o.modes = std::move(modes);
  for (auto _ : state) benchmark::DoNotOptimize(navigate(d, z21_rig(), o));
}

void BM_Navigation_AllModes20min(benchmark::State& state) {
  navigate_modes(state, {NavigationMode::Sins, NavigationMode::Pns, NavigationMode::Integrated});
}
BENCHMARK(BM_Navigation_AllModes20min)->Unit(benchmark::kMillisecond);

void BM_Navigation_Sins20min(benchmark::State& state) { navigate_modes(state, {NavigationMode::Sins}); }
BENCHMARK(BM_Navigation_Sins20min)->Unit(benchmark::kMillisecond);

void BM_Navigation_Pns20min(benchmark::State& state) { navigate_modes(state, {NavigationMode::Pns}); }
BENCHMARK(BM_Navigation_Pns20min)->Unit(benchmark::kMillisecond);

void BM_Navigation_Integrated20min(benchmark::State& state) { navigate_modes(state, {NavigationMode::Integrated}); }
BENCHMARK(BM_Navigation_Integrated20min)->Unit(benchmark::kMillisecond);

void BM_Navigation_Simulate20min(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(simulate_navigation(z21_rig()));
}
BENCHMARK(BM_Navigation_Simulate20min)->Unit(benchmark::kMillisecond);

// Reference: the mechanization alone over the run's samples.
void BM_Navigation_RefMechanize20min(benchmark::State& state) {
  const NavigationDataset& d = z21_run();
  for (auto _ : state) {
    InsState s = d.initial;
    for (std::size_t i = 0; i < d.imu.size(); ++i) s = mechanize(s, d.imu[i == 0 ? 0 : i - 1], d.imu[i]);
    benchmark::DoNotOptimize(s);
  }
}
BENCHMARK(BM_Navigation_RefMechanize20min)->Unit(benchmark::kMillisecond);

}  // namespace
