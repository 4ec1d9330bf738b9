// The closed-form heading (compass/heading, W19 Eq. 25): headings solved per second, without a prior
// (the sun-in-front choice) and with one. Inputs: 1024 random tilted poses (|roll|, |pitch| ≤
// 15°, h_s 1°–70°) made by the solver's own forward rotations, cycled.
//   build/bench/polrig_bench --benchmark_filter=Heading
#include <cmath>
#include <vector>

#include <benchmark/benchmark.h>

#include "polrig/compass/heading.h"
#include "polrig/compass/orientation.h"
#include "polrig/sky/rayleigh.h"
#include "polrig/random.h"
#include "polrig/units.h"

namespace {
using namespace polrig;

struct Input {
  Vec3 sun;
  double aop_deg;
  Tilt tilt;
  double prior_deg;
};

std::vector<Input> inputs() {
  std::vector<Input> in;
  for (std::uint64_t k = 0; k < 1024; ++k) {
    const auto u = [&](std::uint64_t c) { return uniform_unit(7, k, 0, c); };
    const double H = 360 * u(0), A = deg2rad(360 * u(3)), h = deg2rad(1 + 69 * u(4));
    const Tilt tilt{-15 + 30 * u(1), -15 + 30 * u(2)};
    const Vec3 s{std::cos(h) * std::sin(A), std::cos(h) * std::cos(A), std::sin(h)};
    const Vec3 v = body_to_enu({0, 0, 1}, H, tilt);
    in.push_back({s, aop_body_deg(vec3::unit(vec3::cross(s, v)), H, tilt), tilt, H + 3});
  }
  return in;
}

void BM_Heading_Solve(benchmark::State& state) {
  const std::vector<Input> in = inputs();
  for (auto _ : state)
    for (const Input& x : in) benchmark::DoNotOptimize(solve_heading(x.sun, x.aop_deg, x.tilt));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(in.size()));
}
BENCHMARK(BM_Heading_Solve)->Unit(benchmark::kMicrosecond);

void BM_Heading_SolveWithPrior(benchmark::State& state) {
  const std::vector<Input> in = inputs();
  for (auto _ : state)
    for (const Input& x : in)
      benchmark::DoNotOptimize(solve_heading(x.sun, x.aop_deg, x.tilt, x.prior_deg));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(in.size()));
}
BENCHMARK(BM_Heading_SolveWithPrior)->Unit(benchmark::kMicrosecond);

}  // namespace

// Orientation from a DoFP sky image (compass/orientation, H17 Eqs. 6–13): one eigenvector solve over
// H17's 19,200 units (target < 1 ms; H17's Matlab R2015b: about 1 ms), the two comparators, and
// as reference the floor every method pays, one cos and one sin per point. Arg: the points'
// spacing in px over the whole 640 × 480 image: 4 → 160 × 120 = 19,200 points (H17's count;
// 640 × 480 pixels in 2 × 2 cells are 320 × 240 cells, see docs/validation.md), 2 → the 76,800
// cells. The sky: single-scattering Rayleigh (sky/rayleigh.h), a level camera, sun at A = 35°,
// θ_s = 60.75°, heading 37°.
//   build/bench/polrig_bench --benchmark_filter=Orientation
namespace {
using namespace polrig;

SkyPoints h17_sky(int spacing_px) {
  const double H = deg2rad(37.0), A = deg2rad(35.0), h = deg2rad(90.0 - 60.75), f_c = 405.4;
  const Vec3 s{std::cos(h) * std::sin(A), std::cos(h) * std::cos(A), std::sin(h)};
  const Vec3 x{std::sin(H), std::cos(H), 0}, y{-std::cos(H), std::sin(H), 0}, z{0, 0, 1};
  const int cols = 640 / spacing_px, rows = 480 / spacing_px;
  std::vector<double> aop;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      const double dx = (c + 0.5) * spacing_px - 320, dy = (r + 0.5) * spacing_px - 240;
      const Vec3 v = vec3::unit(vec3::add(vec3::add(vec3::mul(x, dx), vec3::mul(y, dy)), vec3::mul(z, f_c)));
      aop.push_back(sky_light(s, v, SkyModel{}).aop_deg + rad2deg(std::atan2(dy, dx)));
    }
  return grid_points(cols, rows, spacing_px, std::move(aop));
}

const CameraIntrinsics kH17{405.4, 320.0, 240.0};

void BM_Reference_Orientation_SinCos(benchmark::State& state) {
  const SkyPoints p = h17_sky(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    double acc = 0;
    for (double a : p.aop_deg) acc += std::cos(deg2rad(a)) + std::sin(deg2rad(a));
    benchmark::DoNotOptimize(acc);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Reference_Orientation_SinCos)->Arg(4)->Arg(2)->Unit(benchmark::kMicrosecond);

void BM_Orientation_Eigenvector(benchmark::State& state) {
  const SkyPoints p = h17_sky(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(sun_vector_eigen(p, kH17));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Orientation_Eigenvector)->Arg(4)->Arg(2)->Unit(benchmark::kMicrosecond);

void BM_Orientation_SinglePoint(benchmark::State& state) {
  const SkyPoints p = h17_sky(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(sun_azimuth_single_point(p, kH17, {}, 0.0));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Orientation_SinglePoint)->Arg(4)->Arg(2)->Unit(benchmark::kMicrosecond);

void BM_Orientation_LineDetection(benchmark::State& state) {
  const SkyPoints p = h17_sky(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(sun_azimuth_line(p, kH17, {}, 0.0));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Orientation_LineDetection)->Arg(4)->Arg(2)->Unit(benchmark::kMicrosecond);

}  // namespace
