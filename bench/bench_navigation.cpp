// Z21's system (study/navigation.h): a 20-minute run of rigs/zhang2021-static.yaml at 100 Hz with
// 1 Hz compass readings, each mode alone and all three (the target for all three: < 0.2 s),
// the dataset's simulation, and as a reference measured in the same run the strapdown mechanization
// alone over the same 120000 samples (ins/mechanization.h: no filter, no sun); the filter's
// covariance step against Padé on van Loan's 30 × 30 block matrix.
//   build/bench/polrig_bench --benchmark_filter=Navigation
#include <string>

#include <benchmark/benchmark.h>
#include <unsupported/Eigen/MatrixFunctions>

#include "polrig/io/rig_yaml.h"
#include "polrig/ins/earth.h"
#include "polrig/ins/error_model.h"
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

// What a Monte-Carlo trial simulates: the run from its scene (study/navigation.h; the trajectory
// and the sun made once per study cell), i.e. the IMU's errors and the 1200 × 9 unit readings.
void BM_Navigation_SimulateFromScene20min(benchmark::State& state) {
  const NavigationScene scene = navigation_scene(z21_rig());
  for (auto _ : state) benchmark::DoNotOptimize(simulate_navigation(z21_rig(), scene));
}
BENCHMARK(BM_Navigation_SimulateFromScene20min)->Unit(benchmark::kMillisecond);

// The filter's covariance step over one 1 s reading interval (ins/error_model.h's Taylor series on
// the balanced F), at Z21's static state and noise; the reference in the same run: Van Loan's
// 30 × 30 block exponential by Eigen's Padé (MatrixFunctions), as the filter computed it before.
struct CovarianceStepCase {
  Matrix15 F, Qc;
  CovarianceStepCase() {
    const Rig& rig = z21_rig();
    const InsState s = initial_state(rig, StartErrors::Stated);
    F = error_dynamics(s, Eigen::Vector3d(0, 0, normal_gravity(s.lat_rad, s.h_m)), filter_settings(rig).noise);
    Qc = process_noise_density(s, filter_settings(rig).noise);
  }
};

void BM_Navigation_CovarianceStep(benchmark::State& state) {
  const CovarianceStepCase c;
  for (auto _ : state) benchmark::DoNotOptimize(discretize_van_loan(c.F, c.Qc, 1.0));
}
BENCHMARK(BM_Navigation_CovarianceStep)->Unit(benchmark::kMicrosecond);

void BM_Navigation_RefCovarianceStepPade30(benchmark::State& state) {
  const CovarianceStepCase c;
  for (auto _ : state) {
    Eigen::Matrix<double, 30, 30> A = Eigen::Matrix<double, 30, 30>::Zero();
    A.block<15, 15>(0, 0) = -c.F;
    A.block<15, 15>(0, 15) = c.Qc;
    A.block<15, 15>(15, 15) = c.F.transpose();
    const Eigen::Matrix<double, 30, 30> E = A.exp();
    const Matrix15 Phi = E.block<15, 15>(15, 15).transpose();
    benchmark::DoNotOptimize(Matrix15(Phi * E.block<15, 15>(0, 15)));
  }
}
BENCHMARK(BM_Navigation_RefCovarianceStepPade30)->Unit(benchmark::kMicrosecond);

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
