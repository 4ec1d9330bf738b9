#include "polrig/ins/imu.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "polrig/random.h"
#include "polrig/units.h"

namespace polrig {
namespace {


// Channels of standard_normal: sensor (gyro 0, accel 1) · 16 + process · 4 + axis.
enum Process : std::uint64_t { kWhite = 0, kGaussMarkov = 1, kRandomWalk = 2, kDrawn = 3 };
constexpr std::uint64_t kDrawnSample = std::numeric_limits<std::uint64_t>::max();

std::uint64_t channel(int sensor, Process p, int axis) {
  return static_cast<std::uint64_t>(sensor) * 16 + p * 4 + static_cast<std::uint64_t>(axis);
}

struct TriadState {
  Eigen::Vector3d constant_bias, gm, rw;
  Eigen::Matrix3d SM;  // diag(s) + M
};

TriadState draw(const SensorErrorSpec& s, std::uint64_t seed, int sensor) {
  TriadState t;
  t.SM.setZero();
  for (int i = 0; i < 3; ++i) {
    const auto n = [&](int k) { return standard_normal(seed, kDrawnSample, channel(sensor, kDrawn, i), k); };
    t.constant_bias[i] = s.bias[i] + s.turn_on_bias_sigma[i] * n(0);
    t.SM(i, i) = s.scale_factor_sigma[i] * n(1);
    for (int j = 0; j < 3; ++j)
      if (j != i) t.SM(i, j) = s.misalignment_sigma_rad * n(2 + j);
    // The Gauss–Markov bias starts from its stationary law; the random walk from 0.
    t.gm[i] = s.bias_instability[i] * standard_normal(seed, kDrawnSample, channel(sensor, kGaussMarkov, i), 0);
    t.rw[i] = 0;
    if (!(s.correlation_time_s[i] > 0))
      throw std::invalid_argument(fmt::format("IMU error spec: correlation time {} s must be > 0",
                                              s.correlation_time_s[i]));
  }
  return t;
}

// Advances the time-varying biases over dt and returns the increment error of the interval.
Eigen::Vector3d step(TriadState& t, const SensorErrorSpec& s, const Eigen::Vector3d& ideal,
                     double dt, std::uint64_t seed, std::uint64_t k, int sensor, Eigen::Vector3d& bias) {
  Eigen::Vector3d error;
  // A process whose σ is 0 draws no deviate (0·w adds nothing): Z21's IMU has white noise only,
  // and the deviates are most of a run's simulation.
  for (int i = 0; i < 3; ++i) {
    const auto n = [&](Process p) { return standard_normal(seed, k, channel(sensor, p, i), 0); };
    bias[i] = t.constant_bias[i] + t.gm[i] + t.rw[i];
    error[i] = bias[i] * dt;
    if (s.white_noise[i] != 0) error[i] += s.white_noise[i] * std::sqrt(dt) * n(kWhite);
    if (s.bias_instability[i] != 0)
      t.gm[i] = gauss_markov_step(t.gm[i], dt, s.bias_instability[i], s.correlation_time_s[i], n(kGaussMarkov));
    if (s.random_walk[i] != 0) t.rw[i] += s.random_walk[i] * std::sqrt(dt) * n(kRandomWalk);
  }
  return t.SM * ideal + error;
}

}  // namespace

ImuErrorSpec z21_imu_errors() {
  ImuErrorSpec spec;
  spec.gyro.turn_on_bias_sigma.setConstant(deg2rad(5.0) / 3600.0);
  spec.gyro.white_noise.setConstant(deg2rad(0.5) / 60.0);
  spec.accel.turn_on_bias_sigma.setConstant(50e-6 * kStandardGravity);
  spec.accel.white_noise.setConstant(25e-6 * kStandardGravity);
  return spec;
}

double gauss_markov_step(double b, double dt_s, double sigma, double tau_s, double w) {
  const double a = std::exp(-dt_s / tau_s);
  return a * b + sigma * std::sqrt(-std::expm1(-2 * dt_s / tau_s)) * w;
}

CorruptedImu corrupt_imu(const std::vector<ImuSample>& ideal, const ImuErrorSpec& spec,
                         std::uint64_t seed) {
  if (!(spec.rate_hz > 0))
    throw std::invalid_argument(fmt::format("IMU error spec: rate {} Hz must be > 0", spec.rate_hz));
  CorruptedImu out;
  TriadState gyro = draw(spec.gyro, seed, 0), accel = draw(spec.accel, seed, 1);
  out.drawn = {gyro.constant_bias, accel.constant_bias, gyro.SM, accel.SM};
  out.samples.reserve(ideal.size());
  out.gyro_bias.resize(ideal.size());
  out.accel_bias.resize(ideal.size());
  double t_prev = ideal.empty() ? 0.0 : ideal.front().t_s - 1.0 / spec.rate_hz;
  for (std::size_t k = 0; k < ideal.size(); ++k) {
    const ImuSample& s = ideal[k];
    const double dt = s.t_s - t_prev;
    if (!(dt > 0))
      throw std::invalid_argument(fmt::format("IMU sample {}: interval {} s must be > 0", k, dt));
    ImuSample c = s;
    c.dtheta += step(gyro, spec.gyro, s.dtheta, dt, seed, k, 0, out.gyro_bias[k]);
    c.dv += step(accel, spec.accel, s.dv, dt, seed, k, 1, out.accel_bias[k]);
    out.samples.push_back(c);
    t_prev = s.t_s;
  }
  return out;
}

}  // namespace polrig
