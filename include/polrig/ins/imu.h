#pragma once
// The IMU: increments of angle and velocity in the body frame, and their error model
// (docs/physics.md §18.2; spec sky-and-compasses.md §4.1 Table 1, §4.7 "IMU noise").
//
// A sample holds the integrals over its interval (t_s − dt, t_s] of the body rate ω_ib^b
// (dtheta, rad) and of the specific force f^b (dv, m/s), as a strapdown IMU outputs them.
// The measured rate of one triad is
//   ω̃ = (I + diag(s) + M)·ω + b + b_GM(t) + b_RW(t) + w,
// s the scale-factor errors, M the misalignment (zero diagonal), b the constant bias, b_GM a
// first-order Gauss–Markov bias (σ, τ) stepped EXACTLY, b⁺ = e^{−Δt/τ}·b + σ·√(1 − e^{−2Δt/τ})·w,
// started from its stationary law, b_RW a random walk (rate random walk K: b⁺ = b + K·√Δt·w)
// started at 0, and w white noise of density N (ARW, VRW): σ of an increment = N·√Δt.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace polrig {

// g₀ = 9.80665 m/s² (CGPM 1901): what an accelerometer's µg and µg/√Hz are counted in.
inline constexpr double kStandardGravity = 9.80665;

struct ImuSample {
  double t_s = 0;  // the end of the interval
  Eigen::Vector3d dtheta = Eigen::Vector3d::Zero();  // ∫ω_ib^b dt (rad)
  Eigen::Vector3d dv = Eigen::Vector3d::Zero();      // ∫f^b dt (m/s)
};

// One triad's errors, per axis (x, y, z of b). Units: the gyro's in rad/s, rad/√s, rad/s/√s;
// the accelerometer's in m/s², m/s/√s, m/s²/√s. Zero means absent.
struct SensorErrorSpec {
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();              // constant, as given
  Eigen::Vector3d turn_on_bias_sigma = Eigen::Vector3d::Zero();  // constant, drawn per seed
  Eigen::Vector3d bias_instability = Eigen::Vector3d::Zero();  // σ of the Gauss–Markov bias
  Eigen::Vector3d correlation_time_s = Eigen::Vector3d::Constant(3600);  // its τ
  Eigen::Vector3d white_noise = Eigen::Vector3d::Zero();       // ARW / VRW density N
  Eigen::Vector3d random_walk = Eigen::Vector3d::Zero();       // rate random walk K
  Eigen::Vector3d scale_factor_sigma = Eigen::Vector3d::Zero();  // drawn per seed (1 = 100 %)
  double misalignment_sigma_rad = 0;  // each off-diagonal element of M, drawn per seed
};

struct ImuErrorSpec {
  SensorErrorSpec gyro;
  SensorErrorSpec accel;
  double rate_hz = 100;  // [C]: Z21's Table 1 reads 50 Hz, garbled (spec §4.1)
};

// Z21's Table 1 as spec §4.1 reads it [C]: gyro bias 5°/h (a turn-on bias, σ per axis) and
// ARW 0.5°/√h; accelerometer bias 50 µg and VRW 25 µg/√Hz (g = 9.80665 m/s²).
ImuErrorSpec z21_imu_errors();

// The constant part of the errors one seed draws: the truth a filter estimates against.
struct ImuErrorsDrawn {
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();   // bias + the drawn turn-on bias
  Eigen::Vector3d accel_bias = Eigen::Vector3d::Zero();
  Eigen::Matrix3d gyro_scale_misalignment = Eigen::Matrix3d::Zero();   // diag(s) + M
  Eigen::Matrix3d accel_scale_misalignment = Eigen::Matrix3d::Zero();
};

struct CorruptedImu {
  std::vector<ImuSample> samples;
  ImuErrorsDrawn drawn;
  // The total bias (constant + Gauss–Markov + random walk) of each sample's interval.
  std::vector<Eigen::Vector3d> gyro_bias, accel_bias;
};

// The ideal samples with spec's errors, the same bits for a given seed whatever the thread count:
// every deviate is standard_normal(seed, sample index, channel, 0) of random.h, the channel naming
// the sensor, the process and the axis. Each sample's dt is t_s minus the previous t_s (the first:
// 1/rate_hz). Throws std::invalid_argument for a non-positive dt or correlation time.
CorruptedImu corrupt_imu(const std::vector<ImuSample>& ideal, const ImuErrorSpec& spec,
                         std::uint64_t seed);

// One exact step of a first-order Gauss–Markov process of stationary σ and correlation time τ,
// w a standard normal deviate.
double gauss_markov_step(double b, double dt_s, double sigma, double tau_s, double w);

}  // namespace polrig
