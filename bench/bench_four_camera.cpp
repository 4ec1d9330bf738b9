// W16's four-camera Stokes image (issue 13's target: a 1034 × 778 four-camera Stokes image in
// under 20 ms): co-registration (bilinear resampling of four frames onto the virtual camera 1
// grid) and the per-pixel Eqs. 3–5, against a reference measured in the same run: the spec's
// closed form for 0/45/90/135° on already co-registered frames (x1 = (F1 − F3)/2, x2 = (F2 − F4)/2,
// x3 = ΣF/4, AoP, DoP), the least any fusion of four frames into five layers costs.
#include <cmath>

#include <benchmark/benchmark.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "polrig/sim/four_camera_frames.h"

using namespace polrig;

namespace {

Rig four_camera_rig() {
  Rig rig;
  rig.device_kind = "four-camera";
  rig.source.model = "sky";
  rig.source.sky.first_stop_utc = "2015-12-16T06:37:00Z";
  rig.source.sky.sky.site.lat_deg = 28.221;
  rig.source.sky.sky.site.lon_deg = 112.992;
  rig.light = make_source(rig.source);
  rig.schedule.angles_deg = {0};
  return rig;
}

struct Frames {
  FourCameraSimulator sim{four_camera_rig()};
  std::array<std::vector<std::uint16_t>, 4> raw = sim.frames(sim.signal(sim.stops()[0]));
};
const Frames& frames() {
  static const Frames f;
  return f;
}

void BM_Reference_ClosedFormStokes_1034x778(benchmark::State& state) {
  const Frames& f = frames();
  const std::size_t n = f.raw[0].size();
  std::vector<float> S0(n), S1(n), S2(n), aop(n), dop(n);
  for (auto _ : state) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 8192), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i < r.end(); ++i) {
        const double F1 = f.raw[0][i], F2 = f.raw[1][i], F3 = f.raw[2][i], F4 = f.raw[3][i];
        const double x1 = 0.5 * (F1 - F3), x2 = 0.5 * (F2 - F4), x3 = 0.25 * (F1 + F2 + F3 + F4);
        S0[i] = static_cast<float>(x3), S1[i] = static_cast<float>(x1), S2[i] = static_cast<float>(x2);
        aop[i] = static_cast<float>(0.5 * std::atan2(x2, x1));
        dop[i] = static_cast<float>(std::sqrt(x1 * x1 + x2 * x2) / x3);
      }
    });
    benchmark::DoNotOptimize(dop.data());
  }
}
BENCHMARK(BM_Reference_ClosedFormStokes_1034x778)->Unit(benchmark::kMillisecond)->UseRealTime();

// The target: four raw frames → the fused S0, S1, S2, AoP, DoP on the virtual grid.
void BM_FourCameraStokesImage_1034x778(benchmark::State& state) {
  const Frames& f = frames();
  for (auto _ : state) benchmark::DoNotOptimize(f.sim.fuse(f.raw).DoP.data());
}
BENCHMARK(BM_FourCameraStokesImage_1034x778)->Unit(benchmark::kMillisecond)->UseRealTime();

// One stop's frames from the sky (the Rayleigh sky along 4 × 1034 × 778 views, Eq. 1, noise, ADC):
// what `polrig simulate` spends per stop before fusing and writing.
void BM_FourCameraSkyFrames_1034x778(benchmark::State& state) {
  const Frames& f = frames();
  for (auto _ : state) benchmark::DoNotOptimize(f.sim.frames(f.sim.signal(f.sim.stops()[0]))[3].data());
}
BENCHMARK(BM_FourCameraSkyFrames_1034x778)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
