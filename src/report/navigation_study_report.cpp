#include "polrig/report/navigation_study_report.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

#include <fmt/format.h>

#include "polrig/io/csv.h"
#include "polrig/io/plot.h"
#include "csv_cells.h"

namespace polrig {

namespace {

constexpr const char* kQuantiles[] = {"p05", "p25", "p50", "p75", "p95"};

std::string percentile_cells(const Percentiles& p, const char* prefix, const char* unit, std::size_t row) {
  std::string out;
  const double v[] = {p.p05, p.p25, p.p50, p.p75, p.p95};
  for (int i = 0; i < 5; ++i) {
    const std::string column = fmt::format("{}_{}_{}", prefix, kQuantiles[i], unit);
    (out += ',') += checked_cell(v[i], column.c_str(), row, true);
  }
  return out;
}

std::string percentile_header(const char* prefix, const char* unit) {
  std::string out;
  for (const char* q : kQuantiles) out += fmt::format(",{}_{}_{}", prefix, q, unit);
  return out;
}

// One colour per mode, in NavigationMode's order (SINS, PNS, integrated, smoothed).
const char* colour(NavigationMode m) {
  switch (m) {
    case NavigationMode::Sins: return "#d62728";
    case NavigationMode::Pns: return "#2ca02c";
    case NavigationMode::Integrated: return "#1f77b4";
    case NavigationMode::Smoothed: return "#9467bd";
  }
  return "black";
}

}  // namespace

std::vector<DatasetFile> report_navigation_study(const std::filesystem::path& dir, const NavigationStudy& study,
                                                 bool plots) {
  const auto cell_cells = [&](const NavigationStudyCell& c, std::size_t row) {
    return fmt::format("{},{},{},{},{}", c.index, c.factor, c.key, checked_cell(c.value, "value", row, true),
                       checked_cell(c.duration_s, "duration_s", row));
  };

  std::string trials =
      "cell,factor,key,value,duration_s,trial,seed,mode,final_t_s,final_north_m,final_east_m,final_error_m,"
      "lat_mae_deg,lat_rmse_deg,lat_std_deg,lon_mae_deg,lon_rmse_deg,lon_std_deg,fixes,mean_nis,updates,"
      "nees_position,nees_attitude,final_heading_error_deg\n";
  for (std::size_t i = 0; i < study.trials.size(); ++i) {
    const NavigationTrialResult& t = study.trials[i];
    trials += cell_cells(study.cells[static_cast<std::size_t>(t.cell)], i);
    trials += fmt::format(",{},{},{}", t.trial, t.seed, navigation_mode_name(t.mode));
    for (auto [v, name] : {std::pair{t.final_t_s, "final_t_s"}, {t.final_north_m, "final_north_m"},
                           {t.final_east_m, "final_east_m"}, {t.final_error_m, "final_error_m"},
                           {t.lat_deg.mae, "lat_mae_deg"}, {t.lat_deg.rmse, "lat_rmse_deg"},
                           {t.lat_deg.std, "lat_std_deg"}, {t.lon_deg.mae, "lon_mae_deg"},
                           {t.lon_deg.rmse, "lon_rmse_deg"}, {t.lon_deg.std, "lon_std_deg"}})
      (trials += ',') += checked_cell(v, name, i, true);
    trials += fmt::format(",{},{},{},{},{},{}\n", t.lat_deg.count, checked_cell(t.filter_nis_mean, "mean_nis", i, true),
                          t.filter_updates, checked_cell(t.nees_position, "nees_position", i, true),
                          checked_cell(t.nees_attitude, "nees_attitude", i, true),
                          checked_cell(t.final_heading_error_deg, "final_heading_error_deg", i, true));
  }

  std::string summary = "cell,factor,key,value,duration_s,mode,trials,finite" +
                        percentile_header("final", "m") + percentile_header("lat_mae", "deg") +
                        percentile_header("lon_mae", "deg") + "\n";
  for (std::size_t i = 0; i < study.summary.size(); ++i) {
    const NavigationStudySummary& s = study.summary[i];
    summary += cell_cells(study.cells[static_cast<std::size_t>(s.cell)], i);
    summary += fmt::format(",{},{},{}", navigation_mode_name(s.mode), s.trials, s.final_error_m.count);
    summary += percentile_cells(s.final_error_m, "final", "m", i) + percentile_cells(s.lat_mae_deg, "lat_mae", "deg", i) +
               percentile_cells(s.lon_mae_deg, "lon_mae", "deg", i) + "\n";
  }

  std::string time = "t_s";
  for (const NavigationErrorBand& b : study.bands) {
    const std::string prefix(navigation_mode_name(b.mode));
    time += percentile_header(prefix.c_str(), "m");
  }
  time += "\n";
  const std::size_t epochs = study.bands.empty() ? 0 : study.bands[0].t_s.size();
  for (std::size_t k = 0; k < epochs; ++k) {
    time += checked_cell(study.bands[0].t_s[k], "t_s", k);
    for (const NavigationErrorBand& b : study.bands) {
      const std::string prefix(navigation_mode_name(b.mode));
      time += percentile_cells(b.error_m[k], prefix.c_str(), "m", k);
    }
    time += "\n";
  }

  std::string tilt =
      "tilt_deg,draws,mean_abs_deg,sd_abs_deg,se_mean_deg,rms_deg,max_abs_deg,first_order_deg,exact_deg,"
      "mean_elevation_deg,z21_deg\n";
  for (std::size_t i = 0; i < study.tilt.size(); ++i) {
    const TiltErrorRow& r = study.tilt[i];
    const double se = r.draws > 0 ? r.sd_abs_deg / std::sqrt(static_cast<double>(r.draws)) : NAN;
    tilt += fmt::format("{},{}", checked_cell(r.tilt_deg, "tilt_deg", i), r.draws);
    for (auto [v, name] : {std::pair{r.mean_abs_deg, "mean_abs_deg"}, {r.sd_abs_deg, "sd_abs_deg"},
                           {se, "se_mean_deg"}, {r.rms_deg, "rms_deg"}, {r.max_abs_deg, "max_abs_deg"},
                           {r.first_order_deg, "first_order_deg"}, {r.exact_deg, "exact_deg"},
                           {study.tilt_mean_elevation_deg, "mean_elevation_deg"}, {r.z21_deg, "z21_deg"}})
      (tilt += ',') += checked_cell(v, name, i, true);
    tilt += "\n";
  }

  std::string dop = "dop_lo,dop_hi,count,mean_abs_deg,sd_abs_deg,mean_true_dop,z21_mean_deg,z21_sd_deg\n";
  for (std::size_t i = 0; i < study.dop.size(); ++i) {
    const DopBin& b = study.dop[i];
    dop += fmt::format("{},{},{}", checked_cell(b.lo, "dop_lo", i), checked_cell(b.hi, "dop_hi", i), b.count);
    for (auto [v, name] : {std::pair{b.mean_abs_deg, "mean_abs_deg"}, {b.sd_abs_deg, "sd_abs_deg"},
                           {b.mean_true_dop, "mean_true_dop"}, {b.z21_mean_deg, "z21_mean_deg"},
                           {b.z21_sd_deg, "z21_sd_deg"}})
      (dop += ',') += checked_cell(v, name, i, true);
    dop += "\n";
  }

  std::string consistency = "cell,factor,key,value,duration_s,trials,quantity,dof,mean,band_lo,band_hi,inside\n";
  for (std::size_t i = 0; i < study.consistency.size(); ++i) {
    const NavigationConsistency& c = study.consistency[i];
    for (auto [b, name] : {std::pair{&c.nees_position, "nees_position"}, {&c.nees_attitude, "nees_attitude"},
                           {&c.nis, "nis"}})
      consistency += cell_cells(study.cells[static_cast<std::size_t>(c.cell)], i) +
                     fmt::format(",{},{},{},{},{},{},{}\n", c.trials, name, b->dof, checked_cell(b->mean, name, i, true),
                                 checked_cell(b->lo, "band_lo", i), checked_cell(b->hi, "band_hi", i),
                                 b->inside() ? "true" : "false");
  }

  std::string goal = "cell,factor,key,value,duration_s,trials,position_met,heading_met,both_met\n";
  for (std::size_t i = 0; i < study.goal.size(); ++i) {
    const NavigationGoal& g = study.goal[i];
    goal += cell_cells(study.cells[static_cast<std::size_t>(g.cell)], i) +
            fmt::format(",{},{},{},{}\n", g.trials, g.position_met, g.heading_met, g.both_met);
  }

  // Every table built (and checked) before the first is written.
  write_text_file(dir / "trials.csv", trials);
  write_text_file(dir / "summary.csv", summary);
  write_text_file(dir / "error_vs_time.csv", time);
  write_text_file(dir / "tilt.csv", tilt);
  write_text_file(dir / "dop.csv", dop);
  write_text_file(dir / "consistency.csv", consistency);
  if (!study.goal.empty()) write_text_file(dir / "goal.csv", goal);
  std::vector<DatasetFile> files{
      {"trials.csv", 3, "per cell (the rig, or one sweep value), trial and mode: the trial's seed, the north, east "
                        "and horizontal error at the last compass reading (m), the latitude and longitude "
                        "errors' MAE, RMSE and STD over the run (°, Z21 §5), the usable fixes and the "
                        "integrated filter's mean NIS, its scalar updates, and the NEES of its last fix's "
                        "horizontal position (2 dof) and attitude (3 dof), and the heading error at the last reading"},
      {"consistency.csv", 1, "per cell: the integrated filter's mean NEES (position, attitude) over the trials "
                             "and mean NIS over every update, with the χ² 95 % band of a consistent filter"},
      {"summary.csv", 1, "per cell and mode: the 5/25/50/75/95 % percentiles over the trials of the final "
                         "horizontal error and of the latitude and longitude MAE"},
      {"error_vs_time.csv", 1, "the rig's own trials: per compass reading, the percentiles over the trials of "
                               "each mode's horizontal position error (m)"},
      {"tilt.csv", 1, "Z21 Fig. 17: per horizontal-attitude error, the sun-elevation error |H^n(tilted) − "
                      "H^n(true)| over the rig's trials' readings (a uniform tilt direction per reading): mean, "
                      "SD, standard error of the mean, RMS, largest; the first-order (2/π)·τ and the exact "
                      "expectation at the readings' mean elevation; Z21's values"},
      {"dop.csv", 1, "Z21 Fig. 16: every unit reading of the rig's trials binned by its DoP (5 % bins): the "
                     "mean and SD of |aop − true aop| (axial, °), the mean true DoP; Z21's two bins"}};
  if (!study.goal.empty())
    files.push_back({"goal.csv", 1, "per cell: the trials (of those with a finite final error) whose integrated solution "
                                    "ends no worse than the better of SINS and PNS in horizontal position, in heading "
                                    "(SINS's; PNS has none of its own), and in both (issue 34 §3)"});
  if (!plots || study.trials.empty()) return files;

  const int n = study.settings.trials;
  std::vector<Plot> figures;
  Plot t{"error_vs_time.png",
         fmt::format("Horizontal position error against time ({} trials: median, 25–75 % and 5–95 %)", n),
         "time (min)", "horizontal position error (m)"};
  for (const NavigationErrorBand& b : study.bands) {
    const std::string m(navigation_mode_name(b.mode));
    const std::string c = colour(b.mode);
    t.series.push_back({"error_vs_time.csv", fmt::format("($t_s/60):${0}_p05_m:${0}_p95_m", m), "",
                        fmt::format("filledcurves fs transparent solid 0.12 noborder lc rgb '{}'", c)});
    t.series.push_back({"error_vs_time.csv", fmt::format("($t_s/60):${0}_p25_m:${0}_p75_m", m), "",
                        fmt::format("filledcurves fs transparent solid 0.3 noborder lc rgb '{}'", c)});
    t.series.push_back({"error_vs_time.csv", fmt::format("($t_s/60):${}_p50_m", m), m + " (median)",
                        fmt::format("lines lw 2 lc rgb '{}'", c)});
  }
  t.extra = "set logscale y\nset format y '%g'\nset key inside top left opaque";
  figures.push_back(t);

  for (const NavigationSweep& sw : navigation_sweeps()) {
    if ((study.settings.*sw.values).empty()) continue;
    Plot p{fmt::format("final_error_vs_{}.png", sw.factor),
           fmt::format("Final horizontal error against {} ({} trials per value: median, boxes 25–75 %, whiskers "
                       "5–95 %)", sw.key, n),
           std::string(sw.key), "final horizontal position error (m)"};
    for (NavigationMode mode : study.modes) {
      const std::string m(navigation_mode_name(mode));
      const std::string c = colour(mode);
      const std::string on = fmt::format("(@factor eq '{}' && @mode eq '{}' ? ", sw.factor, m);
      p.series.push_back({"summary.csv",
                          fmt::format("{0}$value : NaN):{0}$final_p25_m : NaN):{0}$final_p05_m : NaN):"
                                      "{0}$final_p95_m : NaN):{0}$final_p75_m : NaN)",
                                      on),
                          "", fmt::format("candlesticks whiskerbars lc rgb '{}' lw 1.5", c)});
      p.series.push_back({"summary.csv", fmt::format("{0}$value : NaN):{0}$final_p50_m : NaN)", on), m + " (median)",
                          fmt::format("points pt 7 ps 1.2 lc rgb '{}'", c)});
    }
    p.extra = "set logscale y\nset format y '%g'\nset key below horizontal\nset offsets graph 0.05, graph 0.05, 0, 0";
    figures.push_back(p);
  }

  // A figure only with something to draw (gnuplot refuses a plot whose every point is undefined).
  bool tilt_points = false, dop_points = false;
  for (const TiltErrorRow& r : study.tilt) tilt_points = tilt_points || r.draws > 0;
  for (const DopBin& b : study.dop) dop_points = dop_points || b.count > 0;
  if (epochs == 0) figures.clear();
  Plot tp{"tilt.png",
          fmt::format("Sun-elevation error against a tilt error (Z21 Fig. 17; {} trials, mean H = {:.1f}°)",
                      n, study.tilt_mean_elevation_deg),
          "horizontal-attitude error τ (°), towards a uniformly random direction", "mean |elevation error| (°)"};
  tp.series = {{"tilt.csv", "$tilt_deg:$mean_abs_deg:(2*$se_mean_deg)", "polrig (± 2 standard errors)",
                "yerrorbars pt 7 lc rgb '#1f77b4'"},
               {"tilt.csv", "$tilt_deg:$exact_deg", "exact expectation", "lines lw 2 lc rgb 'black'"},
               {"tilt.csv", "$tilt_deg:$first_order_deg", "(2/π)·τ", "lines lw 1 dt 2 lc rgb 'black'"},
               {"tilt.csv", "$tilt_deg:$z21_deg", "Z21 Fig. 17", "points pt 5 ps 1.5 lc rgb '#d62728'"}};
  tp.extra = "set key inside top left\nset xrange [0:*]\nset yrange [0:*]\nset offsets 0, graph 0.05, graph 0.05, 0";
  if (tilt_points) figures.push_back(tp);

  Plot dp{"dop.png", fmt::format("E-vector error against DoP (Z21 Fig. 16; every unit reading of {} trials)", n),
          "DoP (%)", "|aop − true aop| (°)"};
  dp.series = {{"dop.csv", "(50*($dop_lo+$dop_hi)):($count > 0 ? $mean_abs_deg : NaN):$sd_abs_deg",
                "polrig: mean ± SD per 5 % bin", "yerrorbars pt 7 lc rgb '#1f77b4'"},
               {"dop.csv", "(50*($dop_lo+$dop_hi)):($count > 0 ? $mean_abs_deg : NaN)", "", "lines lc rgb '#1f77b4'"},
               {"dop.csv", "(50*($dop_lo+$dop_hi)+0.6):$z21_mean_deg:$z21_sd_deg", "Z21 Fig. 16: mean ± SD",
                "yerrorbars pt 5 ps 1.2 lc rgb '#d62728'"}};
  dp.extra = "set key inside top right\nset logscale y\nset format y '%g'";
  if (dop_points) figures.push_back(dp);

  if (figures.empty()) return files;
  render_plots(dir, "plots.gp", figures);
  for (const Plot& p : figures) {
    std::string what = "Fig. 16: E-vector error against DoP, with Z21's two bins";
    if (p.png == "error_vs_time.png") what = "each mode's horizontal error against time, median and percentile bands";
    else if (p.png == "tilt.png") what = "Fig. 17: mean sun-elevation error against the tilt, with the closed form and Z21's";
    else if (p.png != "dop.png") what = "the final horizontal error's percentiles against the swept key, per mode";
    files.push_back({p.png, 1, what});
  }
  return files;
}

}  // namespace polrig
