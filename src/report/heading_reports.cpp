#include "polrig/report/heading_reports.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "polrig/io/csv.h"
#include "polrig/io/plot.h"
#include "polrig/io/sky_files.h"

namespace polrig {

namespace {

// A number for a CSV cell: finite, or NaN where `undefined_ok` (a trial without a heading).
std::string cell(double v, const char* column, int trial, bool undefined_ok = false) {
  if (!std::isfinite(v) && !(std::isnan(v) && undefined_ok))
    throw std::runtime_error(fmt::format("a result is not finite: column '{}' of trial {} is {}; "
                                         "nothing was written", column, trial, v));
  return fmt::format("{}", v);
}

std::string stats_row(const HeadingErrorStats& s) {
  const auto num = [](double v) { return fmt::format("{}", v); };  // undefined: nan (formats.md §5)
  return fmt::format("{},{},{},{},{},{},{},{},{},{},{}\n", s.factor, s.error, num(s.bin_lo),
                     num(s.bin_hi), s.trials, s.solved, num(s.mean_deg), num(s.rms_deg),
                     num(s.p50_abs_deg), num(s.p95_abs_deg), num(s.max_abs_deg));
}


}  // namespace

std::vector<DatasetFile> report_heading_trials(const std::filesystem::path& dir,
                                               const std::vector<HeadingTrial>& trials,
                                               const HeadingStudySettings& settings, bool plots,
                                               const Progress& progress) {
  std::string text =
      "trial,seed,heading_deg,roll_deg,pitch_deg,sync_s,turn_rate_dps,sync_heading_deg,"
      "ins_roll_error_deg,ins_pitch_error_deg,mount_x_deg,mount_y_deg,mount_tilt_deg,mount_z_deg,"
      "p_max,dop,aop_true_deg,aop_meas_deg,status,heading_est_deg,error_deg,error_sync_deg,"
      "error_ins_tilt_deg,error_mount_deg,error_noise_deg\n";
  for (const HeadingTrial& t : trials) {
    const int k = t.index;
    text += fmt::format("{},{}", k, t.seed);
    for (auto [v, name] : {std::pair{t.heading_deg, "heading_deg"}, {t.roll_deg, "roll_deg"},
                           {t.pitch_deg, "pitch_deg"}, {t.sync_s, "sync_s"},
                           {t.turn_rate_dps, "turn_rate_dps"}, {t.sync_heading_deg(), "sync_heading_deg"},
                           {t.ins_roll_error_deg, "ins_roll_error_deg"},
                           {t.ins_pitch_error_deg, "ins_pitch_error_deg"},
                           {t.mount_x_deg, "mount_x_deg"}, {t.mount_y_deg, "mount_y_deg"},
                           {t.mount_tilt_deg(), "mount_tilt_deg"}, {t.mount_z_deg, "mount_z_deg"},
                           {t.p_max, "p_max"}, {t.dop, "dop"}, {t.aop_true_deg, "aop_true_deg"},
                           {t.aop_meas_deg, "aop_meas_deg"}})
      (text += ',') += cell(v, name, k);
    text += fmt::format(",{}", heading_status_name(t.status));
    for (auto [v, name] : {std::pair{t.heading_est_deg, "heading_est_deg"}, {t.error_deg, "error_deg"},
                           {t.error_sync_deg, "error_sync_deg"},
                           {t.error_ins_tilt_deg, "error_ins_tilt_deg"},
                           {t.error_mount_deg, "error_mount_deg"},
                           {t.error_noise_deg, "error_noise_deg"}})
      (text += ',') += cell(v, name, k, true);
    text += "\n";
  }
  write_text_file(dir / "trials.csv", text);

  // Overall, each factor alone, then the full error binned by each factor.
  std::string summary =
      "factor,error,bin_lo,bin_hi,trials,solved,mean_deg,rms_deg,p50_abs_deg,p95_abs_deg,max_abs_deg\n";
  for (const HeadingErrorStats& row : summarize_heading_trials(trials)) summary += stats_row(row);
  write_text_file(dir / "summary.csv", summary);

  // The distribution of |error|, all factors and each alone, each column sorted on its own.
  const HeadingErrorCdf c = heading_error_cdf(trials);
  std::string cdf = "fraction,all_deg,sync_deg,ins_tilt_deg,mount_deg,noise_deg\n";
  const std::size_t n = trials.size();
  for (std::size_t k = 0; k < n; ++k) {
    cdf += fmt::format("{}", c.fraction[k]);
    for (const std::vector<double>& column : c.abs_error_deg)
      cdf += std::isnan(column[k]) ? std::string(",nan") : fmt::format(",{}", column[k]);
    cdf += "\n";
  }
  write_text_file(dir / "cdf.csv", cdf);

  // Where and when the trials were run, and the sun they saw.
  const Sky sky{settings.site, settings.utc, settings.sun, {}};
  write_text_file(dir / "sun.yaml",
                  sun_yaml("of every trial (polrig study heading)", settings.utc, sky,
                           sun_position(settings.utc, settings.site, settings.sun)));

  std::vector<DatasetFile> files{
      {"sun.yaml", 1, "the site, the time and the sun's azimuth and elevation of every trial"},
      {"trials.csv", 1, "per trial: the drawn attitude, sync error, turn rate, INS tilt error, mount "
                        "misalignment, P_max; the sky's d and θ_b, the noisy θ_b, the status, the "
                        "heading and its error (all factors, then each alone)"},
      {"summary.csv", 1, "mean, RMS, median, 95 % and largest |error| overall and for each factor "
                         "alone, then the full error in 8 bins of each factor"},
      {"cdf.csv", 1, "empirical distribution of |heading error|, all factors and each alone"}};
  if (!plots || n == 0) return files;

  const std::string pts = "points pt 7 ps 0.35 lc rgb '#1f77b4'";
  const std::string alone = "points pt 7 ps 0.35 lc rgb '#d62728'";
  const std::string title_tail = fmt::format("{} trials", n);
  Plot sync{"error_vs_sync.png",
            fmt::format("Heading error against the sync error ω·Δt (|ω| ≤ {}°/s, |Δt| ≤ {} s; {})",
                        settings.turn_rate_max_dps, settings.sync_max_s, title_tail),
            "ω·Δt, turn rate × sensor-INS time offset (°)", "heading error (°)"};
  sync.series = {{"trials.csv", "$sync_heading_deg:$error_deg", "all factors", pts},
                 {"trials.csv", "$sync_heading_deg:$error_sync_deg", "sync error alone", alone},
                 {"trials.csv", "$sync_heading_deg:$sync_heading_deg", "ω·Δt", "lines lw 1 dt 2 lc rgb 'black'"}};
  Plot roll{"error_vs_roll.png", "Heading error against roll (" + title_tail + ")", "roll (°)",
            "heading error (°)"};
  roll.series = {{"trials.csv", "$roll_deg:$error_deg", "all factors", pts},
                 {"trials.csv", "$roll_deg:($error_deg-$error_sync_deg)", "all factors minus the sync error alone", alone}};
  Plot pitch{"error_vs_pitch.png", "Heading error against pitch (" + title_tail + ")", "pitch (°)",
             "heading error (°)"};
  pitch.series = {{"trials.csv", "$pitch_deg:$error_deg", "all factors", pts},
                  {"trials.csv", "$pitch_deg:($error_deg-$error_sync_deg)", "all factors minus the sync error alone", alone}};
  Plot mount_z{"error_vs_mount_azimuth.png", "Heading error against the mount's azimuthal offset",
               "mount azimuth offset m_z (°)", "heading error from the mount alone (°)"};
  mount_z.series = {{"trials.csv", "$mount_z_deg:$error_mount_deg", "mount alone", alone},
                    {"trials.csv", "$mount_z_deg:(-$mount_z_deg)", "−m_z", "lines lw 1 dt 2 lc rgb 'black'"}};
  Plot mount_t{"error_vs_mount_tilt.png", "Heading error against the mount's tilt",
               "mount tilt √(m_x² + m_y²) (°)", "heading error from the mount alone (°)"};
  mount_t.series = {{"trials.csv", "$mount_tilt_deg:($error_mount_deg+$mount_z_deg)", "mount alone, azimuth offset removed", alone}};
  Plot ins{"error_vs_ins_tilt.png", "Heading error against the INS's tilt error",
           "INS tilt error √(δroll² + δpitch²) (°)", "heading error from the INS tilt alone (°)"};
  ins.series = {{"trials.csv", "(sqrt($ins_roll_error_deg**2+$ins_pitch_error_deg**2)):$error_ins_tilt_deg", "INS tilt error alone", alone}};
  Plot pmax{"error_vs_pmax.png", "Heading error from sensor noise against the sky's P_max",
            "P_max", "heading error from sensor noise alone (°)"};
  pmax.series = {{"trials.csv", "$p_max:$error_noise_deg", "sensor noise alone (device model)", alone}};
  Plot dist{"error_cdf.png", "Distribution of |heading error| (" + title_tail + ")",
            "|heading error| (°)", "fraction of trials"};
  dist.series = {{"cdf.csv", "$all_deg:$fraction", "all factors", "steps lw 2 lc rgb 'black'"},
                 {"cdf.csv", "$sync_deg:$fraction", "sync error ω·Δt alone", "steps lw 2 lc rgb '#d62728'"},
                 {"cdf.csv", "$ins_tilt_deg:$fraction", "INS tilt error alone", "steps lw 2 lc rgb '#2ca02c'"},
                 {"cdf.csv", "$mount_deg:$fraction", "mount misalignment alone", "steps lw 2 lc rgb '#9467bd'"},
                 {"cdf.csv", "$noise_deg:$fraction", "sensor noise alone", "steps lw 2 lc rgb '#1f77b4'"}};
  dist.extra = "set logscale x\nset yrange [0:1]\nset format x '%g'";
  for (Plot* p : {&sync, &roll, &pitch, &mount_z, &mount_t, &ins, &pmax})
    p->extra = "set key below horizontal spacing 1.4";  // the scatter gets the whole width
  render_plots(dir, "plots.gp", {sync, roll, pitch, mount_z, mount_t, ins, pmax, dist}, progress);
  for (const char* png : {"error_vs_sync.png", "error_vs_roll.png", "error_vs_pitch.png",
                          "error_vs_mount_azimuth.png", "error_vs_mount_tilt.png",
                          "error_vs_ins_tilt.png", "error_vs_pmax.png", "error_cdf.png"})
    files.push_back({png, 1, "heading error against one factor (see the plot's title)"});
  return files;
}

}  // namespace polrig
