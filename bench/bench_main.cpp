// Google Benchmark cases for polrig. Speed is reported as ratios against references measured in
// the same run (docs/validation.md): a bare loop of the same number of log10 calls that one CS
// study must make, so the ratio says how close the study is to its arithmetic floor; a QR of the
// fit's size; and, for the sphere tracer, rtcIntersect1 alone on stored rays of the kind the
// tracer casts. Compare rays/s of BM_Tracer_SphereSolve with BM_Reference_EmbreeIntersect1:
//   build/bench/polrig_bench --benchmark_filter='EmbreeIntersect1|Tracer'
// (items_per_second is per CPU second; both run on one thread).
#include <cmath>
#include <vector>

#include <Eigen/Dense>
#include <benchmark/benchmark.h>

#include "polrig/calib/fit.h"
#include "polrig/source/sphere_tracer.h"
#include <tbb/global_control.h>
#include "polrig/calib/pipeline.h"

#include "polrig/rig/rig.h"
#include "polrig/sim/simulate.h"
#include "polrig/study/cs.h"
#include "polrig/study/sweep.h"
#include "polrig/vector_log.h"

namespace {
using namespace polrig;

// Reference: 3 pairs × 360 angles of log10, the transcendental floor of one CS study, scalar
// (glibc), as the study computed them before it took its logarithms in vectors.
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

// The roofline of BM_CsSummary: the 1080 natural logarithms one CS study takes, as it takes them
// (polrig::log_array: Highway, dispatched, without FMA), of study-like ratios, alone. Both count
// one item per study, so BM_CsSummary's items/s over this one is the fraction of the study's time
// that its logarithms would take if nothing else cost anything. The rest of a study is cos⁴'s
// distance ratios D_h/D_j (1080 divisions, Source::log_ratio_over_turn), Eq. 5's scaling, the CS
// average and the six means and SDs: measured in one run on this shared machine
// (docs/validation.md), the study takes about 2.3 × the bare logarithms (4.2 µs against 1.8 µs).
//   build/bench/polrig_bench --benchmark_filter='VectorLog_1080|CsSummary|Sweep_20k'
void BM_Reference_VectorLog_1080(benchmark::State& state) {
  std::vector<double> x(1080), y(x.size());
  for (std::size_t k = 0; k < x.size(); ++k) x[k] = 0.95 + 1e-4 * static_cast<double>(k);
  for (auto _ : state) {
    log_array(x.data(), y.data(), x.size());
    benchmark::DoNotOptimize(y.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Reference_VectorLog_1080);

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

// ---- Calibration --------------------------------------------------------------------------

// Reference: one column-pivoting QR of a 57 × 18 matrix, the linear algebra of one LM step.
void BM_Reference_QR_57x18(benchmark::State& state) {
  const Eigen::MatrixXd J = Eigen::MatrixXd::Random(57, 18);
  for (auto _ : state) {
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(J);
    benchmark::DoNotOptimize(qr.matrixQR().data());
  }
}
BENCHMARK(BM_Reference_QR_57x18);

// One Eq. 15 fit: the paper's 19 CS points (57 observations), 18 unknowns, from the nominal
// values, with the noise of the default rig.
void BM_Fit_Eq15_57x18(benchmark::State& state) {
  const FitParams truth = FitParams::coupled(CalibrationParams::wang2019_indoor(), 0.55);
  std::vector<Observation> obs;
  for (int k = 0; k <= 18; ++k)
    for (int i = 0; i < 3; ++i)
      obs.push_back({10.0 * k, i,
                     eq15_voltage(truth, 0.5, i, 10.0 * k) + 1e-5 * standard_normal(1, k, i, 0)});
  const FitParams start = FitParams::coupled(CalibrationParams::theory(kWang2019FilmAxesDeg), 0.55);
  for (auto _ : state) benchmark::DoNotOptimize(fit_eq15(obs, start, 0.5));
}
BENCHMARK(BM_Fit_Eq15_57x18)->Unit(benchmark::kMicrosecond);

// A whole type-3 calibration of the simulated indoor run (CS, preliminary fit, selection, fit,
// decoupling, error curves).
void BM_Calibrate_CsNc_DefaultRig(benchmark::State& state) {
  const Rig rig;
  const Simulation sim = simulate(rig);
  std::vector<StopVoltages> stops;
  for (const Stop& s : sim.stops) stops.push_back({s.theta_R_deg, s.V_mean, "s"});
  CalibrationOptions o;
  o.d_a = 0.55;
  for (auto _ : state) benchmark::DoNotOptimize(calibrate(stops, o));
}
BENCHMARK(BM_Calibrate_CsNc_DefaultRig)->Unit(benchmark::kMicrosecond);

// ---- The traced sphere -------------------------------------------------------------------

// Reference: rtcIntersect1 alone on the JF-500-like default scene, one thread, on a stored
// buffer of the rays a photon tracer casts (from wall points in cosine-weighted directions),
// generated before the timed loop: the time is Embree's traversal and the scene's exact
// double-precision user-geometry intersections, and nothing else.
void BM_Reference_EmbreeIntersect1(benchmark::State& state) {
  const SphereTracer tracer(SceneSpec{});
  const std::vector<SphereTracer::Ray> rays = tracer.wall_rays(10000, 1);
  long long n = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(tracer.plain_intersections(rays));
    n += static_cast<long long>(rays.size());
  }
  state.SetItemsProcessed(n);  // rays
}
BENCHMARK(BM_Reference_EmbreeIntersect1)->Unit(benchmark::kMillisecond);

// The sphere solve on one thread: items are rays (rtcIntersect1 calls), including emission,
// bounces, tallies and the random numbers.
void BM_Tracer_SphereSolve(benchmark::State& state) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  SceneSpec scene;
  scene.trace.photons = 20000;
  scene.trace.batches = 4;
  const SphereTracer tracer(scene);
  long long rays = 0;
  for (auto _ : state) rays += tracer.trace_photons().ledger.rays;
  state.SetItemsProcessed(rays);
}
BENCHMARK(BM_Tracer_SphereSolve)->Unit(benchmark::kMillisecond);

}  // namespace
