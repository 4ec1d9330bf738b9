#pragma once
// Zero-velocity detection from the IMU alone (docs/physics.md §18.9): Skog, Händel, Nilsson and
// Rantakokko 2010 (IEEE Trans. Biomed. Eng. 57:2657), the stance hypothesis optimal detector (SHOE),
//   T = (1/W) Σ_k [ ‖(f_k − b̂_a) − g·ū‖²_{σ_f} + ‖ω_k − ω_rest‖²_{σ_ω} ],   ū = mean(f − b̂_a)/‖·‖,
// over the W samples of a window, f_k = Δv_k/Δt and ω_k = Δθ_k/Δt, each axis weighted by its white
// noise per sample, σ = N/√Δt (N the ARW or VRW density). Skog takes ω_rest = 0; here it is the
// Earth's rate in b with the gyro bias estimate, C_n^b·ω_ie^n + b̂_g, so an IMU whose noise is below
// the Earth's rate is still seen at rest. At rest T ≈ 6 − 2/W (χ²(6W − 2)/W: ū takes two degrees of
// freedom); the vehicle is declared at rest when W·T/(6W − 2) is below the 1 − 10⁻⁶ quantile of
// χ²(6W − 2)/(6W − 2) [C: one missed rest in 10⁶ windows]. Steady straight motion without vibration looks like
// rest to any IMU (f = g, ω = ω_ie): a simulated vehicle needs trajectory.vibration_mps2. The
// size of f is compared with normal gravity less b̂_a: an accelerometer whose vertical bias is not
// estimated (a held height) and far above its white noise per sample (e.g. 50 µg against 1 µg/√Hz
// at 100 Hz) is never seen at rest; Z21's (50 µg, 25 µg/√Hz) adds 0.007 to a mean of 1.
// navigate skips the test (no update) when a reading has a single IMU sample.
#include <span>

#include <Eigen/Core>

#include "polrig/ins/imu.h"

namespace polrig {

// What the IMU reads at rest, apart from its noise.
struct RestModel {
  double g_mps2 = 0;                                          // ‖f‖ at rest: normal gravity
  Eigen::Vector3d omega_b = Eigen::Vector3d::Zero();          // ω_rest: C_n^b ω_ie^n + b̂_g (rad/s)
  Eigen::Vector3d accel_bias = Eigen::Vector3d::Zero();       // b̂_a (m/s²)
};

struct ZeroVelocityTest {
  double statistic = 0;  // W·T/(6W − 2): 1 at rest on average
  double threshold = 0;  // the 1 − 10⁻⁶ quantile of χ²(6W − 2)/(6W − 2)
  bool at_rest = false;
};

struct ZeroVelocityDetector {
  Eigen::Vector3d arw = Eigen::Vector3d::Zero();  // gyro white noise density (rad/√s), > 0 per axis
  Eigen::Vector3d vrw = Eigen::Vector3d::Zero();  // accelerometer's (m/s/√s), > 0 per axis
  // Over a window of two or more raw samples (t_s the end of each interval; window[0]'s interval
  // starts at t0_s). Throws std::invalid_argument for a window of fewer than two samples, a
  // non-positive interval or a density that is not positive.
  ZeroVelocityTest test(std::span<const ImuSample> window, double t0_s, const RestModel& rest) const;
};

}  // namespace polrig
