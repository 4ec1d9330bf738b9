#pragma once
// The strapdown mechanization in ENU: one update per IMU sample, two-sample coning and sculling
// with the previous sample (the KF-GINS form), Earth and transport rates and normal gravity at
// the interval's midpoint (docs/physics.md §18.4). n = ENU, b = RFU (ins/attitude.h).
//
//   velocity: Δv_f^b = R(½dθ)·dv + (dθ₋ × dv + dv₋ × dθ)/12   (R(½dθ)·dv = dv + ½ dθ × dv + O(dθ²))
//             v⁺ = v + R(−½ζ)·C_b^n·Δv_f^b + (g^n − (2ω_ie^n + ω_en^n) × v)·Δt,  ζ = ω_in^n Δt
//   R(a) the rotation by rotation vector a: the half-angle forms of the rotation compensation
//   (I ± ½[·×] to first order, as KF-GINS), exact for a static IMU.
//   position: h, then L (R_M at the mean height), then λ (R_N at the mean L and h), trapezoidal
//   attitude: φ = dθ + dθ₋ × dθ/12;  q_b^n⁺ = q(−ζ) ⊗ q_b^n ⊗ q(φ)
// The first step of a run has no previous sample: pass the current one twice (no correction).
#include <optional>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "polrig/ins/attitude.h"
#include "polrig/ins/imu.h"

namespace polrig {

struct InsState {
  Eigen::Quaterniond q_bn = Eigen::Quaterniond::Identity();  // C_b^n
  Eigen::Vector3d v_n = Eigen::Vector3d::Zero();
  double lat_rad = 0, lon_rad = 0, h_m = 0;
  double t_s = 0;

  Eigen::Matrix3d C_bn() const { return q_bn.toRotationMatrix(); }
  Euler euler() const { return euler_from_C_bn(C_bn()); }
};

// The local-level (ENU, latitude–longitude) mechanization's domain [C]: its longitude rate
// v_E/((R_N + h)·cos φ) and the frame's rotation about the vertical (ω_ie·sin φ + v_E·tan φ/R)
// grow without bound at the poles, where polrig, like KF-GINS and PSINS's default, has no wander-
// azimuth or polar frame. Within 89° a 30 m/s vehicle turns the frame by < 0.02°/s; past it a run
// is refused at load (sky.lat_deg), in simulate (its trajectory) and reported `diverged` by navigate.
inline constexpr double kInsMaxLatitudeDeg = 89;

struct MechanizationOptions {
  // Z21 holds the height to its barometer: after each step h = this and v_U = 0.
  std::optional<double> hold_height_m;
};

// A state inside the mechanization's domain: finite, its latitude within ±kInsMaxLatitudeDeg.
bool in_ins_domain(const InsState& s);

// One step over cur's interval (dt = cur.t_s − state.t_s, > 0); prev is the sample before cur.
// Returns the state at cur.t_s. Throws std::invalid_argument for dt ≤ 0.
InsState mechanize(const InsState& state, const ImuSample& prev, const ImuSample& cur,
                   const MechanizationOptions& options = {});

// The specific force in n over the last step, f^n ≈ C_b^n·dv/Δt (for the error model's F).
Eigen::Vector3d specific_force_n(const InsState& state, const ImuSample& cur, double dt_s);

// The sample with estimated biases removed: dθ − b_g·Δt, dv − b_a·Δt.
ImuSample compensate(const ImuSample& s, const Eigen::Vector3d& gyro_bias,
                     const Eigen::Vector3d& accel_bias, double dt_s);

}  // namespace polrig
