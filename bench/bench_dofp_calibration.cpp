// The whole two-step DoFP calibration at H17's size (spec sky-and-compasses.md §2.4; issue 12's
// target: < 2 s): step 1 from 30 unpolarized levels and step 2 over 19,200 cells × 79 positions
// × 6 intensities (474 frames of 640 × 480), then Table 1. The frames are made once, from
// Eq. 18 with a spread truth and 2 DN of noise, outside the timed loop.
//   build/bench/polrig_bench --benchmark_filter=DofpCalibration
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "polrig/calib/dofp.h"

namespace {
using namespace polrig;

struct DofpBenchData {
  int W, H;
  std::vector<std::vector<double>> frames;
  std::vector<DofpUnpolarizedLevel> levels;
  std::vector<DofpPolarizedStop> stops;
  DofpBenchData(int width, int height) : W(width), H(height) {
    const std::size_t N = static_cast<std::size_t>(W) * H;
    std::vector<double> K(N), b(N), k(N), a(N);
    std::mt19937_64 gen(1);
    std::normal_distribution<double> n01(0, 1);
    const double alpha[4] = {0, 90, 45, 135}, kj[4] = {1, 0.93, 0.96, 0.9}, ej[4] = {0, 1.2, -0.8, 0.6};
    for (std::size_t p = 0; p < N; ++p) {
      const int j = static_cast<int>((p / W) % 2 * 2 + p % 2);
      K[p] = 2000 * (1 + 0.04 * n01(gen));
      b[p] = 50 + 8 * n01(gen);
      k[p] = j == 0 ? 1 : kj[j] + 0.02 * n01(gen);
      a[p] = (alpha[j] - (j == 0 ? 0 : ej[j] + 0.5 * n01(gen))) * std::numbers::pi / 180;
    }
    const auto frame = [&](double I, double d, double phi_deg) {
      std::vector<double> f(N);
      const double phi = phi_deg * std::numbers::pi / 180;
      for (std::size_t p = 0; p < N; ++p)
        f[p] = 0.5 * K[p] * I * (1 + k[p] * d * std::cos(2 * phi - 2 * a[p])) + b[p] + 2 * n01(gen);
      return f;
    };
    frames.reserve(30 + 474);
    for (int i = 0; i < 30; ++i) frames.push_back(frame(i / 29.0, 0, 0));
    const double I[6] = {1, 0.5, 0.25, 0.1, 0.05, 0.025};
    for (double in : I)
      for (int m = 0; m < 79; ++m) frames.push_back(frame(in, 0.9, 30 + 4.6036 * m));
    for (int i = 0; i < 30; ++i) levels.push_back({i / 29.0, frames[i]});
    int s = 30;
    for (double in : I)
      for (int m = 0; m < 79; ++m) stops.push_back({4.6036 * m, in, frames[s++]});
  }
};

// 504 frames, made once: 1.2 GB at 640 × 480, 0.3 GB at 320 × 240.
const DofpBenchData& bench_data(int width) {
  if (width == 640) {
    static const DofpBenchData full(640, 480);
    return full;
  }
  static const DofpBenchData quarter(320, 240);
  return quarter;
}

// Arg: the frame width; 320 × 240 has the 19,200 cells of the target (H17 §2.1's
// "160 × 120 units"), 640 × 480 the 76,800 2 × 2 cells of H17's sensor.
void BM_DofpCalibration_Full(benchmark::State& state) {
  const DofpBenchData& data = bench_data(static_cast<int>(state.range(0)));
  long long usable = 0, iterations = 0;
  for (auto _ : state) {
    const DofpCalibration c = calibrate_dofp(data.W, data.H, data.levels, data.stops);
    usable = c.step2.usable_cells;
    iterations = 0;
    for (const DofpCellFit& f : c.step2.cells) iterations += f.iterations;
    benchmark::DoNotOptimize(c.table1.rows[2].std_deg);
  }
  state.counters["usable_cells"] = static_cast<double>(usable);
  // LM iterations per cell (each one pass over the cell's observations, plus one at the start).
  state.counters["iterations_per_cell"] =
      static_cast<double>(iterations) / ((data.W / 2) * (data.H / 2));
  state.SetItemsProcessed(state.iterations() * (data.W / 2) * (data.H / 2));
}
BENCHMARK(BM_DofpCalibration_Full)->Arg(320)->Arg(640)->Unit(benchmark::kMillisecond)
    ->UseRealTime()->Iterations(2);

void BM_DofpCalibration_Step1(benchmark::State& state) {
  const DofpBenchData& data = bench_data(640);
  for (auto _ : state)
    benchmark::DoNotOptimize(calibrate_dofp_step1(data.W, data.H, data.levels).K.data());
}
BENCHMARK(BM_DofpCalibration_Step1)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(5);

}  // namespace
