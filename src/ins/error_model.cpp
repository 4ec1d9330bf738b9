#include "polrig/ins/error_model.h"

#include <algorithm>
#include <cmath>
#include <limits>

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

namespace {

// Power-of-two scales d with D⁻¹·F·D balanced, D = diag(d) (Parlett & Reinsch 1969, LAPACK's
// dgebal): each state's off-diagonal row and column sums brought within a factor of 2 of each
// other, and a column whose row is empty (a bias: ε drives φ, nothing drives ε) shrunk below 1/64.
// Powers of two scale without rounding. F must be finite (an infinite sum would never halve).
// F's norm is ~10 s⁻¹ from f^n × φ and C_b^n alone (units of rad against m/s); balanced it is a
// few hundredths, and 1 s needs no doubling.
Vector15 balancing_scales(const Matrix15& F) {
  Vector15 d = Vector15::Ones();
  Matrix15 A = F.cwiseAbs();
  A.diagonal().setZero();
  for (int sweep = 0; sweep < 64; ++sweep) {
    bool changed = false;
    for (int i = 0; i < 15; ++i) {
      double c = A.col(i).sum(), r = A.row(i).sum(), f = 1;
      if (c == 0) continue;
      if (r == 0) {
        while (c > 1.0 / 64) c /= 2, f /= 2;
      } else {
        const double sum = c + r;
        while (c < r / 2) c *= 2, r /= 2, f *= 2;
        while (c >= 2 * r) c /= 2, r *= 2, f /= 2;
        if (c + r >= 0.95 * sum) continue;
      }
      if (f == 1) continue;
      d[i] *= f;
      A.col(i) *= f;
      A.row(i) /= f;
      changed = true;
    }
    if (!changed) break;
  }
  return d;
}

// K: the fewest terms with θ^{K+1}/(K+1)! and (2θ)^{K+1}/(K+2)! below 2^-60.
int norm_terms(double theta) {
  int K = 1;
  double phi_left = theta * theta / 2, q_left = 4 * theta * theta / 6;  // K = 1's
  for (; (phi_left > 0x1p-60 || q_left > 0x1p-60) && K < 30; ++K) {
    phi_left *= theta / (K + 2);
    q_left *= 2 * theta / (K + 3);
  }
  return K;
}

// Φ(τ) and Q(τ) by their series: K terms, then on while a term still moves an entry by more than
// 2^-55 of its scale (Φ: its row's largest; Q: √(Q_ii·Q_jj)). Q' spans many orders (a bias's noise
// scaled up, the position's down) and the norm bound speaks for the largest entries only.
// lazyProduct: at 15 × 15 Eigen's coefficient loops beat its blocked GEMM.
Discretized taylor_pair(const Matrix15& F, const Matrix15& Qc, double tau, int K) {
  const auto phi_moves = [](const Matrix15& term, const Matrix15& sum) {
    const Vector15 row_max = sum.cwiseAbs().rowwise().maxCoeff();
    return (term.cwiseAbs().array() > 0x1p-55 * row_max.replicate<1, 15>().array()).any();
  };
  const auto q_moves = [](const Matrix15& term, const Matrix15& sum) {
    const Vector15 sd = sum.diagonal().cwiseAbs().cwiseSqrt();
    return (term.cwiseAbs().array() > 0x1p-55 * (sd * sd.transpose()).array()).any();
  };
  Discretized d{Matrix15::Identity(), Qc * tau};
  Matrix15 phi_term = Matrix15::Identity(), q_term = d.Q;
  for (int k = 1; k <= K || (k <= 30 && (phi_moves(phi_term, d.Phi) || q_moves(q_term, d.Q))); ++k) {
    phi_term = ((tau / k) * F.lazyProduct(phi_term)).eval();
    d.Phi += phi_term;
    const Matrix15 Fq = F.lazyProduct(q_term);
    q_term = (tau / (k + 1)) * (Fq + Fq.transpose());
    d.Q += q_term;
  }
  return d;
}

}  // namespace

// Van Loan's pair by the Taylor series of the integral it stands for, on the balanced F' = D⁻¹FD
// (Φ = D·Φ'·D⁻¹, Q = D·Q'·D with Q_c' = D⁻¹Q_cD⁻¹), at Δt/2^s, then doubled s times: with τ = Δt/2^s,
//   Φ(τ) = Σ_k (Fτ)^k/k!,   Q(τ) = ∫₀^τ e^{Fu} Q_c e^{Fᵀu} du = Σ_{k≥1} τ^k/k! · L^{k−1}(Q_c),
// L(X) = F·X + X·Fᵀ (the integrand's own series, integrated term by term; L(X) of a symmetric X is
// F·X plus its transpose), and Φ(2τ) = Φ(τ)², Q(2τ) = Φ(τ)·Q(τ)·Φ(τ)ᵀ + Q(τ). With θ the larger of
// ‖F'‖₁τ and ‖F'‖∞τ, ‖Fτ‖₁ ≤ θ and ‖L(X)τ‖₁ ≤ (‖F'‖₁ + ‖F'‖∞)τ‖X‖₁ ≤ 2θ‖X‖₁; s makes θ ≤ 1/8
// (s = 0 for the filter's 1 s unless a bias's correlation time is under ~8 s), and the series stop
// where the first terms left out, θ^{K+1}/(K+1)! for Φ and (2θ)^{K+1}/(K+2)! for Q, are below 2^-60
// of the sums' scale, and then on while a term still moves an entry. At the filter's 1 s: s = 0,
// 9 terms, 18 products of 15 × 15 (Padé on the 30 × 30 block matrix costs 2.4× more,
// bench `Navigation_CovarianceStep`); tests/test_ins.cpp checks the result against that Padé in long
// double. A non-finite F or Q_c (a diverged state) gives NaN, as an exponential of it would.
Discretized discretize_van_loan(const Matrix15& F, const Matrix15& Qc, double dt_s) {
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  if (!F.allFinite() || !Qc.allFinite() || !std::isfinite(dt_s))
    return {Matrix15::Constant(nan), Matrix15::Constant(nan)};
  const Vector15 d = balancing_scales(F), d_inv = d.cwiseInverse();
  const Matrix15 Fb = d_inv.asDiagonal() * F * d.asDiagonal();
  const Matrix15 abs_Fdt = (Fb * dt_s).cwiseAbs();
  const double norm = std::max(abs_Fdt.colwise().sum().maxCoeff(), abs_Fdt.rowwise().sum().maxCoeff());
  const int s = norm > 0.125 ? static_cast<int>(std::ceil(std::log2(norm / 0.125))) : 0;
  Discretized x = taylor_pair(Fb, d_inv.asDiagonal() * Qc * d_inv.asDiagonal(), std::ldexp(dt_s, -s),
                              norm_terms(std::ldexp(norm, -s)));
  for (int i = 0; i < s; ++i) {
    const Matrix15 PhiQ = x.Phi.lazyProduct(x.Q);
    x.Q += PhiQ.lazyProduct(x.Phi.transpose());
    x.Phi = x.Phi.lazyProduct(x.Phi).eval();
  }
  const Matrix15 Q = d.asDiagonal() * x.Q * d.asDiagonal();
  return {d.asDiagonal() * x.Phi * d_inv.asDiagonal(), 0.5 * (Q + Q.transpose())};
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
