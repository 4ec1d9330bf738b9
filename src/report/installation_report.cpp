#include "polrig/report/installation_report.h"

#include <cmath>

#include <fmt/format.h>

#include "polrig/io/csv.h"
#include "polrig/io/measured.h"
#include "polrig/io/plot.h"

namespace polrig {

namespace {

// A standard error, or what stands for none (a rank-deficient fit): YAML's null, CSV's empty cell.
std::string standard_error_cell(double se, const char* none) { return std::isfinite(se) ? fmt::format("{}", se) : none; }

std::string calibration_yaml(const InstallationRun& run) {
  std::string out = fmt::format(
      "# polrig calibrate --method unit-array: each unit's mounting error δ about its own X, Y, Z (deg), fitted\n"
      "# to its readings against the ephemeris sun with the {} attitude over {} readings (docs/formats.md §6.19).\n"
      "units:\n", run.attitude_from, run.epochs);
  for (std::size_t i = 0; i < run.units.size(); ++i) {
    const UnitInstallation& u = run.units[i];
    out += fmt::format("  - unit: {}\n    error_deg: [{}, {}, {}]\n    standard_error_deg: [{}, {}, {}]\n"
                       "    rms_before_deg: {}\n    rms_after_deg: {}\n    used: {}\n    iterations: {}\n"
                       "    termination: {}\n    converged: {}\n",
                       i + 1, u.error_deg[0], u.error_deg[1], u.error_deg[2], standard_error_cell(u.standard_error_deg[0], "null"),
                       standard_error_cell(u.standard_error_deg[1], "null"), standard_error_cell(u.standard_error_deg[2], "null"),
                       u.rms_before_deg, u.rms_after_deg, u.used, u.iterations, u.termination, u.converged);
    const Axes3& a = run.nominal[i].C_mb;
    out += fmt::format("    nominal_axes_b: [[{}, {}, {}], [{}, {}, {}], [{}, {}, {}]]  # the layout fitted: X, Y, Z\n",
                       a[0][0], a[0][1], a[0][2], a[1][0], a[1][1], a[1][2], a[2][0], a[2][1], a[2][2]);
  }
  out += fmt::format("elevation_error_deg:  # H^n of the two highest-DoP units minus the ephemeris'\n"
                     "  mean_before: {}\n  mean_after: {}\n  mae_before: {}\n  mae_after: {}\n  readings: {}\n",
                     run.elevation_mean_before_deg, run.elevation_mean_after_deg, run.elevation_mae_before_deg,
                     run.elevation_mae_after_deg, run.elevation_epochs);
  return out;
}

std::string installation_csv(const InstallationRun& run) {
  std::string out = "unit,error_x_deg,error_y_deg,error_z_deg,se_x_deg,se_y_deg,se_z_deg,rms_before_deg,rms_after_deg,"
                    "used,termination\n";
  for (std::size_t i = 0; i < run.units.size(); ++i) {
    const UnitInstallation& u = run.units[i];
    out += fmt::format("{},{},{},{},{},{},{},{},{},{},{}\n", i + 1, u.error_deg[0], u.error_deg[1], u.error_deg[2],
                       standard_error_cell(u.standard_error_deg[0], ""), standard_error_cell(u.standard_error_deg[1], ""),
                       standard_error_cell(u.standard_error_deg[2], ""), u.rms_before_deg, u.rms_after_deg, u.used,
                       u.termination);
  }
  return out;
}

}  // namespace

std::vector<DatasetFile> report_installation(const std::filesystem::path& dir, const InstallationRun& run, bool plots) {
  write_text_file(dir / "calibration.yaml", calibration_yaml(run));
  write_text_file(dir / "installation.csv", installation_csv(run));
  std::vector<DatasetFile> files{
      {"calibration.yaml", 1, "each unit's mounting errors (navigate --calibration reads it) and the elevation error before and after"},
      {"installation.csv", 1, "per unit: the mounting errors, their standard errors, the AoP residual RMS before and after"}};
  if (plots) {
    Plot p{"installation.png", "Each unit's AoP residual against the ephemeris sun: nominal frame (before) and "
                               "calibrated (after), Z21 Table 2",
           "unit", "AoP residual RMS (°)"};
    p.series = {{"installation.csv", "($unit-0.15):$rms_before_deg", "before", "boxes fs solid 0.5 lc rgb '#d62728'"},
                {"installation.csv", "($unit+0.15):$rms_after_deg", "after", "boxes fs solid 0.5 lc rgb '#1f77b4'"}};
    p.extra = "set boxwidth 0.3\nset xtics 1\nset yrange [0:*]\nset key below horizontal maxrows 1 spacing 1.4";
    render_plots(dir, "plots.gp", {p});
    files.push_back({"installation.png", 1, p.title});
  }
  return files;
}

}  // namespace polrig
