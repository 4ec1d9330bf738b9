#include "polrig/report/installation_report.h"
#include "polrig/quoted.h"

#include <cmath>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "polrig/io/csv.h"
#include "polrig/io/measured.h"
#include "polrig/io/plot.h"

namespace polrig {

namespace {

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
                       i + 1, u.error_deg[0], u.error_deg[1], u.error_deg[2], u.standard_error_deg[0],
                       u.standard_error_deg[1], u.standard_error_deg[2], u.rms_before_deg, u.rms_after_deg, u.used,
                       u.iterations, u.termination, u.converged);
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
                       u.standard_error_deg[0], u.standard_error_deg[1], u.standard_error_deg[2], u.rms_before_deg,
                       u.rms_after_deg, u.used, u.termination);
  }
  return out;
}

[[noreturn]] void refuse_key(const std::filesystem::path& file, const YAML::Node& node, const std::string& key,
                         const std::string& problem) {
  const std::string where = node.Mark().is_null() ? file.string() : fmt::format("{}:{}", file.string(), node.Mark().line + 1);
  throw DataError(fmt::format("{}: key '{}': {}", where, key, problem));
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

std::vector<UnitMount> read_installation(const std::filesystem::path& file, const std::vector<UnitMount>& nominal) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(file.string());
  } catch (const YAML::Exception& e) {
    throw DataError(fmt::format("{}: {}", file.string(), e.what()));
  }
  const YAML::Node units = root["units"];
  if (!units || !units.IsSequence()) refuse_key(file, root, "units", "expected a list of units (polrig calibrate --method unit-array)");
  if (units.size() != nominal.size())
    refuse_key(file, units, "units", fmt::format("expected {} units (the dataset's layout), got {}", nominal.size(), units.size()));
  std::vector<UnitMount> out;
  for (std::size_t i = 0; i < units.size(); ++i) {
    // A unit its fit did not determine (converged: false) keeps its nominal frame, as
    // InstallationRun::mounts() does.
    const YAML::Node converged = units[i]["converged"];
    if (!converged || !converged.IsScalar() || (converged.Scalar() != "true" && converged.Scalar() != "false"))
      refuse_key(file, units[i], fmt::format("units[{}].converged (unit {})", i, i + 1), "expected true or false");
    if (converged.Scalar() == "false") {
      out.push_back(nominal[i]);
      continue;
    }
    const YAML::Node e = units[i]["error_deg"];
    const std::string key = fmt::format("units[{}].error_deg (unit {})", i, i + 1);
    if (!e || !e.IsSequence() || e.size() != 3) refuse_key(file, units[i], key, "expected three angles in degrees");
    std::array<double, 3> d{};
    for (std::size_t a = 0; a < 3; ++a) {
      try {
        d[a] = e[a].as<double>();
      } catch (const YAML::Exception&) {
        refuse_key(file, e[a], key, fmt::format("expected a number, got '{}'", quoted_value(e[a].Scalar())));
      }
      if (!(std::abs(d[a]) <= 10))
        refuse_key(file, e[a], key, fmt::format("expected a mounting error within ±10°, got {}", quoted_value(e[a].Scalar())));
    }
    out.push_back({installed_frame(nominal[i].C_mb, d)});
  }
  return out;
}

}  // namespace polrig
