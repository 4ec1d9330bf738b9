#include "polrig/study/cs.h"

#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

#include "polrig/device/sensor.h"
#include "polrig/sim/simulate.h"
#include "polrig/statistics.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

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

// The six photodiodes' irradiance at every step of the turn under the cos⁴ source, into
// E[m·n + k]. This is the hot loop of every sweep, written over the turn so that it vectorizes.
void cos4_irradiance_over_turn(const Rig& rig, const CsTurn& turn, double* E) {
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
}

// The traced source's effective irradiances (light_at_pose) at every step of the turn, one
// array E[m·n + k] per shift.
std::vector<std::vector<double>> traced_irradiance_over_turn(const Rig& rig, const CsTurn& turn,
                                                             const Progress& progress) {
  const int n = turn.steps(), S = rig.source.traced->shifts();
  std::vector<std::vector<double>> E(static_cast<std::size_t>(S), std::vector<double>(static_cast<std::size_t>(6 * n)));
  std::vector<TracedChannel> channel(static_cast<std::size_t>(6 * n));
  for (int mk = 0; mk < 6 * n; ++mk) channel[static_cast<std::size_t>(mk)] = traced_channel(rig, turn.theta_R_deg(mk % n), mk / n);
  // Channels whose photodiodes sit at one point (to 1 pm: a coaxial rig turning in steps that
  // divide the ring's spacing brings every channel to the same points) share the port's rays
  // and radiance, at the point of the first of them.
  std::map<std::pair<long long, long long>, std::size_t> group_at;
  std::vector<std::vector<int>> groups;
  for (int mk = 0; mk < 6 * n; ++mk) {
    const Point2& p = channel[static_cast<std::size_t>(mk)].p_scene;
    const auto [it, added] = group_at.try_emplace({std::llround(p.x() * 1e9), std::llround(p.y() * 1e9)}, groups.size());
    if (added) groups.emplace_back();
    groups[it->second].push_back(mk);
  }
  // Isolated: a sweep's outer loop must not run another grid point on this thread while it
  // waits here, since that point would share this thread's scratch.
  tbb::this_task_arena::isolate([&] { tbb::parallel_for(std::size_t{0}, groups.size(), [&](std::size_t g) {
    const std::vector<int>& members = groups[g];
    std::vector<AnalyzerFilm> films;
    for (int mk : members) films.push_back(channel[static_cast<std::size_t>(mk)].film);
    const std::vector<std::vector<double>> e = rig.source.traced->channel_signals(
        channel[static_cast<std::size_t>(members[0])].p_scene, rig.source.cos4.L_o, films);
    for (std::size_t j = 0; j < members.size(); ++j) {
      const std::size_t mk = static_cast<std::size_t>(members[j]);
      for (int sh = 0; sh < S; ++sh) {
        double x = e[j][static_cast<std::size_t>(sh)];
        x /= channel[mk].bracket;
        E[static_cast<std::size_t>(sh)][mk] = x;
      }
    }
    progress.advance(static_cast<long long>(members.size()));
  }); });
  return E;
}

// ΔV_br of the three pairs over the turn (Eq. 5) from the irradiances E[m·n + k], into br[i·n + k].
void deviations_before(const Rig& rig, const CsTurn& turn, const double* E, double* br) {
  const int n = turn.steps();
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

CsSummary summarise(const Rig& rig, const double* br, const double* mr, int n) {
  CsSummary s;
  for (int i = 0; i < 3; ++i) {
    const auto [mean_br, bsd] = mean_and_population_sd({br + i * n, static_cast<std::size_t>(n)});
    const auto [mean_mr, asd] = mean_and_population_sd({mr + i * n, static_cast<std::size_t>(n)});
    s[i] = {bsd * 1e3, asd * 1e3, mean_br * 1e3, mean_mr * 1e3, eq6_constant_V(rig, i) * 1e3};
  }
  return s;
}

}  // namespace

namespace {

// One estimate of the turn from irradiances E[m·n + k] (cos⁴ when null): ΔV_br and ΔV_mr into
// scratch, and their summary.
CsSummary one_pass(const Rig& rig, const CsTurn& turn, const double* E, std::vector<double>& scratch) {
  const int n = turn.steps();
  scratch.resize(static_cast<std::size_t>(12 * n));
  double* br = scratch.data();
  double* mr = br + 3 * n;
  if (!E) {
    cos4_irradiance_over_turn(rig, turn, mr + 3 * n);
    E = mr + 3 * n;
  }
  deviations_before(rig, turn, E, br);
  for (int i = 0; i < 3; ++i) central_symmetry_average(br + i * n, mr + i * n, n);
  return summarise(rig, br, mr, n);
}

// The standard errors of a traced source's per-shift figures, into `out`.
void add_shift_standard_errors(const std::vector<CsSummary>& per_shift, CsSummary& out) {
  std::vector<double> v(per_shift.size());
  const auto se_of = [&](auto field) {
    for (std::size_t k = 0; k < per_shift.size(); ++k) v[k] = field(per_shift[k]);
    return mean_and_standard_error(v).sd;
  };
  for (int i = 0; i < 3; ++i) {
    out[i].bsd_se_mV = se_of([&](const CsSummary& s) { return s[i].bsd_mV; });
    out[i].asd_se_mV = se_of([&](const CsSummary& s) { return s[i].asd_mV; });
    out[i].mean_br_se_mV = se_of([&](const CsSummary& s) { return s[i].mean_br_mV; });
    out[i].mean_mr_se_mV = se_of([&](const CsSummary& s) { return s[i].mean_mr_mV; });
  }
}

}  // namespace

namespace {

// A traced source: the figures of the curves averaged over the shifts (their sampling noise
// reduced by √shifts), with the standard errors of the per-shift figures. Eq. 6 is a cos⁴
// result and has no meaning here (NaN).
CsSummary traced_summary(const Rig& rig, const CsTurn& turn, std::vector<double>& scratch,
                         std::vector<double>* mean_curves, CsSummary* coaxial_summary,
                         const Progress& progress = {}) {
  const int n = turn.steps(), S = rig.source.traced->shifts();
  std::vector<double> mean(static_cast<std::size_t>(6 * n), 0.0), coaxial_mean(mean.size(), 0.0);
  std::vector<std::vector<double>> curves;  // per shift, for the standard errors per pose
  std::vector<CsSummary> per_shift;
  // ΔV refers to the coaxial rig's traced voltages at the same pose (ideal_irradiance): Eq. 5's
  // bias of the eccentric rig less that of the coaxial one, log10 of the ratio of ratios.
  rig.source.traced->solve(progress);
  progress.begin("study cs: channels at every pose, eccentric and coaxial", 2 * 6 * n);
  std::vector<std::vector<double>> E = traced_irradiance_over_turn(rig, turn, progress);
  const std::vector<std::vector<double>> E_ideal = traced_irradiance_over_turn(coaxial(rig), turn, progress);
  progress.finish();
  for (int k = 0; k < S; ++k) {
    std::vector<double>& e = E[static_cast<std::size_t>(k)];
    const std::vector<double>& ideal = E_ideal[static_cast<std::size_t>(k)];
    if (coaxial_summary) {  // the coaxial rig against the uniform light of the nominal model
      one_pass(rig, turn, ideal.data(), scratch);
      for (std::size_t j = 0; j < coaxial_mean.size(); ++j) coaxial_mean[j] += scratch[j] / S;
    }
    for (int i = 0; i < 3; ++i)
      for (int t = 0; t < n; ++t) {  // scale the h channel so that E_j/E_h becomes the ratio of ratios
        const std::size_t j = static_cast<std::size_t>(pair_j(i) * n + t), h = static_cast<std::size_t>(pair_h(i) * n + t);
        e[h] *= ideal[j] / ideal[h];
      }
    per_shift.push_back(one_pass(rig, turn, e.data(), scratch));
    for (std::size_t j = 0; j < mean.size(); ++j) mean[j] += scratch[j] / S;
    curves.emplace_back(scratch.begin(), scratch.begin() + 6 * n);
  }
  CsSummary out = summarise(rig, mean.data(), mean.data() + 3 * n, n);
  add_shift_standard_errors(per_shift, out);
  if (coaxial_summary) *coaxial_summary = summarise(rig, coaxial_mean.data(), coaxial_mean.data() + 3 * n, n);
  for (int i = 0; i < 3; ++i) out[i].eq6_mV = std::numeric_limits<double>::quiet_NaN();
  if (mean_curves) {
    std::vector<double> v(static_cast<std::size_t>(S));
    const std::size_t values = mean.size();
    for (std::size_t j = 0; j < values; ++j) {
      for (int k = 0; k < S; ++k) v[static_cast<std::size_t>(k)] = curves[static_cast<std::size_t>(k)][j];
      mean.push_back(mean_and_standard_error(v).sd);  // appended: the standard error of each value
    }
    *mean_curves = std::move(mean);
  }
  return out;
}

}  // namespace

CsSummary cs_summary(const Rig& rig, const CsTurn& turn, std::vector<double>& scratch) {
  if (!rig.source.traced) return one_pass(rig, turn, nullptr, scratch);
  return traced_summary(rig, turn, scratch, nullptr, nullptr);
}

CsStudy cs_study(const Rig& rig, const CsTurn& turn, const Progress& progress) {
  const int n = turn.steps();
  std::vector<double> scratch;
  CsStudy study;
  study.traced = rig.source.traced != nullptr;
  for (int k = 0; k < n; ++k) study.theta_R_deg.push_back(turn.theta_R_deg(k));
  std::vector<double> curves;
  if (study.traced) {
    study.summary = traced_summary(rig, turn, scratch, &curves, &study.coaxial, progress);
  } else {
    study.summary = one_pass(rig, turn, nullptr, scratch);
    curves.assign(scratch.begin(), scratch.begin() + 6 * n);
  }
  for (int i = 0; i < 3; ++i) {
    study.dv_br_V[i].assign(curves.begin() + i * n, curves.begin() + (i + 1) * n);
    study.dv_mr_V[i].assign(curves.begin() + (3 + i) * n, curves.begin() + (4 + i) * n);
    if (study.traced) {
      study.dv_br_se_V[i].assign(curves.begin() + (6 + i) * n, curves.begin() + (7 + i) * n);
      study.dv_mr_se_V[i].assign(curves.begin() + (9 + i) * n, curves.begin() + (10 + i) * n);
    }
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
