#include "polrig/study/cs.h"

#include <cmath>
#include <stdexcept>

#include "polrig/device/sensor.h"

namespace polrig {

CsTurn::CsTurn(int steps_per_turn) {
  if (steps_per_turn < 2 || steps_per_turn % 2 != 0)
    throw std::invalid_argument("a CS turn needs an even number of steps ≥ 2");
  for (int k = 0; k < steps_per_turn; ++k) {
    const TableRotation r = TableRotation::at_deg(360.0 * k / steps_per_turn);
    cos_.push_back(r.c);
    sin_.push_back(r.s);
  }
}

namespace {

// ΔV_br of the three pairs over the turn, into br[i·n + k]; E holds 6·n irradiances.
// The hot loop of every sweep, written as plain loops over the turn so that they vectorize.
void deviations_before(const Rig& rig, const CsTurn& turn, double* E, double* br) {
  const int n = turn.steps();
  const double* c = turn.cos_theta();
  const double* s = turn.sin_theta();
  const Point2 port = port_centre(rig.eccentricity);
  const auto p0 = photodiode_positions(rig.device.ring, rig.eccentricity, 0.0);
  const Cos4Source& source = rig.source.cos4;
  for (int m = 0; m < 6; ++m) {
    const double qx = p0[m].x(), qy = p0[m].y();
    double* Em = E + m * n;
    for (int k = 0; k < n; ++k) {
      const double x = c[k] * qx - s[k] * qy - port.x();  // P_m(θ_R) − O_IS
      const double y = s[k] * qx + c[k] * qy - port.y();
      Em[k] = source.falloff(x * x + y * y);
    }
  }
  for (int i = 0; i < 3; ++i) {
    const double* Ej = E + pair_j(i) * n;
    const double* Eh = E + pair_h(i) * n;
    for (int k = 0; k < n; ++k)
      br[i * n + k] = eccentricity_bias(rig.device.truth, rig.electronics, i, Ej[k], Eh[k]);
  }
}

// ΔV_mr(θ_R) = [ΔV_br(θ_R) + ΔV_br(θ_R + 180°)]/2.
void central_symmetry_average(const double* br, double* mr, int n) {
  const int half = n / 2;
  for (int k = 0; k < n; ++k) mr[k] = 0.5 * (br[k] + br[(k + half) % n]);
}

// Mean and population standard deviation, two-pass.
std::pair<double, double> mean_and_sd(const double* x, int n) {
  double sum = 0.0;
  for (int k = 0; k < n; ++k) sum += x[k];
  const double mean = sum / n;
  double ss = 0.0;
  for (int k = 0; k < n; ++k) ss += (x[k] - mean) * (x[k] - mean);
  return {mean, std::sqrt(ss / n)};
}

CsSummary summarise(const Rig& rig, const double* br, const double* mr, int n) {
  CsSummary s;
  for (int i = 0; i < 3; ++i) {
    const auto [mean_br, bsd] = mean_and_sd(br + i * n, n);
    const auto [mean_mr, asd] = mean_and_sd(mr + i * n, n);
    s[i] = {bsd * 1e3, asd * 1e3, mean_br * 1e3, mean_mr * 1e3, eq6_constant_V(rig, i) * 1e3};
  }
  return s;
}

}  // namespace

CsSummary cs_summary(const Rig& rig, const CsTurn& turn, std::vector<double>& scratch) {
  const int n = turn.steps();
  scratch.resize(static_cast<std::size_t>(12 * n));
  double* br = scratch.data();
  double* mr = br + 3 * n;
  deviations_before(rig, turn, mr + 3 * n, br);
  for (int i = 0; i < 3; ++i) central_symmetry_average(br + i * n, mr + i * n, n);
  return summarise(rig, br, mr, n);
}

CsStudy cs_study(const Rig& rig, const CsTurn& turn) {
  const int n = turn.steps();
  std::vector<double> scratch;
  CsStudy study;
  study.summary = cs_summary(rig, turn, scratch);
  for (int k = 0; k < n; ++k) study.theta_R_deg.push_back(turn.theta_R_deg(k));
  for (int i = 0; i < 3; ++i) {
    study.dv_br_V[i].assign(scratch.begin() + i * n, scratch.begin() + (i + 1) * n);
    study.dv_mr_V[i].assign(scratch.begin() + (3 + i) * n, scratch.begin() + (4 + i) * n);
  }
  return study;
}

double eq6_constant_V(const Rig& rig, int pair) {
  const auto p0 = photodiode_positions(rig.device.ring, rig.eccentricity, 0.0);
  const double L_o2 = rig.source.cos4.L_o * rig.source.cos4.L_o;
  const double L_IS2 = rig.eccentricity.L_IS * rig.eccentricity.L_IS;
  const double L_Rj2 = p0[pair_j(pair)].squaredNorm();
  const double L_Rh2 = p0[pair_h(pair)].squaredNorm();
  return 2.0 * rig.device.truth.kv[pair] * rig.electronics.volts_per_decade *
         std::log10((L_o2 + L_Rh2 + L_IS2) / (L_o2 + L_Rj2 + L_IS2));
}

}  // namespace polrig
