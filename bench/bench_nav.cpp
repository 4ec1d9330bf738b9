// The closed-form heading (nav/heading, W19 Eq. 25): headings solved per second, without a prior
// (the sun-in-front choice) and with one. Inputs: 1024 random tilted poses (|roll|, |pitch| ≤
// 15°, h_s 1°–70°) made by the solver's own forward rotations, cycled.
//   build/bench/polrig_bench --benchmark_filter=Heading
#include <vector>

#include <benchmark/benchmark.h>

#include "polrig/nav/heading.h"
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
