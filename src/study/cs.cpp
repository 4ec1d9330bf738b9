#include "polrig/study/cs.h"

#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "polrig/device/sensor.h"
#include "polrig/sim/simulate.h"
#include "polrig/statistics.h"
#include "polrig/vector_log.h"

namespace polrig {

namespace {

// The means and population SDs of the six curves ΔV_br and ΔV_mr of each pair (br 1–3, mr 1–3).
struct CurveMoments {
  double mean[6];
  double sd[6];
};

// One pass's arithmetic from ln(E_j/E_h) of the three pairs in br[i·n + k]: ΔV_br (Eq. 5) in
// place; ΔV_mr(θ_R) = [ΔV_br(θ_R) + ΔV_br(θ_R + 180°)]/2 into mr (in two halves, so no index wraps
// inside a loop); and the moments of the six curves, each summed in mean_and_population_sd's
// interleaved order (statistics.h: eight partial sums, k mod 8), the six side by side.
// Compiled three times, below: for baseline x86-64, AVX2 and AVX-512, with the same operations in
// the same order (no FMA, no reordered sums); the wider paths only take more values at a time (the
// eight partial sums of a curve are one AVX-512 register), so all give the same bits (test
// Cs.EveryCodePathGivesTheSameBits).
[[gnu::always_inline]] inline void curves_and_moments(const Rig& rig, double* br, double* mr, int n,
                                                      CurveMoments& m) {
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < n; ++k)
      br[i * n + k] = eccentricity_bias_of_log(rig.device.truth, rig.electronics, i, br[i * n + k]);
  const int half = n / 2;
  for (int i = 0; i < 3; ++i) {
    const double* b = br + i * n;
    double* a = mr + i * n;
    for (int k = 0; k < half; ++k) a[k] = 0.5 * (b[k] + b[k + half]);
    for (int k = half; k < n; ++k) a[k] = 0.5 * (b[k] + b[k - half]);
  }
  constexpr int kCurves = 6;
  const double* curve[kCurves] = {br, br + n, br + 2 * n, mr, mr + n, mr + 2 * n};
  const int whole = n - n % kSumLanes;
  // Eight lanes as one GCC vector (one AVX-512 register, two AVX2 or four SSE2 ones: the same
  // lane-by-lane adds on every target), the curves innermost: six independent chains, so the adds
  // overlap instead of waiting for each other.
  typedef double Lanes __attribute__((vector_size(kSumLanes * sizeof(double))));
  Lanes sum[kCurves] = {}, ss[kCurves] = {};
  for (int k = 0; k < whole; k += kSumLanes)
    for (int c = 0; c < kCurves; ++c) {
      Lanes v;
      std::memcpy(&v, curve[c] + k, sizeof v);
      sum[c] += v;
    }
  for (int c = 0; c < kCurves; ++c) {
    double s[kSumLanes];
    for (int j = 0; j < kSumLanes; ++j) s[j] = sum[c][j];
    for (int k = whole; k < n; ++k) s[k - whole] += curve[c][k];
    m.mean[c] = combine_lanes(s) / static_cast<double>(n);
  }
  Lanes mean[kCurves];
  for (int c = 0; c < kCurves; ++c)
    for (int j = 0; j < kSumLanes; ++j) mean[c][j] = m.mean[c];
  for (int k = 0; k < whole; k += kSumLanes)
    for (int c = 0; c < kCurves; ++c) {
      Lanes d;
      std::memcpy(&d, curve[c] + k, sizeof d);
      d -= mean[c];
      ss[c] += d * d;
    }
  for (int c = 0; c < kCurves; ++c) {
    double s[kSumLanes];
    for (int j = 0; j < kSumLanes; ++j) s[j] = ss[c][j];
    for (int k = whole; k < n; ++k) s[k - whole] += (curve[c][k] - m.mean[c]) * (curve[c][k] - m.mean[c]);
    m.sd[c] = std::sqrt(combine_lanes(s) / static_cast<double>(n));
  }
}

__attribute__((target("avx512f"))) void curves_and_moments_avx512(const Rig& rig, double* br, double* mr, int n,
                                                                 CurveMoments& m) {
  curves_and_moments(rig, br, mr, n, m);
}

__attribute__((target("avx2"))) void curves_and_moments_avx2(const Rig& rig, double* br, double* mr, int n,
                                                             CurveMoments& m) {
  curves_and_moments(rig, br, mr, n, m);
}
void curves_and_moments_baseline(const Rig& rig, double* br, double* mr, int n, CurveMoments& m) {
  curves_and_moments(rig, br, mr, n, m);
}

// eq6_constant_V of the three pairs, the same values, from one call to the light.
std::array<double, 3> eq6_constants_V(const Rig& rig) {
  std::array<double, 3> v;
  v.fill(std::numeric_limits<double>::quiet_NaN());
  if (!rig.light->has(Source::kClosedFormEq6)) return v;
  const std::array<double, 3> log_ratio = rig.light->eq6_log_ratios(rig.source_view());
  for (int i = 0; i < 3; ++i)
    v[i] = 2.0 * rig.device.truth.kv[i] * rig.electronics.volts_per_decade * log_ratio[i];
  return v;
}

CsSummary summary_of(const Rig& rig, const CurveMoments& m) {
  const std::array<double, 3> eq6 = eq6_constants_V(rig);
  CsSummary s;
  for (int i = 0; i < 3; ++i)
    s[i] = {m.sd[i] * 1e3, m.sd[3 + i] * 1e3, m.mean[i] * 1e3, m.mean[3 + i] * 1e3, eq6[i] * 1e3};
  return s;
}

// The summary of curves computed elsewhere (the mean curves over shifts), as mean_and_population_sd gives it.
CsSummary summarise(const Rig& rig, const double* br, const double* mr, int n) {
  CurveMoments m;
  for (int c = 0; c < 6; ++c) {
    const double* curve = c < 3 ? br + c * n : mr + (c - 3) * n;
    const auto [mean, sd] = mean_and_population_sd({curve, static_cast<std::size_t>(n)});
    m.mean[c] = mean;
    m.sd[c] = sd;
  }
  return summary_of(rig, m);
}

}  // namespace

namespace {

// One estimate of the turn from irradiances E[m·n + k] (when null, the source's own
// ln(E_j/E_h) over the turn: a source with a uniform reference and one shift): ΔV_br and ΔV_mr
// into scratch, and their summary.
CsSummary one_pass(const Rig& rig, const CsTurn& turn, const double* E, std::vector<double>& scratch) {
  const int n = turn.steps();
  scratch.resize(static_cast<std::size_t>(6 * n));
  double* br = scratch.data();
  double* mr = br + 3 * n;
  if (E)
    pair_log_ratios(E, n, br);
  else
    rig.light->log_ratio_over_turn(rig.source_view(), turn, {br, static_cast<std::size_t>(3 * n)});
  CurveMoments m;
  (avx512_paths() ? curves_and_moments_avx512
                  : avx2_paths() ? curves_and_moments_avx2 : curves_and_moments_baseline)(rig, br, mr, n, m);
  return summary_of(rig, m);
}

// The standard errors of the per-shift figures, into `out`.
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

// A source with several shifts, or without a uniform reference: the figures of the curves
// averaged over the shifts (their sampling noise reduced by √shifts), with the standard errors
// of the per-shift figures; ΔV refers to the coaxial rig's irradiances at the same pose
// (ideal_irradiance) when the source has no uniform reference.
CsSummary shifted_summary(const Rig& rig, const CsTurn& turn, std::vector<double>& scratch,
                          std::vector<double>* mean_curves, CsSummary* coaxial_summary,
                          const Progress& progress = {}) {
  const Source& light = *rig.light;
  const int n = turn.steps(), S = light.shifts();
  const bool coaxial_reference = !light.has(Source::kUniformReference);
  const std::size_t block = static_cast<std::size_t>(6 * n);
  std::vector<double> mean(block, 0.0), coaxial_mean(mean.size(), 0.0);
  std::vector<std::vector<double>> curves;  // per shift, for the standard errors per pose
  std::vector<CsSummary> per_shift;
  // ΔV refers to the coaxial rig's voltages at the same pose (ideal_irradiance): Eq. 5's bias of
  // the eccentric rig less that of the coaxial one, log10 of the ratio of ratios.
  light.prepare(progress);
  std::vector<double> E(block * static_cast<std::size_t>(S)), E_ideal;
  if (coaxial_reference) {
    progress.begin("study cs: channels at every pose, eccentric and coaxial", 2 * 6 * n);
    light.irradiance_over_turn(rig.source_view(), turn, E, progress);
    const Rig c = coaxial(rig);
    E_ideal.resize(E.size());
    light.irradiance_over_turn(c.source_view(), turn, E_ideal, progress);
  } else {
    progress.begin("study cs: channels at every pose", 6 * n);
    light.irradiance_over_turn(rig.source_view(), turn, E, progress);
  }
  progress.finish();
  for (int k = 0; k < S; ++k) {
    double* e = E.data() + static_cast<std::size_t>(k) * block;
    if (coaxial_reference) {
      const double* ideal = E_ideal.data() + static_cast<std::size_t>(k) * block;
      if (coaxial_summary) {  // the coaxial rig against the uniform light of the nominal model
        one_pass(rig, turn, ideal, scratch);
        for (std::size_t j = 0; j < coaxial_mean.size(); ++j) coaxial_mean[j] += scratch[j] / S;
      }
      for (int i = 0; i < 3; ++i)
        for (int t = 0; t < n; ++t) {  // scale the h channel so that E_j/E_h becomes the ratio of ratios
          const std::size_t j = static_cast<std::size_t>(pair_j(i) * n + t), h = static_cast<std::size_t>(pair_h(i) * n + t);
          e[h] *= ideal[j] / ideal[h];
        }
    }
    per_shift.push_back(one_pass(rig, turn, e, scratch));
    for (std::size_t j = 0; j < mean.size(); ++j) mean[j] += scratch[j] / S;
    curves.emplace_back(scratch.begin(), scratch.begin() + 6 * n);
  }
  CsSummary out = summarise(rig, mean.data(), mean.data() + 3 * n, n);
  add_shift_standard_errors(per_shift, out);
  if (coaxial_summary && coaxial_reference)
    *coaxial_summary = summarise(rig, coaxial_mean.data(), coaxial_mean.data() + 3 * n, n);
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

// The one-estimate path: a uniform reference and one shift (cos⁴; the sweep's hot loop).
bool single_pass(const Source& light) { return light.has(Source::kUniformReference) && light.shifts() == 1; }

}  // namespace

CsSummary cs_summary(const Rig& rig, const CsTurn& turn, std::vector<double>& scratch) {
  if (single_pass(*rig.light)) return one_pass(rig, turn, nullptr, scratch);
  return shifted_summary(rig, turn, scratch, nullptr, nullptr);
}

double asd_bsd_pct(const CsPairSummary& s) {
  return s.bsd_mV > kCsRounding_mV ? 100.0 * s.asd_mV / s.bsd_mV : std::numeric_limits<double>::quiet_NaN();
}

double eq6_dev_pct(const CsPairSummary& s) {
  return std::abs(s.mean_mr_mV) > kCsRounding_mV ? 100.0 * (s.eq6_mV - s.mean_mr_mV) / s.mean_mr_mV
                                                 : std::numeric_limits<double>::quiet_NaN();
}

CsStudy cs_study(const Rig& rig, const CsTurn& turn, const Progress& progress) {
  require_instrument(rig, Instrument::kPairVoltages, "study cs");
  const int n = turn.steps();
  std::vector<double> scratch;
  CsStudy study;
  const Source& light = *rig.light;
  study.standard_errors = light.has(Source::kStandardErrors);
  study.coaxial_reference = !light.has(Source::kUniformReference);
  study.eq6 = light.has(Source::kClosedFormEq6);
  for (int k = 0; k < n; ++k) study.theta_R_deg.push_back(turn.theta_R_deg(k));
  std::vector<double> curves;
  if (single_pass(light)) {
    light.prepare(progress);
    study.summary = one_pass(rig, turn, nullptr, scratch);
    curves.assign(scratch.begin(), scratch.begin() + 6 * n);
  } else {
    study.summary = shifted_summary(rig, turn, scratch, &curves, &study.coaxial, progress);
  }
  for (int i = 0; i < 3; ++i) {
    study.dv_br_V[i].assign(curves.begin() + i * n, curves.begin() + (i + 1) * n);
    study.dv_mr_V[i].assign(curves.begin() + (3 + i) * n, curves.begin() + (4 + i) * n);
    if (!single_pass(light)) {
      study.dv_br_se_V[i].assign(curves.begin() + (6 + i) * n, curves.begin() + (7 + i) * n);
      study.dv_mr_se_V[i].assign(curves.begin() + (9 + i) * n, curves.begin() + (10 + i) * n);
    }
  }
  return study;
}

double eq6_constant_V(const Rig& rig, int pair) {
  if (!rig.light->has(Source::kClosedFormEq6)) return std::numeric_limits<double>::quiet_NaN();
  return 2.0 * rig.device.truth.kv[pair] * rig.electronics.volts_per_decade *
         rig.light->eq6_log_ratio(rig.source_view(), pair);
}

}  // namespace polrig
