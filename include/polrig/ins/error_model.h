#pragma once
// The 15-state ENU error model of the INS (docs/physics.md §18.5; spec sky-and-compasses.md §4.4,
// §4.7; PSINS etm.m):
//   x = [φ_E φ_N φ_U, δV_E δV_N δV_U, δL δλ δh, ε_x ε_y ε_z, ∇_x ∇_y ∇_z]
// φ the attitude error, C̃_b^n = (I − [φ×])·C_b^n; δV = Ṽ − V; δL, δλ (rad), δh (m) computed
// minus true; ε and ∇ the residual gyro and accelerometer biases on the body axes (ω̃ = ω + ε).
//   φ̇  = −ω_in × φ + δω_in − C_b^n ε
//   δV̇ = f^n × φ + C_b^n ∇ + V × (2δω_ie + δω_en) − (2ω_ie + ω_en) × δV + δg
//   δṗ = M_pv δV + M_pp δp
// δg = (0, 0, −∂g/∂L·δL − ∂g/∂h·δh): the gravity gradient (+3.086e-6·δh in the vertical channel).
// ε̇ = −ε/τ_g, ∇̇ = −∇/τ_a (τ = ∞, the default, makes them constants as Z21's).
#include <limits>

#include <Eigen/Core>

#include "polrig/ins/imu.h"
#include "polrig/ins/mechanization.h"

namespace polrig {

using Vector15 = Eigen::Matrix<double, 15, 1>;
using Matrix15 = Eigen::Matrix<double, 15, 15>;
using RowVector15 = Eigen::Matrix<double, 1, 15>;

// Indices into x.
inline constexpr int kPhi = 0, kDV = 3, kDLat = 6, kDLon = 7, kDh = 8, kGyroBias = 9, kAccelBias = 12;

struct ErrorModelNoise {
  Eigen::Vector3d arw = Eigen::Vector3d::Zero();  // gyro white noise density (rad/√s), per body axis
  Eigen::Vector3d vrw = Eigen::Vector3d::Zero();  // accelerometer white noise density (m/s/√s)
  // Gauss–Markov biases: correlation time (s; infinity: constants) and σ (drives Q).
  Eigen::Vector3d gyro_tau_s = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d accel_tau_s = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d gyro_bias_sigma = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_bias_sigma = Eigen::Vector3d::Zero();
};

// The model's noise from an IMU's error spec: the white-noise densities and the Gauss–Markov
// biases (σ, τ); the constant, turn-on and random-walk parts are left to P0.
ErrorModelNoise error_model_noise(const ImuErrorSpec& imu);

// F at the state s with specific force f^n.
Matrix15 error_dynamics(const InsState& s, const Eigen::Vector3d& f_n,
                        const ErrorModelNoise& noise = {});

// The continuous process noise G·Q_c·Gᵀ: the white noise enters φ through −C_b^n and δV through
// C_b^n (isotropic per axis only when the densities are), the Gauss–Markov biases with 2σ²/τ.
Matrix15 process_noise_density(const InsState& s, const ErrorModelNoise& noise);

struct Discretized {
  Matrix15 Phi;
  Matrix15 Q;
};
// Φ = I + F·Δt and Q = ½(Φ·Q_c + Q_c·Φᵀ)·Δt: PSINS's form at the IMU rate, ‖F‖Δt ≲ 1e-4.
Discretized discretize_first_order(const Matrix15& F, const Matrix15& Qc, double dt_s);
// Van Loan: exp([[−F, Q_c], [0, Fᵀ]]·Δt) = [[·, Φ⁻¹Q], [0, Φᵀ]]; exact for constant F over Δt.
// Computed by the Taylor series of Φ and of Q's integral with scaling and squaring (error_model.cpp).
Discretized discretize_van_loan(const Matrix15& F, const Matrix15& Qc, double dt_s);

// Applies x to the state (closed loop): C_b^n ← q(φ)·C̃_b^n, v ← ṽ − δV, L, λ, h ← minus δp, and
// adds ε, ∇ to the bias estimates. The caller then resets x to 0.
void feed_back(const Vector15& x, InsState& s, Eigen::Vector3d& gyro_bias,
               Eigen::Vector3d& accel_bias);

}  // namespace polrig
