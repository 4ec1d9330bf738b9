#include "polrig/ins/filter.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <fmt/format.h>

#include "polrig/ins/earth.h"
#include "polrig/statistics.h"

namespace polrig {
namespace {

// χ²(1)'s 2.5 % and 97.5 % quantiles.
constexpr double kChi2Lo95 = 0.000982069, kChi2Hi95 = 5.023886;


// A held height (Z21's barometer; MechanizationOptions::hold_height_m) resets h and v_U after
// every step: their errors are 0 whatever the rest does, so δh and δv_U are constants of the error
// dynamics and carry no noise. P's rows and columns for them then stay as P0's (zero) and no update
// or smoother gains information about the horizontal from a vertical channel that does not move.
void pin_vertical(Matrix15& F, Matrix15& Qc) {
  for (const int i : {kDV + 2, kDh}) {
    F.row(i).setZero();
    F.col(i).setZero();
    Qc.row(i).setZero();
    Qc.col(i).setZero();
  }
}

}  // namespace

SunElevationModel sun_elevation_model(double L, double lon, double dec, double gha) {
  const double lha = gha + lon;
  const double sL = std::sin(L), cL = std::cos(L), sD = std::sin(dec), cD = std::cos(dec);
  return {sL * sD + cL * cD * std::cos(lha), sD * cL - cD * sL * std::cos(lha), -cD * cL * std::sin(lha)};
}

SageHusaR::SageHusaR(double R0, double b, double min_factor, double max_factor)
    : R_(R0), b_(b), R_min_(min_factor * R0), R_max_(max_factor * R0) {
  if (!(R0 > 0) || !(b > 0) || !(min_factor > 0) || !(max_factor >= min_factor))
    throw std::invalid_argument(fmt::format("Sage–Husa R: R0 {}, b {}, clamp {}…{} must be positive and ordered",
                                            R0, b, min_factor, max_factor));
}

double SageHusaR::update(double innovation, double HPHt) {
  const double sample = std::max(innovation * innovation - HPHt, R_min_);
  R_ = std::min((1 - beta_) * R_ + beta_ * sample, R_max_);
  beta_ = beta_ / (beta_ + b_);
  return R_;
}

void ErrorFilter::predict(const Matrix15& Phi, const Matrix15& Q) {
  x = Phi * x;
  P = Phi * P * Phi.transpose() + Q;
  P = 0.5 * (P + P.transpose()).eval();
}

ScalarUpdate ErrorFilter::update(const RowVector15& H, double z, double R) {
  ScalarUpdate u;
  const Vector15 PHt = P * H.transpose();
  u.innovation = z - H.dot(x);
  u.R = R;
  u.variance = H.dot(PHt) + R;
  u.nis = u.innovation * u.innovation / u.variance;
  const Vector15 K = PHt / u.variance;
  x += K * u.innovation;
  const Matrix15 IKH = Matrix15::Identity() - K * H;
  P = IKH * P * IKH.transpose() + K * R * K.transpose();
  P = 0.5 * (P + P.transpose()).eval();
  return u;
}

std::string_view filter_status_name(FilterStatus s) {
  switch (s) {
    case FilterStatus::Ok: return "ok";
    case FilterStatus::NoUpdates: return "no_updates";
    case FilterStatus::Inconsistent: return "inconsistent";
    case FilterStatus::NonFinite: return "non_finite";
    case FilterStatus::Diverged: return "diverged";
  }
  return "?";
}

std::string FilterSummary::BriefReport() const {
  const std::string zupt = zero_velocity_updates == 0 ? std::string() :
      fmt::format("; {} zero-velocity updates, mean NIS {:.3g}", zero_velocity_updates, zero_velocity_mean_nis);
  return fmt::format("{}: {} predictions, {} updates ({} skipped), innovation mean {:.3g} rms {:.3g}, "
                     "mean NIS {:.3g}, {:.1f} % outside χ²(1) 95 %, R {:.3g}",
                     filter_status_name(status), predictions, updates, skipped, innovation_mean,
                     innovation_rms, mean_nis, 100 * nis_outside_95, final_R) + zupt;
}

InsFilter::InsFilter(const InsState& initial, const Matrix15& P0, const FilterSettings& settings)
    : state_(initial), settings_(settings) {
  filter_.P = P0;
  if (settings.mechanization.hold_height_m)  // pinned (pin_vertical): held h and v_U have no error
    for (const int i : {kDV + 2, kDh}) {
      filter_.P.row(i).setZero();
      filter_.P.col(i).setZero();
    }
  if (!(settings.sigma_H_rad > 0))
    throw std::invalid_argument(fmt::format("filter: σ_H {} rad must be > 0", settings.sigma_H_rad));
  if (!(settings.sigma_A_rad > 0))
    throw std::invalid_argument(fmt::format("filter: σ_A {} rad must be > 0", settings.sigma_A_rad));

}

void InsFilter::predict(const ImuSample& raw) {
  const double dt = raw.t_s - state_.t_s;
  const ImuSample cur = compensate(raw, gyro_bias_, accel_bias_, dt);
  const ImuSample& prev = has_prev_ ? prev_ : cur;
  const Eigen::Vector3d f_n = specific_force_n(state_, cur, dt);
  state_ = mechanize(state_, prev, cur, settings_.mechanization);
  if (settings_.covariance_step == FilterSettings::CovarianceStep::AtUpdates) {
    f_dt_sum_ += f_n * dt;
    pending_s_ += dt;
  } else {
    Matrix15 F = error_dynamics(state_, f_n, settings_.noise), Qc = process_noise_density(state_, settings_.noise);
    if (settings_.mechanization.hold_height_m) pin_vertical(F, Qc);
    const Discretized d = discretize_first_order(F, Qc, dt);
    filter_.predict(d.Phi, d.Q);
    Phi_since_epoch_ = d.Phi * Phi_since_epoch_;
  }
  prev_ = cur;
  has_prev_ = true;
  ++predictions_;
}

void InsFilter::propagate_covariance() {
  if (!(pending_s_ > 0)) return;
  Matrix15 F = error_dynamics(state_, f_dt_sum_ / pending_s_, settings_.noise);
  Matrix15 Qc = process_noise_density(state_, settings_.noise);
  if (settings_.mechanization.hold_height_m) pin_vertical(F, Qc);
  const Discretized d = discretize_van_loan(F, Qc, pending_s_);
  filter_.predict(d.Phi, d.Q);
  Phi_since_epoch_ = d.Phi * Phi_since_epoch_;
  f_dt_sum_.setZero();
  pending_s_ = 0;
}

std::string_view sun_measurement_name(FilterSettings::SunMeasurement m) {
  using M = FilterSettings::SunMeasurement;
  switch (m) {
    case M::ElevationZ21: return "elevation-z21";
    case M::Elevation: return "elevation";
    case M::Azimuth: return "azimuth";
    case M::SunVector: return "sun-vector";
    case M::PnsFix: return "pns-fix";
  }
  return "?";
}

SunAzimuthModel sun_azimuth_model(double L, double lon, double dec, double gha) {
  const double lha = gha + lon;
  const double sL = std::sin(L), cL = std::cos(L), sD = std::sin(dec), cD = std::cos(dec);
  const double sH = sL * sD + cL * cD * std::cos(lha);
  const double sE = -cD * std::sin(lha), sN = sD * cL - cD * sL * std::cos(lha);
  const double rho2 = sE * sE + sN * sN;
  return {std::atan2(sE, sN), sE * sH / rho2, -cD * (sN * std::cos(lha) + sE * sL * std::sin(lha)) / rho2, sE, sN, sH};
}

void InsFilter::feed_back_and_reset() {
  // A held height (Z21's barometer) is the mechanization's, not the filter's: pinned, its δh and
  // δv_U rows of P are 0, so x's are too and nothing moves the held height.
  feed_back(filter_.x, state_, gyro_bias_, accel_bias_);
  correction_ += filter_.x;
  state_.lon_rad = std::remainder(state_.lon_rad, 2 * std::numbers::pi);  // a correction across 180° stays a longitude
  filter_.x.setZero();
}

ScalarUpdate InsFilter::scalar_update(const RowVector15& H, double z, double R_nominal, std::optional<SageHusaR>* adaptive) {
  if (!std::isfinite(z) || !std::isfinite(R_nominal) || !H.allFinite() || !filter_.P.allFinite()) {
    ++skipped_;
    return {z, kNaNUpdate, kNaNUpdate, R_nominal};
  }
  double R = R_nominal;
  if (settings_.adaptive && adaptive) {
    if (!*adaptive) adaptive->emplace(R_nominal, settings_.sage_husa_b, settings_.R_min_factor, settings_.R_max_factor);
    R = (*adaptive)->update(z - H.dot(filter_.x), H.dot(filter_.P * H.transpose()));
  }
  const ScalarUpdate u = filter_.update(H, z, R);
  if (adaptive) last_R_ = R;  // the sun's R (a whitened fix's is 1, nothing to report)
  ++updates_;
  sum_r_ += u.innovation;
  sum_r2_ += u.innovation * u.innovation;
  sum_nis_ += u.nis;
  if (u.nis < kChi2Lo95 || u.nis > kChi2Hi95) ++nis_outside_;
  return u;
}

InsFilterEpoch InsFilter::end_epoch() {
  propagate_covariance();
  InsFilterEpoch e{Phi_since_epoch_, P_prior_.value_or(filter_.P), filter_.P, correction_};
  Phi_since_epoch_.setIdentity();
  P_prior_.reset();
  correction_.setZero();
  return e;
}

SunUpdate InsFilter::update(const SunObservation& m) {
  using M = FilterSettings::SunMeasurement;
  propagate_covariance();
  if (!P_prior_) P_prior_ = filter_.P;
  if (!(std::abs(m.t_s - state_.t_s) <= 1e-3))
    throw std::invalid_argument(fmt::format("filter: a measurement at {} s for the state at {} s", m.t_s, state_.t_s));
  const M kind = settings_.measurement;
  if (kind == M::PnsFix)
    throw std::invalid_argument("filter: measurement pns-fix takes position fixes (update_position), not the sun");
  const bool elevation = kind != M::Azimuth, azimuth = kind == M::Azimuth || kind == M::SunVector;
  const bool tilt = kind != M::ElevationZ21;
  if (tilt && (!std::isfinite(m.sun_east) || !std::isfinite(m.sun_north)) && std::isfinite(m.elevation_rad))
    throw std::invalid_argument(fmt::format("filter: the {} measurement needs the sun's east and north components",
                                            sun_measurement_name(kind)));
  SunUpdate out;
  // The two components in turn, each fed back before the next is linearized at the corrected state.
  if (elevation) {
    const SunElevationModel model = sun_elevation_model(state_.lat_rad, state_.lon_rad, m.dec_rad, m.gha_rad);
    RowVector15 H = RowVector15::Zero();
    H[kDLat] = model.d_lat;
    H[kDLon] = model.d_lon;
    if (tilt) {
      H[kPhi] = m.sun_north;
      H[kPhi + 1] = -m.sun_east;
    }
    const double z = model.sin_H - std::sin(m.elevation_rad);
    out.elevation = scalar_update(H, z, std::pow(std::cos(m.elevation_rad) * settings_.sigma_H_rad, 2), &sage_husa_);
    if (std::isfinite(out.elevation.nis)) feed_back_and_reset();
  }
  if (azimuth) {
    const SunAzimuthModel model = sun_azimuth_model(state_.lat_rad, state_.lon_rad, m.dec_rad, m.gha_rad);
    const double rho2 = m.sun_east * m.sun_east + m.sun_north * m.sun_north, s_up = std::sin(m.elevation_rad);
    RowVector15 H = RowVector15::Zero();
    H[kDLat] = model.d_lat;
    H[kDLon] = model.d_lon;
    H[kPhi] = s_up * m.sun_east / rho2;
    H[kPhi + 1] = s_up * m.sun_north / rho2;
    H[kPhi + 2] = -1;
    const double z = std::remainder(model.azimuth - std::atan2(m.sun_east, m.sun_north), 2 * std::numbers::pi);
    out.azimuth = scalar_update(H, z, settings_.sigma_A_rad * settings_.sigma_A_rad, &sage_husa_azimuth_);
    if (std::isfinite(out.azimuth.nis)) feed_back_and_reset();
  }
  return out;
}

ZeroVelocityUpdate InsFilter::update_zero_velocity(double sigma_mps) {
  if (!(sigma_mps > 0) || !std::isfinite(sigma_mps))
    throw std::invalid_argument(fmt::format("filter: a zero-velocity σ of {} m/s (expected > 0)", sigma_mps));
  propagate_covariance();
  if (!P_prior_) P_prior_ = filter_.P;
  ZeroVelocityUpdate out;
  ScalarUpdate* component[3] = {&out.east, &out.north, &out.up};
  const int axes = settings_.mechanization.hold_height_m ? 2 : 3;  // held: δv_U pinned at 0
  for (int i = 0; i < axes; ++i) {
    RowVector15 H = RowVector15::Zero();
    H[kDV + i] = 1;
    const double z = state_.v_n[i];  // δv = v̂ − v, v = 0
    if (!std::isfinite(z) || !filter_.P.allFinite()) {
      ++skipped_;
      continue;
    }
    *component[i] = filter_.update(H, z, sigma_mps * sigma_mps);
    ++zero_velocity_updates_;
    zero_velocity_nis_ += component[i]->nis;
    feed_back_and_reset();
  }
  return out;
}

PositionUpdate InsFilter::update_position(double lat_rad, double lon_rad, const Eigen::Matrix2d& cov_north_east_m2) {
  propagate_covariance();
  if (!P_prior_) P_prior_ = filter_.P;
  PositionUpdate out;
  const Eigen::Vector2d z(state_.lat_rad - lat_rad, std::remainder(state_.lon_rad - lon_rad, 2 * std::numbers::pi));
  if (!z.allFinite() || !cov_north_east_m2.allFinite() || !filter_.P.allFinite()) {
    ++skipped_;
    return out;
  }
  // North and east metres → δL, δλ radians at the state.
  const EarthRadii r = earth_radii(state_.lat_rad);
  const Eigen::Vector2d per_m(1 / (r.R_M + state_.h_m), 1 / ((r.R_N + state_.h_m) * std::cos(state_.lat_rad)));
  const Eigen::Matrix2d R = per_m.asDiagonal() * cov_north_east_m2 * per_m.asDiagonal();
  const Eigen::LLT<Eigen::Matrix2d> llt(R);
  if (llt.info() != Eigen::Success || !(R.determinant() > 0))
    throw std::invalid_argument(fmt::format("filter: a position fix's covariance [[{}, {}], [{}, {}]] m² is not positive "
                                            "definite", cov_north_east_m2(0, 0), cov_north_east_m2(0, 1),
                                            cov_north_east_m2(1, 0), cov_north_east_m2(1, 1)));
  const Eigen::Matrix2d L_inv = llt.matrixL().solve(Eigen::Matrix2d::Identity());
  ScalarUpdate* component[2] = {&out.first, &out.second};
  for (int i = 0; i < 2; ++i) {
    // Each whitened row against the state as it now is (the first's correction fed back).
    const Eigen::Vector2d z_now(state_.lat_rad - lat_rad, std::remainder(state_.lon_rad - lon_rad, 2 * std::numbers::pi));
    RowVector15 H = RowVector15::Zero();
    H[kDLat] = L_inv(i, 0);
    H[kDLon] = L_inv(i, 1);
    *component[i] = scalar_update(H, L_inv.row(i).dot(z_now), 1.0, nullptr);  // the fix's own R, never adapted
    if (std::isfinite(component[i]->nis)) feed_back_and_reset();
  }
  return out;
}

FilterSummary InsFilter::summary() const {
  FilterSummary s;
  s.predictions = predictions_;
  s.updates = updates_;
  s.skipped = skipped_;
  s.final_R = last_R_;
  s.zero_velocity_updates = zero_velocity_updates_;
  if (zero_velocity_updates_ > 0) s.zero_velocity_mean_nis = zero_velocity_nis_ / zero_velocity_updates_;
  if (updates_ > 0) {
    s.innovation_mean = sum_r_ / updates_;
    s.innovation_rms = std::sqrt(sum_r2_ / updates_);
    s.mean_nis = sum_nis_ / updates_;
    s.nis_outside_95 = static_cast<double>(nis_outside_) / updates_;
  }
  constexpr double z999 = 3.2905;  // the two-sided 99.9 % normal quantile
  if (skipped_ > 0 || !filter_.P.allFinite() || !state_.v_n.allFinite())
    s.status = FilterStatus::NonFinite;
  else if (updates_ == 0)
    s.status = FilterStatus::NoUpdates;
  else if (s.mean_nis < chi2_mean_quantile(updates_, -z999) || s.mean_nis > chi2_mean_quantile(updates_, z999))
    s.status = FilterStatus::Inconsistent;
  else
    s.status = FilterStatus::Ok;
  return s;
}

}  // namespace polrig
