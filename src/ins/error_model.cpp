#include "polrig/ins/error_model.h"

#include <cmath>


#include "polrig/ins/earth.h"

namespace polrig {

ErrorModelNoise error_model_noise(const ImuErrorSpec& imu) {
  ErrorModelNoise n;
  n.arw = imu.gyro.white_noise;
  n.vrw = imu.accel.white_noise;
  for (int i = 0; i < 3; ++i) {
    if (imu.gyro.bias_instability[i] > 0) {
      n.gyro_tau_s[i] = imu.gyro.correlation_time_s[i];
      n.gyro_bias_sigma[i] = imu.gyro.bias_instability[i];
    }
    if (imu.accel.bias_instability[i] > 0) {
      n.accel_tau_s[i] = imu.accel.correlation_time_s[i];
      n.accel_bias_sigma[i] = imu.accel.bias_instability[i];
    }
  }
  return n;
}

Matrix15 error_dynamics(const InsState& s, const Eigen::Vector3d& f_n, const ErrorModelNoise& noise) {
  const double L = s.lat_rad, h = s.h_m;
  const double vE = s.v_n.x(), vN = s.v_n.y();
  const EarthRadii r = earth_radii(L);
  const double RMh = r.R_M + h, RNh = r.R_N + h;
  const double tanL = std::tan(L), secL = 1.0 / std::cos(L);
  const Eigen::Vector3d w_ie = omega_ie_n(L), w_en = omega_en_n(s.v_n, L, h);
  const Eigen::Matrix3d C_bn = s.C_bn();

  // δω_in = M_av δV + (M_p1 + M_p2) δp: the partials of ω_ie (M_p1) and ω_en (M_av, M_p2).
  Eigen::Matrix3d M_av, M_p1, M_p2;
  M_av << 0, -1 / RMh, 0, 1 / RNh, 0, 0, tanL / RNh, 0, 0;
  M_p1 << 0, 0, 0, -kEarthRate * std::sin(L), 0, 0, kEarthRate * std::cos(L), 0, 0;
  M_p2 << 0, 0, vN / (RMh * RMh), 0, 0, -vE / (RNh * RNh), vE * secL * secL / RNh, 0, -vE * tanL / (RNh * RNh);

  Matrix15 F = Matrix15::Zero();
  F.block<3, 3>(kPhi, kPhi) = -skew(w_ie + w_en);
  F.block<3, 3>(kPhi, kDV) = M_av;
  F.block<3, 3>(kPhi, kDLat) = M_p1 + M_p2;
  F.block<3, 3>(kPhi, kGyroBias) = -C_bn;

  const Eigen::Matrix3d V = skew(s.v_n);
  F.block<3, 3>(kDV, kPhi) = skew(f_n);
  F.block<3, 3>(kDV, kDV) = V * M_av - skew(2 * w_ie + w_en);
  Eigen::Matrix3d M_vp = V * (2 * M_p1 + M_p2);
  const GravityGradient gg = gravity_gradient(L, h);
  M_vp(2, 0) -= gg.dg_dL;
  M_vp(2, 2) -= gg.dg_dh;
  F.block<3, 3>(kDV, kDLat) = M_vp;
  F.block<3, 3>(kDV, kAccelBias) = C_bn;

  Eigen::Matrix3d M_pv, M_pp;
  M_pv << 0, 1 / RMh, 0, secL / RNh, 0, 0, 0, 0, 1;
  M_pp << 0, 0, -vN / (RMh * RMh), vE * secL * tanL / RNh, 0, -vE * secL / (RNh * RNh), 0, 0, 0;
  F.block<3, 3>(kDLat, kDV) = M_pv;
  F.block<3, 3>(kDLat, kDLat) = M_pp;

  for (int i = 0; i < 3; ++i) {
    F(kGyroBias + i, kGyroBias + i) = -1.0 / noise.gyro_tau_s[i];
    F(kAccelBias + i, kAccelBias + i) = -1.0 / noise.accel_tau_s[i];
  }
  return F;
}

Matrix15 process_noise_density(const InsState& s, const ErrorModelNoise& noise) {
  const Eigen::Matrix3d C_bn = s.C_bn();
  Matrix15 Qc = Matrix15::Zero();
  Qc.block<3, 3>(kPhi, kPhi) = C_bn * noise.arw.cwiseAbs2().asDiagonal() * C_bn.transpose();
  Qc.block<3, 3>(kDV, kDV) = C_bn * noise.vrw.cwiseAbs2().asDiagonal() * C_bn.transpose();
  for (int i = 0; i < 3; ++i) {
    if (std::isfinite(noise.gyro_tau_s[i]))
      Qc(kGyroBias + i, kGyroBias + i) = 2 * noise.gyro_bias_sigma[i] * noise.gyro_bias_sigma[i] / noise.gyro_tau_s[i];
    if (std::isfinite(noise.accel_tau_s[i]))
      Qc(kAccelBias + i, kAccelBias + i) = 2 * noise.accel_bias_sigma[i] * noise.accel_bias_sigma[i] / noise.accel_tau_s[i];
  }
  return Qc;
}

Discretized discretize_first_order(const Matrix15& F, const Matrix15& Qc, double dt_s) {
  Discretized d;
  d.Phi = Matrix15::Identity() + F * dt_s;
  d.Q = 0.5 * (d.Phi * Qc + Qc * d.Phi.transpose()) * dt_s;
  return d;
}

// Van Loan's pair by the Taylor series of the integral it stands for, at Δt/2^s, then doubled s
// times: with τ = Δt/2^s,
//   Φ(τ) = Σ_k (Fτ)^k/k!,   Q(τ) = ∫₀^τ e^{Fu} Q_c e^{Fᵀu} du = Σ_{k≥1} τ^k/k! · L^{k−1}(Q_c),
// L(X) = F·X + X·Fᵀ (the integrand's own series, integrated term by term; L(X) of a symmetric X is
// F·X plus its transpose), and Φ(2τ) = Φ(τ)², Q(2τ) = Φ(τ)·Q(τ)·Φ(τ)ᵀ + Q(τ). s makes ‖F‖₁τ ≤ 1/8;
// the first terms left out, Φ's 12th and Q's 13th, are below (1/8)^12/12! ≈ 3e-20 and
// (1/4)^12/13! ≈ 1e-17 of the sums' scale (‖L‖ ≤ 2‖F‖). Fifteen-by-fifteen products only: a third
// of the cost of Padé on the 30 × 30 exp([[−F, Q_c], [0, Fᵀ]]Δt), which tests/test_ins.cpp computes
// as the reference.
Discretized discretize_van_loan(const Matrix15& F, const Matrix15& Qc, double dt_s) {
  const double norm = (F * dt_s).cwiseAbs().colwise().sum().maxCoeff();
  const int s = norm > 0.125 ? static_cast<int>(std::ceil(std::log2(norm / 0.125))) : 0;
  const double tau = std::ldexp(dt_s, -s);
  constexpr int kTerms = 11;
  Matrix15 Phi = Matrix15::Identity(), Q = Qc * tau;
  Matrix15 phi_term = Matrix15::Identity(), q_term = Q;
  // lazyProduct: at 15 × 15 Eigen's coefficient loops beat its blocked GEMM (no packing).
  for (int k = 1; k <= kTerms; ++k) {
    phi_term = ((tau / k) * F.lazyProduct(phi_term)).eval();
    Phi += phi_term;
    const Matrix15 Fq = F.lazyProduct(q_term);
    q_term = (tau / (k + 1)) * (Fq + Fq.transpose());
    Q += q_term;
  }
  for (int i = 0; i < s; ++i) {
    const Matrix15 PhiQ = Phi.lazyProduct(Q);
    Q += PhiQ.lazyProduct(Phi.transpose());
    Phi = Phi.lazyProduct(Phi).eval();
  }
  return {Phi, 0.5 * (Q + Q.transpose())};
}

void feed_back(const Vector15& x, InsState& s, Eigen::Vector3d& gyro_bias, Eigen::Vector3d& accel_bias) {
  s.q_bn = (quaternion_from_rotation_vector(x.segment<3>(kPhi)) * s.q_bn).normalized();
  s.v_n -= x.segment<3>(kDV);
  s.lat_rad -= x[kDLat];
  s.lon_rad -= x[kDLon];
  s.h_m -= x[kDh];
  gyro_bias += x.segment<3>(kGyroBias);
  accel_bias += x.segment<3>(kAccelBias);
}

}  // namespace polrig
