#include "polrig/report/reports.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "polrig/io/csv.h"
#include "polrig/io/dataset.h"
#include "polrig/io/plot.h"
#include "pair_style.h"

namespace polrig {

std::vector<DatasetFile> report_simulation(const std::filesystem::path& dir,
                                           const Simulation& sim, bool plots) {
  std::vector<DatasetFile> files = write_simulation(dir, sim);
  if (!plots) return files;
  Plot volts{"voltages.png", "Pair voltages over the schedule", "table angle θ_R (°)",
             "V_i (mV)"};
  Plot dev{"deviations.png", "Eccentricity deviation V_i - V_i,ideal (Eq. 5)",
           "table angle θ_R (°)", "ΔV_i (mV)"};
  for (int i = 1; i <= 3; ++i) {
    volts.series.push_back({"stops.csv", fmt::format("$theta_R_deg:($V{}_ideal*1e3)", i),
                            fmt::format("V{} ideal", i), line_style(i - 1)});
    volts.series.push_back({"stops.csv", fmt::format("$theta_R_deg:($V{}*1e3)", i),
                            fmt::format("V{} measured", i),
                            fmt::format("points pt 7 ps 0.8 lc rgb '{}'", kPairColour[i - 1])});
    dev.series.push_back({"stops.csv", fmt::format("$theta_R_deg:(($V{0}_ecc-$V{0}_ideal)*1e3)", i),
                          fmt::format("ΔV{0} = V{0},ecc - V{0},ideal", i),
                          fmt::format("linespoints lw 2 pt 7 ps 0.6 lc rgb '{}'", kPairColour[i - 1])});
    dev.series.push_back({"stops.csv", fmt::format("$theta_R_deg:(($V{0}-$V{0}_ideal)*1e3)", i),
                          fmt::format("V{0} measured - V{0},ideal", i),
                          fmt::format("points pt 6 ps 1 lc rgb '{}'", kPairColour[i - 1])});
  }
  render_plots(dir, "plots.gp", {volts, dev});
  files.push_back({"voltages.png", 1, "pair voltages, ideal and measured, against θ_R"});
  files.push_back({"deviations.png", 1, "eccentricity deviations against θ_R"});
  return files;
}

std::vector<DatasetFile> report_cs_study(const std::filesystem::path& dir, const CsStudy& study,
                                         bool plots) {
  std::vector<std::string> dev_columns{"theta_R_deg", "pair", "dv_br_mV", "dv_mr_mV"};
  if (study.standard_errors) dev_columns.insert(dev_columns.end(), {"dv_br_stderr_mV", "dv_mr_stderr_mV"});
  CsvTable dev(dev_columns);
  // Pair-major, so that each pair's rows are contiguous (and plot as one line).
  for (int i = 0; i < 3; ++i)
    for (std::size_t k = 0; k < study.theta_R_deg.size(); ++k) {
      std::vector<double> row{study.theta_R_deg[k], static_cast<double>(i + 1), study.dv_br_V[i][k] * 1e3,
                              study.dv_mr_V[i][k] * 1e3};
      if (study.standard_errors) row.insert(row.end(), {study.dv_br_se_V[i][k] * 1e3, study.dv_mr_se_V[i][k] * 1e3});
      dev.add_row(row);
    }
  write_text_file(dir / "deviations.csv", dev.text());

  std::vector<std::string> columns{"pair", "bsd_mV", "asd_mV", "mean_br_mV", "mean_mr_mV", "eq6_mV"};
  if (study.standard_errors)
    for (const char* c : {"bsd_stderr_mV", "asd_stderr_mV", "mean_br_stderr_mV", "mean_mr_stderr_mV"})
      columns.emplace_back(c);
  if (study.coaxial_reference)
    for (const char* c : {"coaxial_bsd_mV", "coaxial_asd_mV", "coaxial_mean_br_mV"}) columns.emplace_back(c);
  CsvTable summary(columns);
  if (!study.eq6) summary.allow_undefined("eq6_mV");  // no closed form for this source
  for (int i = 0; i < 3; ++i) {
    const CsPairSummary& s = study.summary[i];
    std::vector<double> row{static_cast<double>(i + 1), s.bsd_mV, s.asd_mV, s.mean_br_mV, s.mean_mr_mV, s.eq6_mV};
    const CsPairSummary& c = study.coaxial[i];
    if (study.standard_errors) row.insert(row.end(), {s.bsd_se_mV, s.asd_se_mV, s.mean_br_se_mV, s.mean_mr_se_mV});
    if (study.coaxial_reference) row.insert(row.end(), {c.bsd_mV, c.asd_mV, c.mean_br_mV});
    summary.add_row(row);
  }
  write_text_file(dir / "summary.csv", summary.text());
  std::vector<DatasetFile> files{
      {"deviations.csv", 1, "ΔV before (br) and after (mr) central symmetry over a full turn"},
      {"summary.csv", 1, "per pair: BSD, ASD, expectations and Eq. 6's constant"}};
  if (!plots) return files;

  // Fig. 8a-like: pair 1 before, after 180° and the CS average; Fig. 9-like: all pairs.
  Plot pair1{"cs_pair1.png", "Pair 1: deviation before and after 180° rotation, and CS average",
             "table angle θ_R (°)", "ΔV_1 (mV)"};
  pair1.series = {
      {"deviations.csv", "$theta_R_deg:($pair==1?$dv_br_mV:NaN)", "V1br - V1ideal", "lines lw 2 lc rgb '#1f77b4'"},
      {"deviations.csv", "$theta_R_deg:($pair==1?2*$dv_mr_mV-$dv_br_mV:NaN)", "V1ar - V1ideal", "lines lw 2 lc rgb '#ff7f0e'"},
      {"deviations.csv", "$theta_R_deg:($pair==1?$dv_mr_mV:NaN)", "V1mr - V1ideal (CS)", "lines lw 3 lc rgb '#000000'"}};
  if (study.standard_errors) {  // ± one standard error of the sampled source
    pair1.series[0].using_ += ":$dv_br_stderr_mV";
    pair1.series[0].style = "yerrorlines lw 2 pt 7 ps 0.3 lc rgb '#1f77b4'";
    pair1.series[2].using_ += ":$dv_mr_stderr_mV";
    pair1.series[2].style = "yerrorlines lw 3 pt 7 ps 0.3 lc rgb '#000000'";
    pair1.title += " (± 1 standard error)";
  }
  pair1.extra = "set xrange [0:360]\nset xtics 45";
  Plot all{"cs_deviations.png", "Deviations of the three pairs: before CS (dashed), after CS (solid)",
           "table angle θ_R (°)", "ΔV_i (mV)"};
  if (study.standard_errors) all.title += " (± 1 standard error)";
  for (int i = 0; i < 3; ++i) {
    // A sampled (traced) source: each deviation ± its standard error.
    const auto with_errors = [&](const char* value, const char* error, const char* dash) {
      return study.standard_errors
                 ? PlotSeries{"deviations.csv", fmt::format("$theta_R_deg:($pair=={}?{}:NaN):{}", i + 1, value, error), "",
                              fmt::format("yerrorlines lw 2 pt 7 ps 0.3 {} lc rgb '{}'", dash, kPairColour[i])}
                 : PlotSeries{"deviations.csv", fmt::format("$theta_R_deg:($pair=={}?{}:NaN)", i + 1, value), "",
                              line_style(i, dash)};
    };
    all.series.push_back(with_errors("$dv_br_mV", "$dv_br_stderr_mV", "dt 2"));
    all.series.back().title = fmt::format("ΔV{} br", i + 1);
    all.series.push_back(with_errors("$dv_mr_mV", "$dv_mr_stderr_mV", ""));
    all.series.back().title = fmt::format("ΔV{} mr (CS)", i + 1);
  }
  all.extra = "set xrange [0:360]\nset xtics 45";
  render_plots(dir, "plots.gp", {pair1, all});
  files.push_back({"cs_pair1.png", 1, "pair 1 before/after rotation and CS average (Fig. 8a)"});
  files.push_back({"cs_deviations.png", 1, "all pairs before and after CS (Fig. 9)"});
  return files;
}

std::vector<DatasetFile> report_adc_limits(const std::filesystem::path& dir,
                                           const std::vector<AdcLimit>& limits, bool plots) {
  CsvTable table({"d", "vmax_mV", "limit_deg"});
  for (const AdcLimit& l : limits) table.add_row({l.d, l.vmax_mV, l.limit_deg});
  write_text_file(dir / "accuracy_limit.csv", table.text());
  std::vector<DatasetFile> files{
      {"accuracy_limit.csv", 1, "per d: the largest pair voltage and the ADC accuracy limit"}};
  if (!plots) return files;
  Plot fig{"accuracy_limit.png", "ADC accuracy limit of θ12 and maximum voltage (Fig. 6)",
           "degree of polarization d", "accuracy limit (°)", "max V (mV)"};
  fig.series = {{"accuracy_limit.csv", "$d:$limit_deg", "accuracy limit", "linespoints lw 2 pt 7 ps 0.7"},
                {"accuracy_limit.csv", "$d:$vmax_mV", "max V", "linespoints lw 2 pt 5 ps 0.7 lc rgb '#d62728'",
                 true}};
  fig.extra = "set logscale y\nset y2range [0:*]";
  render_plots(dir, "plots.gp", {fig});
  files.push_back({"accuracy_limit.png", 1, "accuracy limit and max voltage against d"});
  return files;
}

}  // namespace polrig
