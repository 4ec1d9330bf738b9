#include "polrig/calib/pipeline.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "polrig/calib/angles.h"
#include "polrig/units.h"

namespace polrig {

std::string_view method_name(CalibrationMethod m) {
  switch (m) {
    case CalibrationMethod::Section: return "section";
    case CalibrationMethod::CentralSymmetry: return "cs";
    case CalibrationMethod::CentralSymmetryNoncontinuous: return "cs-nc";
    case CalibrationMethod::Noncontinuous: return "nc";
  }
  return "?";
}

std::optional<CalibrationMethod> parse_method(std::string_view name) {
  for (CalibrationMethod m : kAllMethods)
    if (method_name(m) == name) return m;
  if (name == method_name(CalibrationMethod::Noncontinuous)) return CalibrationMethod::Noncontinuous;
  return std::nullopt;
}

bool uses_raw_stops(CalibrationMethod m) {
  return m == CalibrationMethod::Section || m == CalibrationMethod::Noncontinuous;
}

namespace {

std::vector<Observation> observations_of(const std::vector<EvalPoint>& points) {
  std::vector<Observation> obs;
  for (std::size_t n = 0; n < points.size(); ++n)
    for (int i = 0; i < 3; ++i)
      obs.push_back({points[n].theta_ref_deg, i, points[n].V[i], n, points[n].d_ratio});
  return obs;
}

// The start value of c, from how much the voltages swing: an ideal pair spans
// ±v_dec·log10[(1 + d)/(1 − d)], so half the range of V_i gives d_i = (10^(A/v) − 1)/(10^(A/v) + 1).
// The median over the three pairs; offsets k_i do not enter, and unpolarized light gives ~0.
// A swing too large for double precision (10^(A/v) overflows) gives d = 1, not NaN.
struct StartEstimate {
  double d;
  int pair;         // the median pair
  double swing_V;   // its peak-to-peak voltage
};
StartEstimate estimate_d(const std::vector<EvalPoint>& points, const CalibrationOptions& o) {
  std::array<StartEstimate, 3> d{};
  for (int i = 0; i < 3; ++i) {
    double lo = points.front().V[i], hi = lo;
    for (const EvalPoint& p : points) lo = std::min(lo, p.V[i]), hi = std::max(hi, p.V[i]);
    const double a = std::pow(10.0, 0.5 * (hi - lo) / o.volts_per_decade);
    d[i] = {std::isinf(a) ? 1.0 : (a - 1.0) / (a + 1.0), i, hi - lo};
  }
  std::sort(d.begin(), d.end(), [](const auto& x, const auto& y) { return x.d < y.d; });
  return d[1];
}

FitSummary failed_before_fit(FitTermination t, std::string message, std::size_t observations) {
  FitSummary s;
  s.termination = t;
  s.message = std::move(message);
  s.observations = static_cast<int>(observations);
  return s;
}

}  // namespace

std::vector<AngleErrors> angle_errors(const CalibrationParams& p, double v_dec,
                                      const std::vector<EvalPoint>& points) {
  Electronics e;
  e.volts_per_decade = v_dec;
  std::vector<AngleErrors> out;
  for (const EvalPoint& pt : points) {
    const SensorAngles a = sensor_angles(p, e, pt.V);
    const double ref = pt.theta_ref_deg;
    const int bad = bad_voltage_of(a.section);
    const double d = bad == 0 ? a.theta23.d : bad == 1 ? a.theta13.d : a.theta12.d;
    out.push_back({ref, axis_difference_deg(a.theta12.theta_deg, ref),
                   axis_difference_deg(a.theta13.theta_deg, ref),
                   axis_difference_deg(a.theta23.theta_deg, ref),
                   axis_difference_deg(a.theta_sec_deg, ref), a.section, d});
  }
  return out;
}

std::array<AngleAccuracy, 4> accuracy_of(const std::vector<AngleErrors>& errors) {
  std::array<AngleAccuracy, 4> acc;
  for (int k = 0; k < 4; ++k) {
    acc[k].max_deg = -1e300;
    acc[k].min_deg = 1e300;
  }
  for (const AngleErrors& e : errors) {
    const double v[4] = {e.e12_deg, e.e13_deg, e.e23_deg, e.esec_deg};
    for (int k = 0; k < 4; ++k) {
      acc[k].max_deg = std::max(acc[k].max_deg, v[k]);
      acc[k].min_deg = std::min(acc[k].min_deg, v[k]);
    }
  }
  return acc;
}

CalibrationResult calibrate(const std::vector<StopVoltages>& stops, const CalibrationOptions& o) {
  if (!(std::isfinite(o.volts_per_decade) && o.volts_per_decade > 0))
    throw CalibrationError(fmt::format("volts_per_decade = {}: expected a finite gain > 0",
                                       o.volts_per_decade));
  const bool raw_stops = uses_raw_stops(o.method);
  const StopCorrections& corr = o.corrections;
  if (!corr.empty() && !raw_stops)
    throw CalibrationError(fmt::format("per-stop drift corrections need a method on raw stops "
                                       "(section or nc), not {}: a CS point mixes two times",
                                       method_name(o.method)));
  for (const std::vector<double>* v : {&corr.dtheta_deg, &corr.d_ratio})
    if (!v->empty() && v->size() != stops.size())
      throw CalibrationError(fmt::format("{} per-stop corrections for {} stops", v->size(),
                                         stops.size()));
  CalibrationResult r;
  r.method = o.method;
  r.drift = corr.source;
  if (raw_stops) {
    for (std::size_t k = 0; k < stops.size(); ++k) {
      EvalPoint p{stops[k].theta_R_deg, stops[k].V};
      if (!corr.dtheta_deg.empty()) p.theta_ref_deg += corr.dtheta_deg[k];
      if (!corr.d_ratio.empty()) p.d_ratio = corr.d_ratio[k];
      if (!(std::isfinite(p.theta_ref_deg) && std::isfinite(p.d_ratio) && p.d_ratio > 0.0))
        throw CalibrationError(fmt::format("{}: the drift correction (Δθ = {}°, d ratio {}) is "
                                           "not finite, or the ratio not > 0", stops[k].label,
                                           corr.dtheta_deg.empty() ? 0.0 : corr.dtheta_deg[k],
                                           p.d_ratio));
      r.points.push_back(p);
    }
  } else {
    for (const CsPoint& p : central_symmetry_points(stops)) r.points.push_back({p.theta_R_deg, p.V});
  }
  if (r.points.size() < 6) {
    r.fit.summary = failed_before_fit(
        FitTermination::TooFewObservations,
        fmt::format("{} {} to fit; Eq. 15 has 6 unknowns per pair, so at least 6 are needed",
                    r.points.size(), raw_stops ? "stops" : "CS points"),
        3 * r.points.size());
    return r;
  }

  const StartEstimate d0 = estimate_d(r.points, o);
  if (!(d0.d < 1.0)) {
    r.fit.summary = failed_before_fit(
        FitTermination::OutsideDomain,
        fmt::format("V{} swings by {:.6g} V, {:.3g} decades of light ratio at {} V per decade: more "
                    "than any degree of polarization below 1 can give (check the voltage columns "
                    "and volts_per_decade)",
                    d0.pair + 1, d0.swing_V, d0.swing_V / o.volts_per_decade, o.volts_per_decade),
        3 * r.points.size());
    return r;
  }
  if (!(d0.d >= 0.02)) {
    r.fit.summary = failed_before_fit(
        FitTermination::RankDeficient,
        fmt::format("the light's degree of polarization is about {:.3g} (V{} swings by {:.3g} V): "
                    "too small to calibrate (the angle signal vanishes as d → 0; at least 0.02 is "
                    "needed)", d0.d, d0.pair + 1, d0.swing_V),
        3 * r.points.size());
    return r;
  }
  const FitParams start = FitParams::coupled(CalibrationParams::theory(o.film_axis_deg), d0.d);

  const std::vector<Observation> all = observations_of(r.points);
  std::vector<Observation> used = all;
  if (o.method == CalibrationMethod::CentralSymmetryNoncontinuous ||
      o.method == CalibrationMethod::Noncontinuous) {
    // Slopes from a preliminary fit of all points, so that the selection does not depend on
    // how the table zero sits against the port polarizer (or the sky's E-vector).
    const FitResult preliminary = fit_eq15(all, start, o.volts_per_decade, o.fit);
    if (!preliminary.summary.usable()) {
      r.fit = preliminary;
      r.fit.summary.message = fmt::format("the preliminary fit of all {}: {}",
                                          raw_stops ? "stops" : "CS points", r.fit.summary.message);
      return r;
    }
    used = select_noncontinuous(all, preliminary.params, o.volts_per_decade, o.noncontinuous);
  }
  r.fit = fit_eq15(used, start, o.volts_per_decade, o.fit);
  if (!r.fit.summary.usable()) return r;

  r.fitted.assign(3, std::vector<bool>(r.points.size(), false));
  for (const Observation& ob : used) r.fitted[static_cast<std::size_t>(ob.pair)][ob.row] = true;

  if (o.d_a) {
    r.d_a = *o.d_a;
    r.d_a_source = o.d_a_source;
  } else {
    r.d_a = *std::max_element(r.fit.params.c.begin(), r.fit.params.c.end());
    r.d_a_source = "max c_m (the best film taken as ideal, kd = 0)";
  }
  if (!(r.d_a > 0.0 && r.d_a < 1.0)) {  // a fit whose best film polarizes fully or not at all
    r.fit.summary.termination = FitTermination::OutsideDomain;
    r.fit.summary.message = fmt::format("d_a = {} ({}) is outside (0, 1)", r.d_a, r.d_a_source);
    return r;
  }
  r.params = r.fit.params.decoupled(r.d_a);
  r.standard_error.alpha_deg = r.fit.standard_error.alpha_deg;
  r.standard_error.k_mV = r.fit.standard_error.k_mV;
  r.standard_error.kv = r.fit.standard_error.kv;
  for (int m = 0; m < 6; ++m) r.standard_error.kd[m] = r.fit.standard_error.c[m] / r.d_a;

  r.errors = angle_errors(r.params, o.volts_per_decade, r.points);
  r.accuracy = accuracy_of(r.errors);
  return r;
}

std::vector<Replacement> replacement_analysis(const CalibrationParams& calibrated,
                                              const CalibrationParams& theory, double v_dec,
                                              const std::vector<EvalPoint>& points) {
  static const char* const kNames[4] = {"α", "k", "kv", "kd"};
  std::vector<Replacement> out;
  for (unsigned mask = 0; mask < 16; ++mask) {
    CalibrationParams p = calibrated;
    if (mask & 1u) p.alpha_deg = theory.alpha_deg;
    if (mask & 2u) p.k_mV = theory.k_mV;
    if (mask & 4u) p.kv = theory.kv;
    if (mask & 8u) p.kd = theory.kd;
    std::string label;
    for (int b = 0; b < 4; ++b) {
      if (!(mask & (1u << b))) continue;
      if (!label.empty()) label += '-';
      label += kNames[b];
    }
    if (label.empty()) label = "none";
    out.push_back({label, mask, accuracy_of(angle_errors(p, v_dec, points))[kThetaSec].accuracy_deg()});
  }
  return out;
}

}  // namespace polrig
