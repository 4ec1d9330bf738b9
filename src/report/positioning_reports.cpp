#include "polrig/report/positioning_reports.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "polrig/io/csv.h"
#include "polrig/io/plot.h"
#include "csv_cells.h"

namespace polrig {

namespace {

std::string root_row(const char* which, const PositionRoot& r, const std::optional<Site>& truth) {
  const PositionSummary& s = r.summary;
  const double error = truth ? great_circle_km(r.lat_deg, r.lon_deg, truth->lat_deg, truth->lon_deg) : NAN;
  const std::size_t row = which[0] == 'c' ? 1 : 2;
  return fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", which,
                     checked_cell(r.lat_deg, "lat_deg", row), checked_cell(r.lon_deg, "lon_deg", row),
                     checked_cell(error, "error_km", row, true), checked_cell(r.prior_distance_km, "prior_distance_km", row),
                     position_termination_name(s.termination), s.iterations, s.evaluations,
                     s.relinearizations, s.sightings, s.rank, checked_cell(s.singular_ratio, "singular_ratio", row, true),
                     checked_cell(s.final_cost_deg2, "cost_deg2", row, true),
                     checked_cell(s.residual_rms_deg, "residual_rms_deg", row, true),
                     checked_cell(r.sd_north_km, "sd_north_km", row, true), checked_cell(r.sd_east_km, "sd_east_km", row, true),
                     checked_cell(r.sd_major_km, "sd_major_km", row, true));
}

}  // namespace

std::vector<DatasetFile> report_positioning_study(const std::filesystem::path& dir,
                                                  const PositioningStudy& study, bool plots) {
  const PositioningStudySettings& s = study.settings;
  std::string summary =
      "cell,factor,window_s,noise_sd_deg,tilt_deg,correlation_s,sightings,delta_beta_deg,trials,"
      "converged,rms_km,mean_km,p50_km,p95_km,max_km,mean_north_km,mean_east_km,eq15_km,linear_rms_km,"
      "mirror_km,wrong_root\n";
  for (std::size_t i = 0; i < study.cells.size(); ++i) {
    const PositioningCell& c = study.cells[i];
    const PositioningStats& st = study.stats[i];
    summary += fmt::format("{},{},{},{},{},{},{},{},{},{}", c.index, c.factor, checked_cell(c.window_s, "window_s", i),
                           checked_cell(c.noise_sd_deg, "noise_sd_deg", i), checked_cell(c.tilt_deg, "tilt_deg", i),
                           checked_cell(s.correlation_s, "correlation_s", i), c.sightings,
                           checked_cell(c.delta_beta_deg, "delta_beta_deg", i), st.trials, st.converged);
    for (auto [v, name] : {std::pair{st.rms_km, "rms_km"}, {st.mean_km, "mean_km"}, {st.p50_km, "p50_km"},
                           {st.p95_km, "p95_km"}, {st.max_km, "max_km"}, {st.mean_north_km, "mean_north_km"},
                           {st.mean_east_km, "mean_east_km"}})
      (summary += ',') += checked_cell(v, name, i, true);
    summary += fmt::format(",{},{},{},{}\n", checked_cell(c.eq15_km, "eq15_km", i), checked_cell(c.linear_rms_km, "linear_rms_km", i),
                           checked_cell(c.mirror_km, "mirror_km", i, true), st.wrong_root);
  }
  write_text_file(dir / "summary.csv", summary);

  std::string trials =
      "cell,factor,window_s,noise_sd_deg,tilt_deg,trial,tilt_azimuth_deg,prior_lat_deg,prior_lon_deg,"
      "lat_deg,lon_deg,error_km,north_km,east_km,termination,iterations,residual_rms_deg,sd_major_km\n";
  for (std::size_t i = 0; i < study.trials.size(); ++i) {
    const PositioningTrial& t = study.trials[i];
    const PositioningCell& c = study.cells[static_cast<std::size_t>(t.cell)];
    trials += fmt::format("{},{},{},{},{},{}", c.index, c.factor, c.window_s, c.noise_sd_deg, c.tilt_deg, t.trial);
    for (auto [v, name] : {std::pair{t.tilt_azimuth_deg, "tilt_azimuth_deg"}, {t.prior_lat_deg, "prior_lat_deg"},
                           {t.prior_lon_deg, "prior_lon_deg"}, {t.lat_deg, "lat_deg"}, {t.lon_deg, "lon_deg"},
                           {t.error_km, "error_km"}, {t.north_km, "north_km"}, {t.east_km, "east_km"}})
      (trials += ',') += checked_cell(v, name, i);
    trials += fmt::format(",{},{},{},{}\n", position_termination_name(t.termination), t.iterations,
                          checked_cell(t.residual_rms_deg, "residual_rms_deg", i, true),
                          checked_cell(t.sd_major_km, "sd_major_km", i, true));
  }
  write_text_file(dir / "trials.csv", trials);

  std::vector<DatasetFile> files{
      {"summary.csv", 1, "per cell of the three sweeps (window, noise, tilt): the position error's RMS, "
                         "mean, median, 95 % and largest over the converged trials, its mean north and "
                         "east, Eq. 15's two-sighting error over the window's Δβ, the linearized "
                         "least-squares RMS, the mirror root M′'s distance and the trials nearer it"},
      {"trials.csv", 1, "per trial: the cell, the tilt azimuth, the prior, the fix, its error (km, "
                        "north, east), how the fit ended, its residual RMS and its own 1σ"}};
  if (!plots || study.trials.empty()) return files;

  // The baseline cell: the noise sweep's cell at the baseline σ (else the last window cell).
  int baseline = -1;
  for (const PositioningCell& c : study.cells)
    if (baseline < 0 && c.factor == "noise" && c.noise_sd_deg == s.baseline_noise_sd_deg) baseline = c.index;
  if (baseline < 0)
    for (const PositioningCell& c : study.cells)
      if (c.factor == "window") baseline = c.index;
  const PositioningCell& b = study.cells[static_cast<std::size_t>(baseline)];
  const std::string noise_text =
      s.correlation_s > 0 ? fmt::format("Gauss–Markov noise, τ_c = {} s", s.correlation_s) : std::string("white noise");
  const std::string tail = fmt::format("{} trials per point, {}", s.trials, noise_text);
  const auto on = [](const char* factor, const char* column) {
    return fmt::format("(@factor eq '{}' ? ${} : NaN)", factor, column);
  };
  const std::string rms = "linespoints lw 2 pt 7 lc rgb '#1f77b4'", p95 = "linespoints lw 1 pt 6 lc rgb '#1f77b4' dt 2";
  const std::string eq15 = "lines lw 2 lc rgb '#d62728'", lin = "lines lw 1 lc rgb 'black' dt 3";
  Plot window{"error_vs_window.png",
              fmt::format("Position error against the window (σ = {}°, tilt {}°; {})", s.baseline_noise_sd_deg,
                          s.baseline_tilt_deg, tail),
              "window (min)", "position error (km)"};
  window.series = {{"summary.csv", "($window_s/60):" + on("window", "rms_km"), "Monte-Carlo RMS", rms},
                   {"summary.csv", "($window_s/60):" + on("window", "p95_km"), "Monte-Carlo 95 %", p95},
                   {"summary.csv", "($window_s/60):" + on("window", "eq15_km"),
                    "Eq. 15 (each window's first and last sighting: its Δβ)", eq15},
                   {"summary.csv", "($window_s/60):" + on("window", "linear_rms_km"), "linearized least squares", lin}};
  window.extra = "set logscale xy\nset format y '%g'\nset format x '%g'\nset key below horizontal spacing 1.4";
  Plot noise{"error_vs_noise.png",
             fmt::format("Position error against the zenith-angle noise ({} s window, tilt {}°; {})",
                         b.window_s, s.baseline_tilt_deg, tail),
             "zenith-angle noise σ (°)", "position error (km)"};
  noise.series = {{"summary.csv", "$noise_sd_deg:" + on("noise", "rms_km"), "Monte-Carlo RMS", rms},
                  {"summary.csv", "$noise_sd_deg:" + on("noise", "p95_km"), "Monte-Carlo 95 %", p95},
                  {"summary.csv", "$noise_sd_deg:" + on("noise", "eq15_km"),
                   fmt::format("Eq. 15 (first and last sighting, Δβ = {:.2f}°)", b.delta_beta_deg), eq15},
                  {"summary.csv", "$noise_sd_deg:" + on("noise", "linear_rms_km"), "linearized least squares", lin}};
  noise.extra = "set key below horizontal spacing 1.4";
  Plot tilt{"error_vs_tilt.png",
            fmt::format("Position error against the levelling error ({} s window, σ = {}°; {})", b.window_s,
                        s.baseline_noise_sd_deg, tail),
            "levelling error τ (°), towards a random azimuth", "position error (km)"};
  tilt.series = {{"summary.csv", "$tilt_deg:" + on("tilt", "rms_km"), "Monte-Carlo RMS", rms},
                 {"summary.csv", "$tilt_deg:" + on("tilt", "p95_km"), "Monte-Carlo 95 %", p95},
                 {"summary.csv", "$tilt_deg:" + on("tilt", "eq15_km"),
                  fmt::format("Eq. 15 with ε = √(σ² + τ²), Δβ = {:.2f}°", b.delta_beta_deg), eq15},
                 {"summary.csv", "$tilt_deg:" + on("tilt", "linear_rms_km"), "linearized least squares", lin}};
  tilt.extra = "set key below horizontal spacing 1.4";
  Plot fixes{"fixes.png",
             fmt::format("Fixes around the truth ({} s window, σ = {}°, tilt {}°; {})", b.window_s, b.noise_sd_deg,
                         b.tilt_deg, tail),
             "east (km)", "north (km)"};
  fixes.series = {{"trials.csv", fmt::format("($cell=={} ? $east_km : NaN):$north_km", baseline), "fixes",
                   "points pt 7 ps 0.5 lc rgb '#1f77b4'"}};
  fixes.extra = "set size ratio -1\nset key inside top right opaque\nset xzeroaxis lt -1\nset yzeroaxis lt -1";  // the axes cross at the truth
  fixes.width = 700;
  fixes.height = 700;
  render_plots(dir, "plots.gp", {window, noise, tilt, fixes});
  files.push_back({"error_vs_window.png", 1, "position error against the window's length, with Eq. 15"});
  files.push_back({"error_vs_noise.png", 1, "position error against the zenith-angle noise, with Eq. 15"});
  files.push_back({"error_vs_tilt.png", 1, "position error against the levelling error, with Eq. 15"});
  files.push_back({"fixes.png", 1, "the baseline cell's fixes, north and east of the truth"});
  return files;
}

std::vector<DatasetFile> report_location(const std::filesystem::path& dir, const Location& location,
                                         const std::optional<Site>& truth,
                                         const std::vector<double>& true_heading_deg) {
  if (!true_heading_deg.empty() && true_heading_deg.size() != location.samples.size())
    throw std::invalid_argument(fmt::format("report_location: {} true headings for {} sightings",
                                            true_heading_deg.size(), location.samples.size()));
  std::string fix =
      "root,lat_deg,lon_deg,error_km,prior_distance_km,termination,iterations,evaluations,"
      "relinearizations,sightings,rank,singular_ratio,cost_deg2,residual_rms_deg,sd_north_km,"
      "sd_east_km,sd_major_km\n";
  fix += root_row("chosen", location.fix.chosen, truth);
  if (location.fix.alternative) fix += root_row("alternative", *location.fix.alternative, truth);
  write_text_file(dir / "fix.csv", fix);

  std::string heading =
      "utc,weight,zenith_deg,zenith_fix_deg,residual_deg,alpha_s_deg,beta_deg,heading_deg,"
      "heading_true_deg,heading_error_deg\n";
  for (std::size_t k = 0; k < location.samples.size(); ++k) {
    const LocateSample& s = location.samples[k];
    const double truth_deg = true_heading_deg.empty() ? NAN : true_heading_deg[k];
    const double error = std::isnan(truth_deg) || std::isnan(s.heading_deg)
                             ? NAN
                             : std::remainder(s.heading_deg - truth_deg, 360.0);
    heading += fmt::format("{},{},{},{},{},{},{},{},{},{}\n", format_utc(s.utc), checked_cell(s.weight, "weight", k),
                           checked_cell(s.zenith_deg, "zenith_deg", k), checked_cell(s.zenith_fix_deg, "zenith_fix_deg", k, true),
                           checked_cell(s.residual_deg, "residual_deg", k, true), checked_cell(s.alpha_s_deg, "alpha_s_deg", k),
                           checked_cell(s.beta_deg, "beta_deg", k, true), checked_cell(s.heading_deg, "heading_deg", k, true),
                           checked_cell(truth_deg, "heading_true_deg", k, true), checked_cell(error, "heading_error_deg", k, true));
  }
  write_text_file(dir / "heading.csv", heading);
  return {{"fix.csv", 1, "the position fix from the sun's zenith angles (Eq. 17): the chosen root (nearest "
                         "the prior) and the alternative, with the error against the truth when known and "
                         "how each fit ended"},
          {"heading.csv", 1, "per sighting: the measured and fitted zenith angle, α_S (clockwise), the sun's "
                             "azimuth β at the fix and the heading ψ = β − α_S (Eq. 18)"}};
}

}  // namespace polrig
