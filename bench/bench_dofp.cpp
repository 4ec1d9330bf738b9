// The DoFP camera's frame simulation (issue 12's target: < 5 ms per 640 × 480 frame), against a
// reference measured in the same run: one random.h standard normal per pixel, the cost of the
// six-photodiode simulation's noise for the same count.
#include <benchmark/benchmark.h>

#include "polrig/random.h"
#include "polrig/sim/dofp_frames.h"

using namespace polrig;

namespace {

Rig camera_rig(bool sky) {
  Rig rig;
  rig.device_kind = "dofp-camera";
  rig.source.cos4.E_0 = 1.0;
  rig.camera.gain_spread = 0.02;
  rig.camera.offset_DN = 20;
  if (sky) {
    rig.source.model = "sky";
    rig.light = make_source(rig.source);
  }
  return rig;
}

void BM_Reference_StandardNormal_640x480(benchmark::State& state) {
  std::vector<double> z(640 * 480);
  std::uint64_t stop = 0;
  for (auto _ : state) {
    for (std::size_t i = 0; i < z.size(); ++i) z[i] = standard_normal(1, stop, i, 0);
    ++stop;
    benchmark::DoNotOptimize(z.data());
  }
}
BENCHMARK(BM_Reference_StandardNormal_640x480)->Unit(benchmark::kMillisecond);

void dofp_frame(benchmark::State& state, bool sky) {
  const DofpSimulator sim(camera_rig(sky));
  const DofpStop stop = sim.stops()[1];
  int frame = 0;
  for (auto _ : state) benchmark::DoNotOptimize(sim.frame(stop, frame++).data());
}
// A sphere-rig frame (cos4: uniform polarized light), noise on: the indoor dataset's frames.
void BM_DofpFrame_Cos4_640x480(benchmark::State& state) { dofp_frame(state, false); }
BENCHMARK(BM_DofpFrame_Cos4_640x480)->Unit(benchmark::kMillisecond)->UseRealTime();
// A further frame of a stop whose signal (the light along the views, Eq. 18 without noise) is
// made: the noise and the ADC alone, what each of a stop's frames_per_stop frames after its first costs.
void BM_DofpFrame_Cos4_NextFrameOfStop_640x480(benchmark::State& state) {
  const DofpSimulator sim(camera_rig(false));
  const DofpSimulator::StopSignal signal = sim.signal(sim.stops()[1]);
  int frame = 0;
  for (auto _ : state) benchmark::DoNotOptimize(sim.frame(signal, frame++).data());
}
BENCHMARK(BM_DofpFrame_Cos4_NextFrameOfStop_640x480)->Unit(benchmark::kMillisecond)->UseRealTime();
// A sky frame: the Rayleigh sky along every pixel's view (the sun once per frame).
void BM_DofpFrame_Sky_640x480(benchmark::State& state) { dofp_frame(state, true); }
BENCHMARK(BM_DofpFrame_Sky_640x480)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
