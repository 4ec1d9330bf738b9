// Z21's unit-array compass with a strapdown INS (spec sky-and-compasses.md §4): `navigate DIR`, the
// SINS, PNS and SINS/PNS modes on a unit-array dataset (`polrig simulate` of a unit-array rig, or
// measured files of the same form).
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "cli.h"
#include "polrig/io/measured.h"
#include "polrig/io/navigation_dataset.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/ins/mechanization.h"
#include "polrig/io/installation_yaml.h"
#include "polrig/report/installation_report.h"
#include "polrig/report/navigation_report.h"
#include "polrig/rig/error.h"
#include "polrig/study/installation.h"
#include "polrig/study/navigation.h"

namespace polrig::cli {

namespace {

struct NavigateOptions {
  std::string input, rig_path, mode = "all", calibration;
  double sins_rate_hz = 0;
  std::vector<std::string> sets;
  OutputOptions out;
};

// The dataset's rig (DIR/rig.yaml, read through the open folder, or --rig) with the --set
// overrides: a unit array under the sky.
LoadedRig navigation_rig(const NavigateOptions& o, const DatasetFolder& folder) {
  LoadedRig r;
  std::vector<RigOverride> overrides;
  for (const std::string& s : o.sets) overrides.push_back(RigOverride::parse(s));
  if (!o.rig_path.empty()) {
    r = load_rig(o.rig_path, overrides, RigUse::ReadDataset);
  } else {
    if (!folder.has("rig.yaml"))
      throw DataError(fmt::format("{}: no rig.yaml (a unit-array dataset holds its rig; else give --rig)", o.input));
    r = parse_rig(folder.read("rig.yaml", kMaxRigYamlBytes), folder.path("rig.yaml").string(), overrides, RigUse::ReadDataset);
  }
  require_instrument(r.rig, Instrument::kUnitArray, "navigate", r.origin);
  return r;
}

// The dataset's folder, opened once for the rig and every file (io/dataset_folder.h).
DatasetFolder dataset_folder(const std::string& input) {
  if (!std::filesystem::is_directory(input)) throw DataError(fmt::format("{}: not a folder (expected a unit-array dataset)", input));
  return DatasetFolder(input);
}

void print_summary(const NavigationDataset& data, const NavigationRun& run) {
  std::cout << fmt::format("{} IMU samples, {} compass readings\n", data.imu.size(), data.compass.size());
  std::string channel = run.vertical_channel;
  if (const std::size_t hash = channel.find("  # "); hash != std::string::npos) channel.replace(hash, 4, " (") += ")";
  std::cout << "vertical channel: " << channel << "\n";
  std::cout << "start: " << run.start.substr(0, run.start.find("  # ")) << "\n";
  if (!run.filter.empty()) std::cout << "integrated filter: " << run.filter_summary.BriefReport() << "\n";
  for (std::size_t m = 0; m < run.modes.size(); ++m)
    for (const NavigationFix& f : run.fixes[m])
      if (f.status == "diverged") {
        std::cerr << fmt::format("polrig: warning: {} diverged at t = {:.3f} s (its latitude past ±{}° or not finite); "
                                 "its rows from then on say `diverged` and repeat its last state inside the domain\n",
                                 navigation_mode_name(run.modes[m]), f.t_s, kInsMaxLatitudeDeg);
        break;
      }
  for (const ModeErrorSummary& s : summarize_navigation(data, run))
    std::cout << fmt::format("{:>10}: latitude MAE/RMSE/STD {:.4f}/{:.4f}/{:.4f}°, longitude {:.4f}/{:.4f}/{:.4f}° "
                             "({} fixes); at the end {:.2f} km north, {:.2f} km east\n",
                             navigation_mode_name(s.mode), s.lat.mae, s.lat.rmse, s.lat.std, s.lon.mae, s.lon.rmse,
                             s.lon.std, s.lat.count, s.final_north_m / 1000, s.final_east_m / 1000);
}

void run_navigate(const NavigateOptions& o) {
  const DatasetFolder folder = dataset_folder(o.input);
  const LoadedRig r = navigation_rig(o, folder);
  NavigationOptions options;
  try {
    options.modes = parse_navigation_modes(o.mode);
  } catch (const std::invalid_argument& e) {
    throw DataError(fmt::format("--mode: {}", e.what()));
  }
  options.sins_rate_hz = o.sins_rate_hz;
  const NavigationDataset data = read_navigation_dataset(folder, r.rig);
  if (!o.calibration.empty()) options.mounts = read_installation(o.calibration, data.mounts);
  OutputDir dir = o.out.open();
  NavigationRun run;
  try {
    run = navigate(data, r.rig, options, progress());
  } catch (const std::invalid_argument& e) {
    throw DataError(fmt::format("{}: {}", o.input, e.what()));
  }
  std::vector<std::string> inputs{folder.path("imu.csv").string()};
  if (folder.has("units.csv")) inputs.push_back(folder.path("units.csv").string());
  if (data.truth) inputs.push_back((std::filesystem::path(o.input) / "truth.csv").string());
  if (!o.calibration.empty()) inputs.push_back(o.calibration);
  write_manifest(dir.staging(), {command_line(), &r, report_navigation(dir.staging(), data, run, r.rig, o.out.plots()), inputs});
  finish(dir);
  print_summary(data, run);
}

}  // namespace

void run_calibrate_unit_array(const std::string& input, const std::string& rig_path, const OutputOptions& out) {
  NavigateOptions o;
  o.input = input;
  o.rig_path = rig_path;
  const DatasetFolder folder = dataset_folder(input);
  const LoadedRig r = navigation_rig(o, folder);
  const NavigationDataset data = read_navigation_dataset(folder, r.rig);
  OutputDir dir = out.open();
  InstallationRun run;
  try {
    run = calibrate_unit_array(data, r.rig);
  } catch (const std::invalid_argument& e) {
    throw DataError(fmt::format("{}: {}", input, e.what()));
  }
  write_manifest(dir.staging(), {command_line(), &r, report_installation(dir.staging(), run, out.plots()), {input}});
  finish(dir);
  std::cout << fmt::format("unit-array installation: {} readings, attitude from the {}\n", run.epochs, run.attitude_from);
  for (std::size_t i = 0; i < run.units.size(); ++i) {
    const UnitInstallation& u = run.units[i];
    const std::string se = std::isfinite(u.standard_error_deg[0])
                               ? fmt::format("± [{:.3f}, {:.3f}, {:.3f}]°", u.standard_error_deg[0],
                                             u.standard_error_deg[1], u.standard_error_deg[2])
                               : std::string("undetermined");
    std::cout << fmt::format("  unit {}: δ = [{:.3f}, {:.3f}, {:.3f}]° {}; AoP rms {:.3f}° → {:.3f}° ({} readings, {}{})\n",
                             i + 1, u.error_deg[0], u.error_deg[1], u.error_deg[2], se, u.rms_before_deg,
                             u.rms_after_deg, u.used, u.termination, u.converged ? "" : ", not used");
  }
  std::cout << fmt::format("sun elevation error: mean {:.3f}° → {:.3f}°, mean |error| {:.3f}° → {:.3f}° ({} readings)\n",
                           run.elevation_mean_before_deg, run.elevation_mean_after_deg, run.elevation_mae_before_deg,
                           run.elevation_mae_after_deg, run.elevation_epochs);
}

void simulate_unit_array(const LoadedRig& r, const OutputOptions& out) {
  OutputDir dir = out.open(false);
  NavigationDataset data;
  try {
    data = simulate_navigation(r.rig, progress());
  } catch (const std::invalid_argument& e) {
    throw RigError(fmt::format("{}: {}", r.origin, e.what()));
  }
  write_manifest(dir.staging(), {command_line(), &r, write_navigation_dataset(dir.staging(), data)});
  finish(dir);
  std::cout << fmt::format("{} IMU samples at {} Hz, {} readings of {} units at {} Hz\n", data.imu.size(), r.rig.imu.rate_hz,
                           data.compass.size(), data.mounts.size(), r.rig.units.rate_hz);
}

std::vector<Command> add_navigation_commands(CLI::App& root, int& threads) {
  std::vector<Command> commands;
  auto* app = root.add_subcommand("navigate", "SINS, PNS and SINS/PNS navigation on a unit-array dataset (Z21)");
  auto o = std::make_shared<NavigateOptions>();
  app->add_option("DIR", o->input, "a unit-array dataset: polrig simulate's folder, or measured imu.csv and units.csv "
                                   "with a rig.yaml")->required();
  app->add_option("--mode", o->mode,
                  "sins, pns, integrated, smoothed (integrated after the RTS smoother) or all (sins, pns and integrated), "
                  "or a comma-separated list (e.g. all,smoothed)")
      ->capture_default_str();
  app->add_option("--rig", o->rig_path, "the rig (default: DIR/rig.yaml)");
  app->add_option("--sins-rate-hz", o->sins_rate_hz,
                  "the SINS mode's output rate, a rate that divides imu.rate_hz (default: at the compass readings, "
                  "or every IMU sample of a log without units.csv)")
      ->check(finite_range(0, 1e4, "Hz"));
  app->add_option("--calibration", o->calibration, "the units' frames from a calibration.yaml (polrig calibrate "
                                                   "--method unit-array); default: the nominal layout");
  add_set_option(*app, o->sets);
  o->out.add_to(*app);
  add_threads_option(*app, threads);
  commands.push_back({app, [o, app] {
                        require_file_name(*app, "--rig", o->rig_path);
                        require_file_name(*app, "--calibration", o->calibration);
                        run_navigate(*o);
                      }});
  return commands;
}

}  // namespace polrig::cli
