#pragma once
// A vehicle's true trajectory from a list of segments, and the ideal IMU that flies it
// (docs/physics.md §18.3).
//
// The truth's kinematics: speed u along the body's forward axis projected by yaw and pitch,
//   v^n = u·(sin ψ cos θ, cos ψ cos θ, sin θ),
//   L̇ = v_N/(R_M + h),  λ̇ = v_E/((R_N + h) cos L),  ḣ = v_U,
// with u, ψ (yaw) and θ (pitch) piecewise linear in time (the segments' rates); roll stays.
// The ideal IMU outputs the integrals over each interval of
//   ω_ib^b = ω_nb^b + C_n^b·(ω_ie^n + ω_en^n),
//   f^b    = C_n^b·(v̇^n + (2ω_ie^n + ω_en^n) × v^n − g^n),
// ω_nb^b from the Euler rates in closed form, evaluated along the truth (position by RK4 on
// substeps) and integrated by Simpson's rule over the same substeps: never by differencing
// sampled attitudes. Static (u = 0, no rates) reduces to ω_ib^b = C_n^b ω_ie^n, f^b = −C_n^b g^n.
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "polrig/ins/attitude.h"
#include "polrig/ins/imu.h"

namespace polrig {

enum class SegmentKind { Static, Accelerate, Turn, Climb };
std::string_view segment_kind_name(SegmentKind k);  // "static", "accelerate", "turn", "climb"

struct Segment {
  SegmentKind kind = SegmentKind::Static;
  double duration_s = 0;
  double rate = 0;  // accelerate: du/dt (m/s²); turn: dψ/dt (rad/s, clockwise); climb: dθ/dt (rad/s)
};

struct TrajectorySpec {
  double lat_rad = 0, lon_rad = 0, h_m = 0;
  Euler attitude;          // roll stays as given
  double speed_mps = 0;    // along the forward axis; Static segments need 0
  std::vector<Segment> segments;
  double imu_rate_hz = 100;
  int substeps = 8;        // per IMU interval, even (Simpson)
  // A vehicle's vibration [C]: a body-fixed oscillating acceleration, rms vibration_mps2 per axis at
  // speeds of 1 m/s and more, in proportion to the speed below (none at rest), one tone per axis
  // (kVibrationHz), in the IMU's Δv only: the truth omits its velocity (≤ √2·a/ω, 5 mm/s at
  // 0.3 m/s²) and displacement (< 0.1 mm). Steady motion without it looks like rest to an IMU.
  double vibration_mps2 = 0;

  double duration_s() const {  // the segments' sum
    double t = 0;
    for (const Segment& g : segments) t += g.duration_s;
    return t;
  }
};

inline constexpr double kVibrationHz[3] = {11.3, 13.7, 17.9};  // x, y, z of b [C: a car body's]

struct TruthSample {
  double t_s = 0;
  double lat_rad = 0, lon_rad = 0, h_m = 0;
  Eigen::Matrix3d C_bn = Eigen::Matrix3d::Identity();
  Euler euler;
  Eigen::Vector3d v_n = Eigen::Vector3d::Zero();
};

// truth[0] is the start (t = 0) and truth[k] the end of imu[k − 1]'s interval: imu has one
// sample fewer than truth.
struct Trajectory {
  std::vector<TruthSample> truth;
  std::vector<ImuSample> imu;
};

// Throws std::invalid_argument: a segment whose duration is not a whole number of IMU intervals
// (its boundaries must fall on samples), a static segment while moving, a negative speed, odd
// or non-positive substeps, a non-positive rate.
Trajectory generate_trajectory(const TrajectorySpec& spec);

// pyins's sine-velocity motion (pyins.sim.generate_sine_velocity_motion, whose tests polrig's
// reproduce): each ENU component of the velocity a sine about its mean,
//   v_i(t) = v̄_i + A_i·sin(2π t/T + φ_i),
// roll 0, yaw and pitch along v^n (no side-slip), the IMU as generate_trajectory's.
struct SineVelocitySpec {
  double lat_rad = 0, lon_rad = 0, h_m = 0;
  Eigen::Vector3d v_mean_enu = Eigen::Vector3d::Zero();     // v̄ (m/s)
  Eigen::Vector3d amplitude_enu = Eigen::Vector3d::Zero();  // A (m/s)
  Eigen::Vector3d phase_rad = Eigen::Vector3d::Zero();      // φ
  double period_s = 60;                                     // T
  double duration_s = 0;
  double imu_rate_hz = 100;
  int substeps = 8;  // per IMU interval, even (Simpson)
};
// Throws std::invalid_argument: a duration that is not a whole number of IMU intervals, odd or
// non-positive substeps, a non-positive period, or a mean horizontal speed not above the
// horizontal amplitude (the heading would be undefined).
Trajectory generate_sine_velocity_trajectory(const SineVelocitySpec& spec);

}  // namespace polrig
