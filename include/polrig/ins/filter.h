#pragma once
// Z21's filter (docs/physics.md §18.6; spec sky-and-compasses.md §4.3, §4.4, §4.7): the 15-state
// error Kalman filter of ins/error_model.h, its state mechanized at the IMU rate and P predicted
// there with Φ = I + F·Δt or once per update by van Loan (FilterSettings::covariance_step), updated
// by the sun's elevation,
//   z = sin H_c − sin H^n,   sin H_c = sin L̃ sin Dec + cos L̃ cos Dec cos LHA,   LHA = GHA + λ̃,
//   H = [0₁ₓ₆, ∂sinH/∂L, ∂sinH/∂λ, 0₁ₓ₇]  (spec §4.3's corrected Eq. 15),
//   R = (cos H^n·σ_H)² (the azimuth's: σ_A²),
// with the Joseph-form covariance update, optionally Sage–Husa's adaptive R, and closed-loop
// feedback into the INS state and the bias estimates after every update. Besides the sun: zero-
// velocity updates (update_zero_velocity, docs/physics.md §18.9) and position fixes with their
// covariance (update_position: a PNS's, loosely coupled). Dec and GHA (the sun's
// declination and Greenwich hour angle, radians) are plain numbers here: sky/ supplies them.
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>

#include <Eigen/Core>

#include "polrig/ins/error_model.h"
#include "polrig/ins/imu.h"
#include "polrig/ins/mechanization.h"
#include "polrig/units.h"

namespace polrig {

// sin H of the sun at (L, λ) and its partial derivatives (spec §4.3 Eq. 16, corrected).
struct SunElevationModel {
  double sin_H = 0;
  double d_lat = 0;  // ∂sinH/∂L = sin Dec cos L − cos Dec sin L cos LHA
  double d_lon = 0;  // ∂sinH/∂λ = −cos Dec cos L sin LHA
};
SunElevationModel sun_elevation_model(double lat_rad, double lon_rad, double dec_rad, double gha_rad);

// The sun's azimuth A (clockwise from north, radians) at (L, λ) and its partial derivatives, from the
// sun's direction in ENU (s_E = −cos Dec sin LHA, s_N = sin Dec cos L − cos Dec sin L cos LHA,
// s_U = sin H, ρ² = s_E² + s_N²; docs/physics.md §18.6):
//   ∂A/∂L = s_E·sin H/ρ²,   ∂A/∂λ = −cos Dec·(s_N cos LHA + s_E sin L sin LHA)/ρ².
struct SunAzimuthModel {
  double azimuth = 0;
  double d_lat = 0, d_lon = 0;
  double s_east = 0, s_north = 0, s_up = 0;
};
SunAzimuthModel sun_azimuth_model(double lat_rad, double lon_rad, double dec_rad, double gha_rad);

// The Sage–Husa estimate of a scalar R (spec §4.7; PSINS kfupdate.m):
//   R_k = min((1 − β_k)·R_{k−1} + β_k·s_k, R_max),   s_k = max(r² − H P⁻ Hᵀ, R_min),
//   β_1 = 1,   β_{k+1} = β_k/(β_k + b).
// PSINS instead sets R_k = R_max whenever one sample s_k exceeds R_max: a single 2.5σ innovation
// then throws R to its ceiling when the true R is within ~6× of it (test_ins), so polrig clamps
// the average, as the spec's formula reads.
class SageHusaR {
 public:
  SageHusaR(double R0, double b = 0.98, double min_factor = 0.01, double max_factor = 100);
  double update(double innovation, double HPHt);  // returns the new R
  double R() const { return R_; }
  double beta() const { return beta_; }

 private:
  double R_, b_, R_min_, R_max_, beta_ = 1.0;
};

inline constexpr double kNaNUpdate = std::numeric_limits<double>::quiet_NaN();
struct ScalarUpdate {
  double innovation = 0;   // z − H x⁻
  double variance = 0;     // S = H P⁻ Hᵀ + R
  double nis = 0;          // innovation² / S
  double R = 0;
};

// The linear Kalman filter on the 15 error states.
struct ErrorFilter {
  Vector15 x = Vector15::Zero();
  Matrix15 P = Matrix15::Zero();

  void predict(const Matrix15& Phi, const Matrix15& Q);
  // One scalar measurement z = H x + v, v ~ N(0, R); P by Joseph's form (I − KH)P(I − KH)ᵀ + KRKᵀ.
  ScalarUpdate update(const RowVector15& H, double z, double R);
};

struct FilterSettings {
  double sigma_H_rad = deg2rad(0.1);  // the compass' elevation σ [C]
  double sigma_A_rad = deg2rad(0.0405);  // its azimuth σ (SunMeasurement Azimuth, SunVector) [C]
  bool adaptive = true;            // Sage–Husa R [C]
  double sage_husa_b = 0.98;       // Z21's forgetting factor as b (spec §4.7)
  double R_min_factor = 0.01, R_max_factor = 100;  // PSINS's clamp on R, times R0
  MechanizationOptions mechanization;  // Z21 holds the height to its barometer
  // What the compass's sun updates (docs/physics.md §18.6). The sun is measured through the INS's
  // attitude, C̃_b^n = (I − [φ×])·C_b^n, so s̃^n = s^n + s^n × φ:
  //   ElevationZ21  z = sin H_c − sin H̃^n, H = [∂sinH/∂L, ∂sinH/∂λ] only (Z21 Eq. 15): the tilt the
  //                 measurement carries is not modelled;
  //   Elevation     the same z with the tilt columns [s_N, −s_E] on φ_E, φ_N (sin H̃^n = sin H^n −
  //                 φ_E·s_N + φ_N·s_E) [C]: the filter estimates the tilt the measurement carries;
  //   Azimuth       z = A_c − Ã^n (wrapped), Ã^n = A^n + φ_U − s_U·(s_E φ_E + s_N φ_N)/ρ²: the
  //                 heading (what these compasses are for), the tilt, and the position through A_c;
  //   SunVector     both, as two scalar updates (the two components' errors independent).
  //   PnsFix        no sun update: the PNS's position fixes instead (update_position), loosely
  //                 coupled (the caller makes them, from windows that do not overlap).
  enum class SunMeasurement { ElevationZ21, Elevation, Azimuth, SunVector, PnsFix };
  SunMeasurement measurement = SunMeasurement::Elevation;
  // When P is propagated: at every IMU sample with Φ = I + F·Δt (PSINS's form, Z21's), or once per
  // update interval T with van Loan's exact Φ = e^{F̄T} and Q, F̄ at the interval's end state and its
  // mean specific force (F changes little over T at rest or in steady motion; 100× less work at
  // 100 Hz with 1 Hz updates). The state is mechanized at every sample either way.
  enum class CovarianceStep { EverySample, AtUpdates };
  CovarianceStep covariance_step = CovarianceStep::EverySample;
  ErrorModelNoise noise = error_model_noise(z21_imu_errors());  // Z21's Table 1 [C]
};

// "elevation-z21", "elevation", "azimuth", "sun-vector", "pns-fix"
std::string_view sun_measurement_name(FilterSettings::SunMeasurement m);

// One compass reading as the filter takes it: the measured sun in n, s̃^n = C̃_b^n·s^b.
struct SunObservation {
  double t_s = 0;
  double elevation_rad = 0;  // H̃^n = asin s̃_U
  double dec_rad = 0, gha_rad = 0;  // the sun's, at t_s
  // s̃^n's east and north components: the tilt columns and the azimuth Ã^n = atan2(s̃_E, s̃_N).
  double sun_east = std::numeric_limits<double>::quiet_NaN(), sun_north = std::numeric_limits<double>::quiet_NaN();
};

// The scalar updates of one reading (NaN where the measurement has no such component).
struct SunUpdate {
  ScalarUpdate elevation{kNaNUpdate, kNaNUpdate, kNaNUpdate, kNaNUpdate};
  ScalarUpdate azimuth{kNaNUpdate, kNaNUpdate, kNaNUpdate, kNaNUpdate};
};

// A zero-velocity update's scalar updates, z = v̂_i − 0 on δv_E, δv_N, δv_U (up NaN when the height
// is held: δv_U is pinned).
struct ZeroVelocityUpdate {
  ScalarUpdate east{kNaNUpdate, kNaNUpdate, kNaNUpdate, kNaNUpdate};
  ScalarUpdate north{kNaNUpdate, kNaNUpdate, kNaNUpdate, kNaNUpdate};
  ScalarUpdate up{kNaNUpdate, kNaNUpdate, kNaNUpdate, kNaNUpdate};
};

// A position fix's update: z = (L̂ − L_fix, λ̂ − λ_fix) with R its covariance, whitened by R's
// Cholesky factor (z' = L⁻¹z, H' = L⁻¹H, R' = I) into two independent scalar updates.
struct PositionUpdate {
  ScalarUpdate first{kNaNUpdate, kNaNUpdate, kNaNUpdate, kNaNUpdate};
  ScalarUpdate second{kNaNUpdate, kNaNUpdate, kNaNUpdate, kNaNUpdate};
  double nis() const { return first.nis + second.nis; }  // the fix's χ²(2)
};

enum class FilterStatus {
  Ok,              // every update finite and the NIS consistent
  NoUpdates,       // predicted only
  Inconsistent,    // the mean NIS is outside its 99.9 % χ² band for the number of updates
  NonFinite,       // a measurement, innovation or covariance was not finite: the update was skipped
  Diverged         // the state left the mechanization's domain (ins/mechanization.h, in_ins_domain)
};
// "ok", "no_updates", "inconsistent", "non_finite", "diverged"
std::string_view filter_status_name(FilterStatus s);

// How a run went (after Ceres's Solver::Summary): failures are data.
struct FilterSummary {
  FilterStatus status = FilterStatus::NoUpdates;
  int predictions = 0;
  int updates = 0;                  // scalar sun updates (two a reading for the sun vector)
  int skipped = 0;                  // non-finite measurements or innovations
  double innovation_mean = 0;       // of z − Hx⁻
  double innovation_rms = 0;
  double mean_nis = 0;
  double nis_outside_95 = 0;        // the fraction outside χ²(1)'s [0.000982, 5.024]
  double final_R = std::numeric_limits<double>::quiet_NaN();
  // Zero-velocity updates (scalar, one per velocity component), apart from the sun's above: they
  // neither enter the sun's NIS statistics nor the status.
  int zero_velocity_updates = 0;
  double zero_velocity_mean_nis = std::numeric_limits<double>::quiet_NaN();
  std::string BriefReport() const;  // one line
};

// One compass epoch of the filter as the RTS smoother needs it (ins/smoother.h's FilterRecord).
struct InsFilterEpoch {
  Matrix15 Phi = Matrix15::Identity();      // Φ since the previous epoch (the product of every step's)
  Matrix15 P_prior = Matrix15::Zero();      // P before this epoch's updates
  Matrix15 P_post = Matrix15::Zero();       // P after them (= P_prior without one)
  Vector15 correction = Vector15::Zero();   // the sum of what its updates fed back
};

// The INS with the filter in closed loop.
class InsFilter {
 public:
  // With a held height (settings.mechanization.hold_height_m) δv_U and δh are pinned: P0's rows and
  // columns for them are taken as zero, and F's and Q's are zeroed at every step.
  InsFilter(const InsState& initial, const Matrix15& P0, const FilterSettings& settings = {});

  // Mechanizes one raw sample (the bias estimates removed) over Δt = cur.t_s − state().t_s and
  // predicts P with Φ = I + FΔt, F at the new state and f^n of the sample (CovarianceStep::
  // EverySample), or keeps f^n·Δt for propagate_covariance (AtUpdates). x stays 0 (closed loop).
  void predict(const ImuSample& cur);
  // Brings P to the current state's time (with CovarianceStep::AtUpdates; otherwise it already is).
  // update() calls it first; call it before reading P() between updates.
  void propagate_covariance();
  // The sun's update(s) at the current state (FilterSettings::measurement), with feedback. Throws
  // std::invalid_argument when m.t_s is more than 1 ms from the state's time (a programming error);
  // a non-finite measurement is data: skipped and counted in the summary.
  SunUpdate update(const SunObservation& m);
  // A zero-velocity update at the current state (the vehicle at rest: ins/zupt.h says when), each
  // velocity component a scalar update with R = σ², fed back; the velocity error is then observed
  // directly, the tilt and the horizontal accelerometer biases through it (docs/physics.md §18.9).
  ZeroVelocityUpdate update_zero_velocity(double sigma_mps);
  // A position fix (a PNS's, loosely coupled) at the current state: latitude and longitude (rad) and
  // the covariance of its north and east errors (m²), counted as the sun's updates are (two scalar
  // ones: NIS, status). Throws std::invalid_argument when the covariance is not positive definite;
  // a non-finite fix is skipped and counted.
  PositionUpdate update_position(double lat_rad, double lon_rad, const Eigen::Matrix2d& cov_north_east_m2);
  // Ends a compass epoch at the current state (after its updates, or none) and returns its record
  // for a smoother; the next epoch's Φ and correction start from here.
  InsFilterEpoch end_epoch();

  const InsState& state() const { return state_; }
  const Eigen::Vector3d& gyro_bias() const { return gyro_bias_; }
  const Eigen::Vector3d& accel_bias() const { return accel_bias_; }
  const Matrix15& P() const { return filter_.P; }
  // The R of the last update (Sage–Husa's estimate when adaptive), NaN before the first.
  double R() const { return last_R_; }
  FilterSummary summary() const;

 private:
  // One scalar update (Sage–Husa's R when settings_.adaptive and `adaptive` is given; R_nominal when
  // null), counted in the summary; skipped when not finite.
  ScalarUpdate scalar_update(const RowVector15& H, double z, double R_nominal, std::optional<SageHusaR>* adaptive);
  void feed_back_and_reset();  // x into the state and the bias estimates, then x = 0

  InsState state_;
  ImuSample prev_;
  bool has_prev_ = false;
  Eigen::Vector3d gyro_bias_ = Eigen::Vector3d::Zero(), accel_bias_ = Eigen::Vector3d::Zero();
  ErrorFilter filter_;
  FilterSettings settings_;
  std::optional<SageHusaR> sage_husa_;  // started at the first update's (cos H^n σ_H)²
  std::optional<SageHusaR> sage_husa_azimuth_;  // the azimuth's, from σ_A²
  double last_R_ = std::numeric_limits<double>::quiet_NaN();
  Matrix15 Phi_since_epoch_ = Matrix15::Identity();  // for end_epoch
  std::optional<Matrix15> P_prior_;                  // P at the epoch's first update
  Vector15 correction_ = Vector15::Zero();           // fed back since the epoch began
  Eigen::Vector3d f_dt_sum_ = Eigen::Vector3d::Zero();  // ∫f^n dt since P was last propagated (AtUpdates)
  double pending_s_ = 0;                               // and that interval's length
  int predictions_ = 0, updates_ = 0, skipped_ = 0, nis_outside_ = 0, zero_velocity_updates_ = 0;
  double zero_velocity_nis_ = 0;
  double sum_r_ = 0, sum_r2_ = 0, sum_nis_ = 0;
};

}  // namespace polrig
