#include "polrig/report/calibration_reports.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "polrig/calib/model.h"
#include "polrig/io/csv.h"
#include "polrig/io/params_yaml.h"
#include "polrig/io/plot.h"

namespace polrig {

std::vector<DatasetFile> report_calibration(const std::filesystem::path& dir,
                                            const CalibrationResult& r,
                                            const CalibrationOptions& o, bool plots) {
  const double v_dec = o.volts_per_decade;
  write_text_file(dir / "params.yaml", params_to_yaml(r, v_dec));

  const FitParams fitted = r.fit.params;
  CsvTable points({"theta_ref_deg", "V1", "V2", "V3", "V1_model", "V2_model", "V3_model",
                   "V1_fitted", "V2_fitted", "V3_fitted"});
  for (std::size_t n = 0; n < r.points.size(); ++n) {
    const EvalPoint& p = r.points[n];
    std::vector<double> row{p.theta_ref_deg, p.V[0], p.V[1], p.V[2]};
    for (int i = 0; i < 3; ++i)
      row.push_back(eq15_voltage(fitted, v_dec, i, p.theta_ref_deg, p.d_ratio));
    for (int i = 0; i < 3; ++i) row.push_back(r.fitted[i][n] ? 1.0 : 0.0);
    points.add_row(row);
  }
  write_text_file(dir / "points.csv", points.text());

  CsvTable curve({"theta_deg", "V1_model", "V2_model", "V3_model"});
  for (int k = 0; k <= 720; ++k) {
    const double t = 0.5 * k;
    curve.add_row({t, eq15_voltage(fitted, v_dec, 0, t), eq15_voltage(fitted, v_dec, 1, t),
                   eq15_voltage(fitted, v_dec, 2, t)});
  }
  write_text_file(dir / "model_curve.csv", curve.text());

  CsvTable errors({"theta_ref_deg", "section", "err12_deg", "err13_deg", "err23_deg",
                   "errsec_deg", "d"});
  for (const AngleErrors& e : r.errors)
    errors.add_row({e.theta_ref_deg, static_cast<double>(e.section), e.e12_deg, e.e13_deg,
                    e.e23_deg, e.esec_deg, e.d});
  write_text_file(dir / "errors.csv", errors.text());

  // The angle column holds names, which CsvTable (numbers only) does not write.
  const char* names[4] = {"theta12", "theta13", "theta23", "theta_sec"};
  std::string acc_text = "angle,max_deg,min_deg,accuracy_deg\n";
  for (int k = 0; k < 4; ++k)
    acc_text += fmt::format("{},{},{},{}\n", names[k], r.accuracy[k].max_deg, r.accuracy[k].min_deg,
                            r.accuracy[k].accuracy_deg());
  write_text_file(dir / "accuracy.csv", acc_text);

  const std::vector<Replacement> rep =
      replacement_analysis(r.params, CalibrationParams::theory(o.film_axis_deg), v_dec, r.points);
  std::string rep_text = "replaced,accuracy_deg\n";
  for (const Replacement& x : rep) rep_text += fmt::format("{},{}\n", x.label, x.accuracy_deg);
  write_text_file(dir / "replacement.csv", rep_text);

  std::vector<DatasetFile> files{
      {"params.yaml", 1, "calibrated Eq. 15 parameters, standard errors and fit statistics"},
      {"points.csv", 1, "the points calibrated (raw stops or CS points), the fitted model, and "
                        "which voltages entered the fit"},
      {"model_curve.csv", 1, "the fitted Eq. 15 over 0..360° in 0.5° steps"},
      {"errors.csv", 1, "θ12, θ13, θ23 and θ_sec minus the reference angle at every point"},
      {"accuracy.csv", 1, "max, min and accuracy (half range) of each error curve"},
      {"replacement.csv", 1, "θ_sec accuracy with subsets of {α, k, kv, kd} put back to theory"}};
  if (!plots) return files;

  const std::string m(method_name(r.method));
  Plot err{"errors.png", fmt::format("Error curves after calibration ({})", m),
           "reference angle θ (°)", "error (°)"};
  err.series = {{"errors.csv", "$theta_ref_deg:$err12_deg", "θ12", "linespoints lw 1.5 pt 6 ps 0.8 lc rgb '#1f77b4'"},
                {"errors.csv", "$theta_ref_deg:$err13_deg", "θ13", "linespoints lw 1.5 pt 6 ps 0.8 lc rgb '#d62728'"},
                {"errors.csv", "$theta_ref_deg:$err23_deg", "θ23", "linespoints lw 1.5 pt 6 ps 0.8 lc rgb '#2ca02c'"},
                {"errors.csv", "$theta_ref_deg:$errsec_deg", "θ_sec", "linespoints lw 2.5 dt 2 pt 7 ps 0.9 lc rgb '#000000'"}};
  Plot fit{"fit.png", fmt::format("Calibration points and fitted Eq. 15 ({}): filled = fitted", m),
           "reference angle θ (°)", "V (mV)"};
  const char* colours[3] = {"#1f77b4", "#d62728", "#2ca02c"};
  for (int i = 0; i < 3; ++i) {
    fit.series.push_back({"model_curve.csv", fmt::format("$theta_deg:($V{}_model*1e3)", i + 1),
                          fmt::format("V{} model", i + 1),
                          fmt::format("lines lw 1.5 lc rgb '{}'", colours[i])});
    fit.series.push_back({"points.csv", fmt::format("($V{0}_fitted==1?$theta_ref_deg:NaN):($V{0}*1e3)", i + 1),
                          fmt::format("V{} fitted", i + 1),
                          fmt::format("points pt 9 ps 1.3 lc rgb '{}'", colours[i])});
    fit.series.push_back({"points.csv", fmt::format("($V{0}_fitted==0?$theta_ref_deg:NaN):($V{0}*1e3)", i + 1),
                          fmt::format("V{} not fitted", i + 1),
                          fmt::format("points pt 8 ps 1.3 lc rgb '{}'", colours[i])});
  }
  double hi = 0;
  for (const EvalPoint& p : r.points) hi = std::max(hi, p.theta_ref_deg);
  fit.extra = fmt::format("set xrange [-5:{}]", hi + 5);
  Plot repl{"replacement.png", "θ_sec accuracy with parameters replaced by theory values (Fig. 21)",
            "parameters replaced", "accuracy (°)"};
  repl.series = {{"replacement.csv", "$accuracy_deg:xtic(@replaced)", "accuracy", "boxes fill solid 0.6 lc rgb '#1f77b4'"}};
  repl.extra = "set logscale y\nset boxwidth 0.7\nset xtics rotate by -45\nset style data boxes\nset key off";
  render_plots(dir, "plots.gp", {err, fit, repl});
  files.push_back({"errors.png", 1, "error curves (Figs. 16, 19)"});
  files.push_back({"fit.png", 1, "points and fitted model (Fig. 17)"});
  files.push_back({"replacement.png", 1, "replacement analysis (Fig. 21)"});
  return files;
}

std::vector<DatasetFile> report_calibration_comparison(const std::filesystem::path& dir,
                                                       const std::vector<CalibrationResult>& results,
                                                       bool plots) {
  std::string text = "method,theta12_deg,theta13_deg,theta23_deg,theta_sec_deg\n";
  for (const CalibrationResult& r : results)
    text += fmt::format("{},{},{},{},{}\n", method_name(r.method), r.accuracy[0].accuracy_deg(),
                        r.accuracy[1].accuracy_deg(), r.accuracy[2].accuracy_deg(),
                        r.accuracy[3].accuracy_deg());
  write_text_file(dir / "comparison.csv", text);
  std::vector<DatasetFile> files{
      {"comparison.csv", 1, "accuracy (half range, degrees) of each angle for each calibration type"}};
  if (!plots) return files;
  Plot fig{"comparison.png", "Accuracy of the three calibration types (Fig. 20)",
           "calibration type", "accuracy (°)"};
  fig.series = {{"comparison.csv", "$theta12_deg:xtic(@method)", "θ12", "histograms"},
                {"comparison.csv", "$theta13_deg", "θ13", "histograms"},
                {"comparison.csv", "$theta23_deg", "θ23", "histograms"},
                {"comparison.csv", "$theta_sec_deg", "θ_sec", "histograms"}};
  fig.extra = "set logscale y\nset style histogram clustered gap 1\nset style fill solid 0.7\n"
              "set yrange [1e-4:*]";
  render_plots(dir, "plots.gp", {fig});
  files.push_back({"comparison.png", 1, "accuracy of each calibration type (Fig. 20)"});
  return files;
}

}  // namespace polrig

namespace polrig {

std::vector<DatasetFile> report_calibration_trials(const std::filesystem::path& dir,
                                                   const std::vector<Trial>& trials, bool plots) {
  std::string text =
      "trial,seed,L_IS,alpha_IS,L_S,alpha_S,acc_section_deg,acc_cs_deg,acc_cs_nc_deg\n";
  std::string failures = "trial,method,termination,iterations,evaluations,reason\n";
  bool any_failure = false;
  for (const Trial& t : trials) {
    text += fmt::format("{},{},{},{},{},{},{},{},{}\n", t.index, t.seed, t.eccentricity.L_IS,
                        t.eccentricity.alpha_IS, t.eccentricity.L_S, t.eccentricity.alpha_S,
                        t.accuracy_deg[0], t.accuracy_deg[1], t.accuracy_deg[2]);
    for (std::size_t m = 0; m < 3; ++m)
      if (!t.fit[m].usable()) {
        any_failure = true;
        std::string reason = t.fit[m].message;
        std::replace(reason.begin(), reason.end(), '"', '\'');
        failures += fmt::format("{},{},{},{},{},\"{}\"\n", t.index, method_name(kAllMethods[m]),
                                termination_name(t.fit[m].termination), t.fit[m].iterations,
                                t.fit[m].evaluations, reason);
      }
  }
  write_text_file(dir / "trials.csv", text);
  std::string summary = "method,succeeded,failed,median_deg,p05_deg,p95_deg,mean_deg";
  for (FitTermination k : kAllTerminations) summary += fmt::format(",{}", termination_name(k));
  summary += "\n";
  for (const TrialSummary& s : summarize_trials(trials)) {
    summary += fmt::format("{},{},{},{},{},{},{}", method_name(s.method), s.succeeded, s.failed,
                           s.median_deg, s.p05_deg, s.p95_deg, s.mean_deg);
    for (int count : s.terminations) summary += fmt::format(",{}", count);
    summary += "\n";
  }
  write_text_file(dir / "summary.csv", summary);
  std::vector<DatasetFile> files{
      {"trials.csv", 1, "per trial: seed, eccentricity and the θ_sec accuracy of each type"},
      {"summary.csv", 1, "per type: median, 5% and 95% quantiles and mean of the accuracy, and how "
                         "many fits ended in each termination type"}};
  if (any_failure) {
    write_text_file(dir / "failures.csv", failures);
    files.push_back({"failures.csv", 2, "calibrations whose fit is not usable: termination type, "
                                        "iterations, evaluations and the reason"});
  }

  // Empirical distribution: each column sorted on its own (failed trials left out).
  std::array<std::vector<double>, 3> sorted;
  for (const Trial& t : trials)
    for (std::size_t m = 0; m < 3; ++m)
      if (!std::isnan(t.accuracy_deg[m])) sorted[m].push_back(t.accuracy_deg[m]);
  for (auto& v : sorted) std::sort(v.begin(), v.end());
  std::string cdf = "fraction,section_deg,cs_deg,cs_nc_deg\n";
  const std::size_t n = trials.size();
  for (std::size_t k = 0; k < n; ++k) {
    cdf += fmt::format("{}", (static_cast<double>(k) + 0.5) / static_cast<double>(n));
    for (std::size_t m = 0; m < 3; ++m)
      cdf += k < sorted[m].size() ? fmt::format(",{}", sorted[m][k]) : std::string(",nan");
    cdf += "\n";
  }
  write_text_file(dir / "cdf.csv", cdf);
  files.push_back({"cdf.csv", 1, "empirical distribution of the accuracy of each type"});
  if (!plots || n == 0) return files;
  Plot fig{"accuracy_cdf.png",
           fmt::format("Accuracy of θ_sec over {} Monte-Carlo calibrations", n),
           "accuracy, half range of the θ_sec error (°)", "fraction of trials"};
  fig.series = {{"cdf.csv", "$section_deg:$fraction", "type 1: section", "steps lw 2 lc rgb '#7f7f7f'"},
                {"cdf.csv", "$cs_deg:$fraction", "type 2: CS + section", "steps lw 2 lc rgb '#1f77b4'"},
                {"cdf.csv", "$cs_nc_deg:$fraction", "type 3: CS + noncontinuous + section", "steps lw 2 lc rgb '#d62728'"}};
  fig.extra = "set logscale x\nset yrange [0:1]";
  render_plots(dir, "plots.gp", {fig});
  files.push_back({"accuracy_cdf.png", 1, "distribution of the accuracy of each type"});
  return files;
}

}  // namespace polrig
