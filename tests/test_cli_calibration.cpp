// End-to-end tests of calibrate, apply and study calibration: each test runs the real polrig
// executable in a fresh temporary folder and inspects the files it writes (or does not write).
#include <gtest/gtest.h>
#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "polrig/io/params_yaml.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/rig/rig.h"
#include "support.h"

namespace fs = std::filesystem;
using namespace polrig::test;

namespace {

const std::string& kRig = kDefaultRigFile;

// The top-level lines of a params.yaml for the four parameter lists (not the standard errors,
// which are indented).
std::map<std::string, std::string> param_lines(const fs::path& params) {
  std::map<std::string, std::string> out;
  for (const std::string& l : lines_of(read_file(params)))
    for (const char* key : {"alpha_deg:", "k_mV:", "kv:", "kd:"})
      if (l.rfind(key, 0) == 0) out[key] = l;
  return out;
}

// θ_a − θ_b for axes (period 180°), in [−90°, 90°).
double axis_diff(double a, double b) {
  double x = std::fmod(a - b + 90.0, 180.0);
  if (x < 0) x += 180.0;
  return x - 90.0;
}

// Each run's stdout and stderr go to tmp/logs, so that they do not show up among the outputs
// checked.
class CliCalibration : public PolrigTest {
 protected:
  CliCalibration() : PolrigTest("polrig_test_cli_calibration_", "logs") {}

  // Simulates the indoor rig into tmp/NAME (extra: more options).
  fs::path simulate(const std::string& name = "sim", const std::string& extra = "") {
    const fs::path out = tmp / name;
    ok("simulate " + shell_quote(kRig) + " -o " + shell_quote(out) + " --no-plots" + extra);
    return out;
  }

  // Entries of `parent` that are staging or backup folders (of `name` or of anything else).
  static std::vector<std::string> leftovers(const fs::path& parent, const std::string& name) {
    return entries_where(parent, [&](const std::string& f) {
      return f.rfind("." + name + ".", 0) == 0 || f.find(".partial-") != std::string::npos ||
             f.find(".old-") != std::string::npos;
    });
  }

  // Runs a command that must fail with `status` (or any non-zero status for -1), naming each of
  // `needles` on stderr, and leave neither `out` nor a staging folder behind.
  void expect_refused(const std::string& args, const fs::path& out, int status,
                      const std::vector<std::string>& needles) {
    SCOPED_TRACE("polrig " + args);
    const Result r = polrig(args);
    if (status < 0)
      EXPECT_NE(r.status, 0);
    else
      EXPECT_EQ(r.status, status) << "stderr: " << r.err;
    for (const std::string& n : needles) EXPECT_HAS(r.err, n);
    EXPECT_FALSE(fs::exists(out)) << out;
    EXPECT_TRUE(leftovers(out.parent_path(), out.filename().string()).empty());
    EXPECT_EQ(r.out.find("wrote"), std::string::npos) << r.out;
  }

  // A measured CSV with only theta_R_deg,V1,V2,V3 taken from a dataset's stops.csv, the cells
  // copied as text; `rows` selects and orders the stops (all when empty).
  static std::string measured_from(const fs::path& stops_csv, const std::vector<int>& rows = {}) {
    const Csv s = read_csv(stops_csv);
    const std::size_t c[4] = {s.col("theta_R_deg"), s.col("V1"), s.col("V2"), s.col("V3")};
    std::string text = "theta_R_deg,V1,V2,V3\n";
    std::vector<int> pick = rows;
    if (pick.empty())
      for (std::size_t n = 0; n < s.rows.size(); ++n) pick.push_back(static_cast<int>(n));
    for (int n : pick) {
      const auto& row = s.rows.at(static_cast<std::size_t>(n));
      text += row[c[0]] + "," + row[c[1]] + "," + row[c[2]] + "," + row[c[3]] + "\n";
    }
    return text;
  }
};

// ---------------------------------------------------------------------------------------------
// calibrate
// ---------------------------------------------------------------------------------------------

TEST_F(CliCalibration, CalibrateCsWritesTheReport) {
  const fs::path sim = simulate();
  const fs::path cal = tmp / "cal";
  const Result r =
      ok("calibrate " + shell_quote(sim) + " --method cs -o " + shell_quote(cal) + " --no-plots");
  EXPECT_HAS(r.out, "wrote " + cal.string());
  EXPECT_HAS(r.out, "d_a = 0.55 (the rig's device.d)");

  const YAML::Node params = YAML::LoadFile((cal / "params.yaml").string());
  EXPECT_EQ(params["method"].as<std::string>(""), "cs");
  EXPECT_EQ(params["d_a"].as<double>(0), 0.55);  // the dataset rig's d
  EXPECT_EQ(params["d_a_source"].as<std::string>(""), "the rig's device.d");
  EXPECT_EQ(params["fit"]["observations"].as<int>(0), 57);
  // The fit's summary: how it ended, and the same one-line report on stdout.
  EXPECT_EQ(params["fit"]["termination"].as<std::string>(""), "converged");
  EXPECT_TRUE(params["fit"]["usable"].as<bool>(false));
  EXPECT_GT(params["fit"]["iterations"].as<int>(0), 0);
  EXPECT_LT(params["fit"]["final_cost_V2"].as<double>(1), params["fit"]["initial_cost_V2"].as<double>(0));
  EXPECT_HAS(r.out, "fit: " + params["fit"]["brief_report"].as<std::string>(""));
  EXPECT_HAS(r.out, "fit: converged: ");
  const polrig::LoadedParams loaded = polrig::read_params_yaml(cal / "params.yaml");
  // Close to the rig's truth (Table 2): the CS calibration recovers the device.
  const polrig::CalibrationParams truth = polrig::CalibrationParams::wang2019_indoor();
  for (int m = 0; m < 6; ++m) EXPECT_NEAR(loaded.params.alpha_deg[m], truth.alpha_deg[m], 0.05);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(loaded.params.kv[i], truth.kv[i], 2e-3);

  const Csv points = read_csv(cal / "points.csv");
  EXPECT_EQ(points.header,
            (std::vector<std::string>{"theta_ref_deg", "V1", "V2", "V3", "V1_model", "V2_model",
                                      "V3_model", "V1_fitted", "V2_fitted", "V3_fitted"}));
  ASSERT_EQ(points.rows.size(), 19u);
  for (std::size_t n = 0; n < 19; ++n) {
    SCOPED_TRACE(n);
    EXPECT_EQ(std::stod(points.rows[n][0]), 10.0 * static_cast<double>(n));
    for (std::size_t c = 7; c < 10; ++c) EXPECT_EQ(points.rows[n][c], "1");  // cs fits all
  }

  const Csv errors = read_csv(cal / "errors.csv");
  EXPECT_EQ(errors.header, (std::vector<std::string>{"theta_ref_deg", "section", "err12_deg",
                                                     "err13_deg", "err23_deg", "errsec_deg", "d"}));
  EXPECT_EQ(errors.rows.size(), 19u);

  const Csv acc = read_csv(cal / "accuracy.csv");
  EXPECT_EQ(acc.header, (std::vector<std::string>{"angle", "max_deg", "min_deg", "accuracy_deg"}));
  ASSERT_EQ(acc.rows.size(), 4u);
  const char* names[4] = {"theta12", "theta13", "theta23", "theta_sec"};
  for (int k = 0; k < 4; ++k) {
    SCOPED_TRACE(names[k]);
    EXPECT_EQ(acc.rows[k][0], names[k]);
    const double a = std::stod(acc.rows[k][3]);
    EXPECT_GT(a, 0.0);
    EXPECT_LT(a, 0.01);  // CS removes the eccentricity: a few thousandths of a degree
    EXPECT_NEAR(a, 0.5 * (std::stod(acc.rows[k][1]) - std::stod(acc.rows[k][2])), 1e-15);
  }
  EXPECT_EQ(params["accuracy_deg"]["theta_sec"].as<std::string>(""), acc.rows[3][3]);

  const Csv rep = read_csv(cal / "replacement.csv");
  EXPECT_EQ(rep.header, (std::vector<std::string>{"replaced", "accuracy_deg"}));
  ASSERT_EQ(rep.rows.size(), 16u);
  EXPECT_EQ(rep.rows.front()[0], "none");
  EXPECT_EQ(rep.rows.front()[1], acc.rows[3][3]);  // nothing replaced: the θ_sec accuracy

  const YAML::Node manifest = YAML::LoadFile((cal / "manifest.yaml").string());
  ASSERT_TRUE(manifest["inputs"].IsSequence());
  ASSERT_EQ(manifest["inputs"].size(), 2u);  // the voltages and the rig that described the sensor
  EXPECT_EQ(manifest["inputs"][0].as<std::string>(""), (sim / "stops.csv").string());
  EXPECT_EQ(manifest["inputs"][1].as<std::string>(""), (sim / "rig.yaml").string());
  for (const char* f : {"params.yaml", "points.csv", "errors.csv", "accuracy.csv",
                        "replacement.csv", "model_curve.csv"}) {
    SCOPED_TRACE(f);
    EXPECT_TRUE(manifest["files"][f].IsMap());
    EXPECT_TRUE(fs::exists(cal / f));
  }
  EXPECT_HAS(manifest["command"].as<std::string>(""), "polrig calibrate");
  // --no-plots: no PNG files.
  for (const auto& e : fs::directory_iterator(cal))
    EXPECT_NE(e.path().extension(), ".png") << e.path();
  EXPECT_TRUE(leftovers(tmp, "cal").empty());
}

TEST_F(CliCalibration, MeasuredCsvCalibratesExactlyLikeTheDataset) {
  const fs::path sim = simulate();
  const fs::path csv = tmp / "measured.csv";
  write_file(csv, measured_from(sim / "stops.csv"));
  ASSERT_EQ(lines_of(read_file(csv)).size(), 38u);
  const fs::path from_dataset = tmp / "cal-dataset", from_csv = tmp / "cal-csv";
  ok("calibrate " + shell_quote(sim) + " --method all -o " + shell_quote(from_dataset) +
     " --no-plots");
  ok("calibrate " + shell_quote(csv) + " --method all --d-a 0.55 -o " + shell_quote(from_csv) +
     " --no-plots");
  for (const char* m : {"cs", "section", "cs-nc"}) {
    SCOPED_TRACE(m);
    const auto a = param_lines(from_dataset / m / "params.yaml");
    const auto b = param_lines(from_csv / m / "params.yaml");
    ASSERT_EQ(a.size(), 4u);
    EXPECT_EQ(a, b);
    EXPECT_EQ(read_file(from_dataset / m / "points.csv"), read_file(from_csv / m / "points.csv"));
  }
  const YAML::Node manifest = YAML::LoadFile((from_csv / "cs" / "manifest.yaml").string());
  EXPECT_EQ(manifest["inputs"][0].as<std::string>(""), csv.string());
}

TEST_F(CliCalibration, MethodAllWritesSubfoldersAndComparison) {
  const fs::path sim = simulate();
  const fs::path cal = tmp / "cal";
  const Result r =
      ok("calibrate " + shell_quote(sim) + " --method all -o " + shell_quote(cal) + " --no-plots");
  const std::vector<std::string> methods{"section", "cs", "cs-nc"};
  for (const std::string& m : methods) {
    SCOPED_TRACE(m);
    EXPECT_TRUE(fs::is_directory(cal / m));
    for (const char* f : {"params.yaml", "points.csv", "errors.csv", "accuracy.csv",
                          "replacement.csv", "manifest.yaml"})
      EXPECT_TRUE(fs::exists(cal / m / f)) << f;
    EXPECT_EQ(YAML::LoadFile((cal / m / "params.yaml").string())["method"].as<std::string>(""), m);
    EXPECT_HAS(r.out, m);
  }
  EXPECT_EQ(read_csv(cal / "section" / "points.csv").rows.size(), 37u);  // raw stops
  EXPECT_EQ(read_csv(cal / "cs-nc" / "points.csv").rows.size(), 19u);    // CS points
  const Csv cmp = read_csv(cal / "comparison.csv");
  EXPECT_EQ(cmp.header, (std::vector<std::string>{"method", "theta12_deg", "theta13_deg",
                                                  "theta23_deg", "theta_sec_deg"}));
  ASSERT_EQ(cmp.rows.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    SCOPED_TRACE(methods[k]);
    EXPECT_EQ(cmp.rows[k][0], methods[k]);
    // The comparison repeats each subfolder's accuracy.csv.
    const Csv acc = read_csv(cal / methods[k] / "accuracy.csv");
    ASSERT_EQ(acc.rows.size(), 4u);
    for (std::size_t a = 0; a < 4; ++a) EXPECT_EQ(cmp.rows[k][1 + a], acc.rows[a][3]);
  }
  // The paper's ordering: CS removes the eccentricity the section type suffers from.
  EXPECT_GT(std::stod(cmp.rows[0][4]), 10 * std::stod(cmp.rows[1][4]));
  EXPECT_TRUE(YAML::LoadFile((cal / "manifest.yaml").string())["files"]["comparison.csv"].IsMap());
  EXPECT_FALSE(fs::exists(cal / "comparison.png"));
}

TEST_F(CliCalibration, MethodAllWithPlotsWritesPngFiles) {
  if (!gnuplot_present()) GTEST_SKIP() << "gnuplot is not installed";
  const fs::path sim = simulate();
  const fs::path cal = tmp / "cal";
  ok("calibrate " + shell_quote(sim) + " --method all -o " + shell_quote(cal));
  ASSERT_TRUE(fs::exists(cal / "comparison.png"));
  EXPECT_TRUE(starts_with_png_signature(cal / "comparison.png"));
  for (const char* m : {"section", "cs", "cs-nc"}) {
    SCOPED_TRACE(m);
    ASSERT_TRUE(fs::exists(cal / m / "errors.png"));
    EXPECT_TRUE(starts_with_png_signature(cal / m / "errors.png"));
    EXPECT_TRUE(
        YAML::LoadFile((cal / m / "manifest.yaml").string())["files"]["errors.png"].IsMap());
  }
}

// ---------------------------------------------------------------------------------------------
// apply
// ---------------------------------------------------------------------------------------------

TEST_F(CliCalibration, ApplyTurnsVoltagesIntoAngles) {
  const fs::path sim = simulate();
  const fs::path cal = tmp / "cal";
  ok("calibrate " + shell_quote(sim) + " --method cs -o " + shell_quote(cal) + " --no-plots");

  const auto check = [&](const fs::path& stops, double max_error_deg) {
    SCOPED_TRACE(stops.string());
    const fs::path out = tmp / ("apply-" + stops.parent_path().filename().string());
    const Result r = ok("apply " + shell_quote(cal / "params.yaml") + " " + shell_quote(stops) +
                        " -o " + shell_quote(out) + " --no-plots");
    EXPECT_HAS(r.out, "wrote " + out.string());
    const Csv a = read_csv(out / "angles.csv");
    EXPECT_EQ(a.header, (std::vector<std::string>{"row", "theta_R_deg", "theta12_deg",
                                                  "theta13_deg", "theta23_deg", "theta_sec_deg",
                                                  "section", "d", "error_deg"}));
    EXPECT_EQ(a.rows.size(), 37u);
    double worst = 0;
    for (std::size_t n = 0; n < a.rows.size(); ++n) {
      SCOPED_TRACE(n);
      EXPECT_EQ(a.rows[n].size(), 9u);
      if (a.rows[n].size() != 9u) continue;
      EXPECT_EQ(a.rows[n][0], std::to_string(n));
      EXPECT_EQ(std::stod(a.rows[n][1]), 10.0 * static_cast<double>(n));
      const double err = std::stod(a.rows[n][8]);
      worst = std::max(worst, std::abs(err));
      EXPECT_LT(std::abs(err), max_error_deg);
      EXPECT_NEAR(err, axis_diff(std::stod(a.rows[n][5]), std::stod(a.rows[n][1])), 1e-9);
      EXPECT_NEAR(std::stod(a.rows[n][7]), 0.55, 0.01);
      const int section = std::stoi(a.rows[n][6]);
      EXPECT_GE(section, 0);
      EXPECT_LE(section, 5);
    }
    const YAML::Node m = YAML::LoadFile((out / "manifest.yaml").string());
    EXPECT_TRUE(m["inputs"].IsSequence());
    EXPECT_EQ(m["inputs"].size(), 2u);
    EXPECT_TRUE(m["files"]["angles.csv"].IsMap());
    return worst;
  };
  // The port centred (L_IS = 0, same device and sensor offset): the calibration accounts for
  // everything else, so θ_sec is right to a few thousandths of a degree.
  const fs::path centred = simulate("sim-centred", " --set eccentricity.L_IS=0");
  check(centred / "stops.csv", 0.05);
  // The calibration data themselves: single stops keep the port-offset bias that CS averages
  // out (L_IS = 0.05 mm gives about 0.1°), so the bound is looser there.
  const double worst = check(sim / "stops.csv", 0.2);
  EXPECT_GT(worst, 0.05);  // the bias is real: raw stops are not CS points
}

TEST_F(CliCalibration, ApplyWithoutThetaWritesNanErrors) {
  const fs::path sim = simulate();
  const fs::path cal = tmp / "cal";
  ok("calibrate " + shell_quote(sim) + " --method cs -o " + shell_quote(cal) + " --no-plots");
  std::string text = "V1,V2,V3\n";
  const Csv s = read_csv(sim / "stops.csv");
  for (std::size_t n = 0; n < 3; ++n)
    text += s.rows[n][s.col("V1")] + "," + s.rows[n][s.col("V2")] + "," + s.rows[n][s.col("V3")] + "\n";
  write_file(tmp / "v.csv", text);
  const fs::path out = tmp / "apply";
  ok("apply " + shell_quote(cal / "params.yaml") + " " + shell_quote(tmp / "v.csv") + " -o " +
     shell_quote(out));
  const Csv a = read_csv(out / "angles.csv");
  ASSERT_EQ(a.rows.size(), 3u);
  for (const auto& row : a.rows) {
    EXPECT_EQ(row[1], "nan");
    EXPECT_EQ(row[8], "nan");
  }
  EXPECT_FALSE(fs::exists(out / "errors.png"));  // nothing to plot without a reference
}

// ---------------------------------------------------------------------------------------------
// device.truth_from
// ---------------------------------------------------------------------------------------------

TEST_F(CliCalibration, RigWithTruthFromCalibrationSimulates) {
  const fs::path sim = simulate();
  const fs::path cal = tmp / "cal";
  ok("calibrate " + shell_quote(sim) + " --method cs -o " + shell_quote(cal) + " --no-plots");
  // Relative to the rig file, run from another working directory.
  write_file(tmp / "calibrated.yaml", "device:\n  truth_from: cal/params.yaml\nseed: 5\n");
  const fs::path again = tmp / "again";
  ok("simulate " + shell_quote(tmp / "calibrated.yaml") + " -o " + shell_quote(again) +
         " --no-plots",
     "cd / && ");
  ASSERT_TRUE(fs::exists(again / "stops.csv"));
  EXPECT_EQ(read_csv(again / "stops.csv").rows.size(), 37u);
  const std::string resolved = read_file(again / "rig.yaml");
  EXPECT_EQ(resolved.find("truth_from"), std::string::npos) << resolved;
  const polrig::LoadedParams p = polrig::read_params_yaml(cal / "params.yaml");
  EXPECT_TRUE(polrig::load_rig(again / "rig.yaml").rig.device.truth == p.params);
  // The dataset reproduces itself from its rig.yaml.
  const fs::path third = tmp / "third";
  ok("simulate " + shell_quote(again / "rig.yaml") + " -o " + shell_quote(third) + " --no-plots");
  EXPECT_EQ(read_file(third / "stops.csv"), read_file(again / "stops.csv"));
  // An absolute path works too.
  write_file(tmp / "abs.yaml", "device:\n  truth_from: " + (cal / "params.yaml").string() + "\n");
  ok("simulate " + shell_quote(tmp / "abs.yaml") + " -o " + shell_quote(tmp / "abs") +
     " --no-plots");
}

TEST_F(CliCalibration, RigWithMissingTruthFromFileIsRefused) {
  write_file(tmp / "rig.yaml", "device:\n  truth_from: nothere/params.yaml\n");
  expect_refused("simulate " + shell_quote(tmp / "rig.yaml") + " -o " + shell_quote(tmp / "out") +
                     " --no-plots",
                 tmp / "out", 2,
                 {(tmp / "rig.yaml").string() + ":2: key 'device.truth_from'",
                  (tmp / "nothere" / "params.yaml").string()});
}

// ---------------------------------------------------------------------------------------------
// study calibration
// ---------------------------------------------------------------------------------------------

TEST_F(CliCalibration, StudyCalibrationIsIndependentOfThreadCount) {
  const fs::path a = tmp / "mc1", b = tmp / "mc2";
  ok("study calibration " + shell_quote(kRig) + " --trials 8 -o " + shell_quote(a) +
     " --no-plots --threads 1");
  const Result r = ok("study calibration " + shell_quote(kRig) + " --trials 8 -o " +
                      shell_quote(b) + " --no-plots --threads 2");
  const Csv trials = read_csv(a / "trials.csv");
  EXPECT_EQ(trials.header,
            (std::vector<std::string>{"trial", "seed", "L_IS", "alpha_IS", "L_S", "alpha_S",
                                      "acc_section_deg", "acc_cs_deg", "acc_cs_nc_deg"}));
  ASSERT_EQ(trials.rows.size(), 8u);
  for (std::size_t n = 0; n < 8; ++n) {
    SCOPED_TRACE(n);
    EXPECT_EQ(trials.rows[n][0], std::to_string(n));
    for (std::size_t c = 6; c < 9; ++c) EXPECT_GT(std::stod(trials.rows[n][c]), 0.0);
    // Eccentricity drawn within the defaults: 2 × the rig's L_IS and L_S.
    EXPECT_LE(std::stod(trials.rows[n][2]), 0.1);
    EXPECT_LE(std::stod(trials.rows[n][4]), 0.04);
  }
  const Csv summary = read_csv(a / "summary.csv");
  EXPECT_EQ(summary.header, (std::vector<std::string>{
                                "method", "succeeded", "failed", "median_deg", "p05_deg",
                                "p95_deg", "mean_deg", "converged", "no_convergence",
                                "outside_domain", "rank_deficient", "too_few_observations"}));
  ASSERT_EQ(summary.rows.size(), 3u);
  const char* methods[3] = {"section", "cs", "cs-nc"};
  for (int k = 0; k < 3; ++k) {
    SCOPED_TRACE(methods[k]);
    EXPECT_EQ(summary.rows[k][0], methods[k]);
    EXPECT_EQ(summary.rows[k][1], "8");
    EXPECT_EQ(summary.rows[k][2], "0");
    EXPECT_EQ(summary.rows[k][7], "8");  // every fit converged
    for (std::size_t c = 8; c < 12; ++c) EXPECT_EQ(summary.rows[k][c], "0");
  }
  EXPECT_FALSE(fs::exists(a / "failures.csv"));
  EXPECT_EQ(read_file(a / "trials.csv"), read_file(b / "trials.csv"))
      << "trials.csv differs between 1 and 2 threads";
  EXPECT_EQ(read_file(a / "summary.csv"), read_file(b / "summary.csv"));
  EXPECT_HAS(r.out, "wrote " + b.string());
  EXPECT_TRUE(fs::exists(a / "manifest.yaml"));
  EXPECT_TRUE(fs::exists(a / "rig.yaml"));
}

// ---------------------------------------------------------------------------------------------
// bad input writes nothing
// ---------------------------------------------------------------------------------------------

TEST_F(CliCalibration, StudyCalibrationRefusesAScheduleWithUnpairedStopsUpFront) {
  // 0°..270°: 100°..170° have no partner 180° away. That is the rig's error, the same for every
  // trial, said once before any work (it used to escape the trial loop as an exception).
  const fs::path a = tmp / "unpaired";
  expect_refused("study calibration " + shell_quote(kRig) + " --trials 4 --set schedule.stop_deg=270 -o " +
                     shell_quote(a),
                 a, 3, {"the rig's schedule: stop 10 (theta_R = 100°) has no partner 180° away"});
}

TEST_F(CliCalibration, StudyCalibrationCountsTerminationTypes) {
  // Light too weakly polarized for any calibration: every fit ends rank deficient, and the
  // study says so instead of failing.
  const fs::path a = tmp / "weak";
  const Result r = ok("study calibration " + shell_quote(kRig) + " --trials 3 --set device.d=0.015 "
                      "--d-a 0.5 -o " + shell_quote(a) + " --no-plots");
  EXPECT_HAS(r.out, "3 failed; fits: 3 rank_deficient");
  const Csv summary = read_csv(a / "summary.csv");
  ASSERT_EQ(summary.rows.size(), 3u);
  for (const auto& row : summary.rows) {
    SCOPED_TRACE(row[0]);
    EXPECT_EQ(row[summary.col("failed")], "3");
    EXPECT_EQ(row[summary.col("rank_deficient")], "3");
    EXPECT_EQ(row[summary.col("converged")], "0");
  }
  const Csv failures = read_csv(a / "failures.csv");
  EXPECT_EQ(failures.header, (std::vector<std::string>{"trial", "method", "termination",
                                                       "iterations", "evaluations", "reason"}));
  ASSERT_EQ(failures.rows.size(), 9u);
  for (const auto& row : failures.rows) {
    EXPECT_EQ(row[2], "rank_deficient");
    EXPECT_HAS(row[5], "too small to calibrate");
  }
}

TEST_F(CliCalibration, MissingInputIsRefused) {
  const fs::path none = tmp / "none.csv";
  expect_refused(
      "calibrate " + shell_quote(none) + " -o " + shell_quote(tmp / "out") + " --no-plots",
      tmp / "out", 2, {none.string() + ": cannot read the file: no such file"});
  // A missing dataset folder names the path given.
  expect_refused(
      "calibrate " + shell_quote(tmp / "nosim") + " -o " + shell_quote(tmp / "out") + " --no-plots",
      tmp / "out", 2, {(tmp / "nosim").string()});
}

TEST_F(CliCalibration, CsvMissingAColumnIsRefused) {
  write_file(tmp / "nov3.csv", "theta_R_deg,V1,V2\n0,0.1,0.2\n");
  expect_refused("calibrate " + shell_quote(tmp / "nov3.csv") + " -o " + shell_quote(tmp / "out") +
                     " --no-plots",
                 tmp / "out", 2, {(tmp / "nov3.csv").string() + ":1: missing column 'V3'"});
}

TEST_F(CliCalibration, CsvWithTextInANumberIsRefused) {
  const fs::path sim = simulate();
  std::vector<std::string> lines = lines_of(measured_from(sim / "stops.csv"));
  std::vector<std::string> f = split(lines[3]);  // line 4 of the file
  f[1] = "abc";
  lines[3] = f[0] + "," + f[1] + "," + f[2] + "," + f[3];
  std::string text;
  for (const std::string& l : lines) text += l + "\n";
  const fs::path csv = tmp / "abc.csv";
  write_file(csv, text);
  expect_refused("calibrate " + shell_quote(csv) + " --method cs -o " + shell_quote(tmp / "out") +
                     " --no-plots",
                 tmp / "out", 2,
                 {csv.string() + ":4:", "'V1'",
                  csv.string() + ":4: column 'V1': expected a finite number, got 'abc'"});
}

TEST_F(CliCalibration, EmptyCsvIsRefused) {
  write_file(tmp / "empty.csv", "");
  expect_refused("calibrate " + shell_quote(tmp / "empty.csv") + " -o " + shell_quote(tmp / "out") +
                     " --no-plots",
                 tmp / "out", 2, {(tmp / "empty.csv").string() + ": the file is empty"});
  write_file(tmp / "header.csv", "theta_R_deg,V1,V2,V3\n");
  expect_refused("calibrate " + shell_quote(tmp / "header.csv") + " -o " +
                     shell_quote(tmp / "out") + " --no-plots",
                 tmp / "out", 2, {(tmp / "header.csv").string() + ": no data rows"});
}

TEST_F(CliCalibration, TooFewStopsIsRefused) {
  const fs::path sim = simulate();
  write_file(tmp / "five.csv", measured_from(sim / "stops.csv", {0, 1, 2, 3, 4}));
  expect_refused("calibrate " + shell_quote(tmp / "five.csv") + " --method section -o " +
                     shell_quote(tmp / "out") + " --no-plots",
                 tmp / "out", 3, {"cannot calibrate", "5 stops to fit", "at least 6"});
}

TEST_F(CliCalibration, UnpairedStopIsRefusedForCentralSymmetry) {
  const fs::path sim = simulate();
  // 0, 10, …, 350 (all paired) plus 185 on line 38: only 185 has no partner.
  std::vector<int> rows;
  for (int n = 0; n < 36; ++n) rows.push_back(n);
  std::string text = measured_from(sim / "stops.csv", rows);
  // The 185° row carries stop 18's voltages.
  const std::string line18 = lines_of(measured_from(sim / "stops.csv", {18}))[1];
  const std::string odd = "185" + line18.substr(line18.find(',')) + "\n";
  ASSERT_EQ(line18.rfind("180,", 0), 0u) << line18;
  text += odd;
  const fs::path csv = tmp / "unpaired.csv";
  write_file(csv, text);
  expect_refused(
      "calibrate " + shell_quote(csv) + " --method cs -o " + shell_quote(tmp / "out") +
          " --no-plots",
      tmp / "out", 3,
      {csv.string() + ":38 (theta_R = 185°) has no partner 180° away", "the section method does not"});
  // The brief's schedule 0, 10, …, 170 plus 185: no stop has a partner; the first is named.
  rows.resize(18);
  std::string half = measured_from(sim / "stops.csv", rows) + odd;
  write_file(tmp / "half.csv", half);
  expect_refused("calibrate " + shell_quote(tmp / "half.csv") + " --method cs -o " +
                     shell_quote(tmp / "out") + " --no-plots",
                 tmp / "out", 3,
                 {(tmp / "half.csv").string() + ":2 (theta_R = 0°) has no partner 180° away"});
  // The section method takes the same file.
  ok("calibrate " + shell_quote(csv) + " --method section --d-a 0.55 -o " +
     shell_quote(tmp / "sec") + " --no-plots");
  EXPECT_EQ(read_csv(tmp / "sec" / "points.csv").rows.size(), 37u);
}

TEST_F(CliCalibration, UnpolarizedLightIsRefused) {
  // Unpolarized light on the default rig's device: V_i = k_i at every stop. Nothing to
  // calibrate; the command must not write a "calibration" (with kv ≈ 0) that apply then rejects.
  std::string text = "theta_R_deg,V1,V2,V3\n";
  for (int n = 0; n <= 36; ++n) text += std::to_string(10 * n) + ",-0.0101519,0.007923,-0.0094542\n";
  write_file(tmp / "unpolarized.csv", text);
  expect_refused("calibrate " + shell_quote(tmp / "unpolarized.csv") +
                     " --method cs --d-a 0.55 -o " + shell_quote(tmp / "out") + " --no-plots",
                 tmp / "out", 3, {"cannot calibrate", "too small"});
}

TEST_F(CliCalibration, ACorruptedColumnIsRefusedWithTheFitSummary) {
  // Issue 8 §3.6: V2 replaced by numbers unrelated to the angle. The fit stops within its
  // limits and says how it ended; nothing is written.
  const fs::path sim = simulate();
  const Csv s = read_csv(sim / "stops.csv");
  std::string text = "theta_R_deg,V1,V2,V3\n";
  for (std::size_t n = 0; n < s.rows.size(); ++n)
    text += s.rows[n][s.col("theta_R_deg")] + "," + s.rows[n][s.col("V1")] + "," +
            fmt::format("{}", 0.4 * std::sin(7.3 * static_cast<double>(n * n))) + "," +
            s.rows[n][s.col("V3")] + "\n";
  write_file(tmp / "corrupt.csv", text);
  for (const char* method : {"section", "cs", "cs-nc"}) {
    SCOPED_TRACE(method);
    const Result r = polrig("calibrate " + shell_quote(tmp / "corrupt.csv") + " --method " +
                            method + " -o " + shell_quote(tmp / "out") + " --no-plots");
    EXPECT_EQ(r.status, 3) << r.err;
    EXPECT_HAS(r.err, std::string("method ") + method + ": the fit is not usable: ");
    EXPECT_HAS(r.err, " iterations, ");
    EXPECT_LACKS(r.err, "nan");
    EXPECT_FALSE(fs::exists(tmp / "out"));
  }
}

TEST_F(CliCalibration, AnOverflowingSwingIsNamedNotNan) {
  // Issue 8 §3.10: a swing so large that 10^(swing/v_dec) overflowed made the message read
  // "the light's degree of polarization is about -nan". Two pairs swinging by 50 V (100
  // decades at 0.5 V per decade) give d = 1 in double precision: the swing is named instead.
  const fs::path sim = simulate();
  std::vector<std::string> l = lines_of(measured_from(sim / "stops.csv"));
  l[3] = "20,50,50,0.1";
  std::string text;
  for (const std::string& x : l) text += x + "\n";
  write_file(tmp / "swing.csv", text);
  // Beyond any ADC's range: refused as input, naming file, line, column and value.
  l[3] = "20,0.1,1e200,0.1";
  text.clear();
  for (const std::string& x : l) text += x + "\n";
  write_file(tmp / "huge.csv", text);
  expect_refused("calibrate " + shell_quote(tmp / "huge.csv") + " -o " + shell_quote(tmp / "out") +
                     " --no-plots",
                 tmp / "out", 2,
                 {(tmp / "huge.csv").string() + ":4: column 'V2': 1e+200 V is outside any ADC's range"});
  for (const char* method : {"section", "cs", "cs-nc"}) {
    SCOPED_TRACE(method);
    const Result r = polrig("calibrate " + shell_quote(tmp / "swing.csv") + " --method " + method +
                            " -o " + shell_quote(tmp / "out") + " --no-plots");
    EXPECT_EQ(r.status, 3) << r.err;
    EXPECT_HAS(r.err, "outside_domain: not fitted, ");
    EXPECT_HAS(r.err, "more than any degree of polarization below 1 can give");
    EXPECT_LACKS(r.err, "nan");
    EXPECT_FALSE(fs::exists(tmp / "out"));
  }
}

TEST_F(CliCalibration, UnknownMethodIsRefused) {
  const fs::path sim = simulate();
  expect_refused("calibrate " + shell_quote(sim) + " --method bogus -o " +
                     shell_quote(tmp / "out") + " --no-plots",
                 tmp / "out", 2, {"--method bogus: expected section, cs, cs-nc, nc, all, dofp, four-camera or unit-array"});
}

TEST_F(CliCalibration, ApplyWithParamsMissingKdIsRefused) {
  const fs::path sim = simulate();
  const fs::path cal = tmp / "cal";
  ok("calibrate " + shell_quote(sim) + " --method cs -o " + shell_quote(cal) + " --no-plots");
  std::string text;
  for (const std::string& l : lines_of(read_file(cal / "params.yaml")))
    if (l.rfind("kd:", 0) != 0) text += l + "\n";
  ASSERT_NE(text.size(), read_file(cal / "params.yaml").size());
  write_file(tmp / "nokd.yaml", text);
  expect_refused("apply " + shell_quote(tmp / "nokd.yaml") + " " + shell_quote(sim / "stops.csv") +
                     " -o " + shell_quote(tmp / "out") + " --no-plots",
                 tmp / "out", 2, {(tmp / "nokd.yaml").string() + ": missing key 'kd'"});
  // Voltages with a bad cell: the voltages file, line and column.
  write_file(tmp / "v.csv", "V1,V2,V3\n0.1,0.2,0.3\n0.1,x,0.3\n");
  expect_refused("apply " + shell_quote(cal / "params.yaml") + " " + shell_quote(tmp / "v.csv") +
                     " -o " + shell_quote(tmp / "out") + " --no-plots",
                 tmp / "out", 2, {(tmp / "v.csv").string() + ":3: column 'V2'"});
}

TEST_F(CliCalibration, ApplyRefusesValuesOutsideTheirPhysicalRange) {
  // Issue 8 §3.3: volts_per_decade = 1e-300 in params.yaml, or a voltage of 1e300, cast NaN to
  // int in section_of and wrote −nan angles with section −2, exit 0.
  const fs::path sim = simulate();
  const fs::path cal = tmp / "cal";
  ok("calibrate " + shell_quote(sim) + " --method cs -o " + shell_quote(cal) + " --no-plots");
  const std::string params = read_file(cal / "params.yaml");
  const auto with_line = [&](const std::string& key, const std::string& line) {
    std::string text;
    int at = 0, n = 0;
    for (const std::string& l : lines_of(params)) {
      ++n;
      if (l.rfind(key + ":", 0) == 0) {
        text += line + "\n";
        at = n;
      } else {
        text += l + "\n";
      }
    }
    EXPECT_GT(at, 0) << key;
    return std::pair{text, at};
  };
  write_file(tmp / "v.csv", "V1,V2,V3\n0.1,0.2,0.1\n0.1,0.2,0.1\n");
  const auto [tiny, tiny_line] = with_line("volts_per_decade", "volts_per_decade: 1e-300");
  write_file(tmp / "tiny.yaml", tiny);
  expect_refused("apply " + shell_quote(tmp / "tiny.yaml") + " " + shell_quote(tmp / "v.csv") +
                     " -o " + shell_quote(tmp / "out") + " --no-plots",
                 tmp / "out", 2,
                 {fmt::format("{}:{}: key 'volts_per_decade': expected a value in [0.01, 10]",
                              (tmp / "tiny.yaml").string(), tiny_line),
                  "got 1e-300"});

  // A voltage no ADC gives: file, line, column and value.
  write_file(tmp / "huge.csv", "V1,V2,V3\n0.1,0.2,0.1\n0.1,1e300,0.1\n");
  expect_refused("apply " + shell_quote(cal / "params.yaml") + " " + shell_quote(tmp / "huge.csv") +
                     " -o " + shell_quote(tmp / "out") + " --no-plots",
                 tmp / "out", 2,
                 {(tmp / "huge.csv").string() + ":3: column 'V2': 1e+300 V is outside any ADC's range"});
  // Within an ADC's range but hundreds of decades of light ratio at the smallest scale.
  const auto [small, small_line] = with_line("volts_per_decade", "volts_per_decade: 0.01");
  write_file(tmp / "small.yaml", small);
  write_file(tmp / "four.csv", "V1,V2,V3\n0.1,0.2,0.1\n4,-4,4\n");
  expect_refused("apply " + shell_quote(tmp / "small.yaml") + " " + shell_quote(tmp / "four.csv") +
                     " -o " + shell_quote(tmp / "out") + " --no-plots",
                 tmp / "out", 2, {(tmp / "four.csv").string() + ":3: column 'V1': 4 V is ", "decades"});
  // Parameters under which a row has no finite angle (all films at one angle: the linear
  // system in d·cos2θ, d·sin2θ is singular).
  const auto [flat, flat_line] = with_line("alpha_deg", "alpha_deg: [0, 0, 0, 0, 0, 0]");
  write_file(tmp / "flat.yaml", flat);
  expect_refused("apply " + shell_quote(tmp / "flat.yaml") + " " + shell_quote(tmp / "v.csv") +
                     " -o " + shell_quote(tmp / "out") + " --no-plots",
                 tmp / "out", 2,
                 {(tmp / "v.csv").string() + ":2: V1 = 0.1, V2 = 0.2, V3 = 0.1 give no finite angle"});
}

TEST_F(CliCalibration, ParamsWithADuplicateKeyAreRefused) {
  const fs::path sim = simulate();
  const fs::path cal = tmp / "cal";
  ok("calibrate " + shell_quote(sim) + " --method cs -o " + shell_quote(cal) + " --no-plots");
  const std::string params = read_file(cal / "params.yaml");
  int kv_line = 0, n = 0;
  for (const std::string& l : lines_of(params)) {
    ++n;
    if (l.rfind("kv:", 0) == 0) kv_line = n;
  }
  ASSERT_GT(kv_line, 0);
  write_file(tmp / "dup.yaml", params + "kv: [1, 1, 1]\n");
  expect_refused("apply " + shell_quote(tmp / "dup.yaml") + " " + shell_quote(sim / "stops.csv") +
                     " -o " + shell_quote(tmp / "out") + " --no-plots",
                 tmp / "out", 2,
                 {fmt::format("{}:{}: key 'kv': duplicate key (first at line {})",
                              (tmp / "dup.yaml").string(), n + 1, kv_line)});
}

TEST_F(CliCalibration, DaOutsideTheUnitIntervalIsRejectedByTheParser) {
  const fs::path sim = simulate();
  expect_refused(
      "calibrate " + shell_quote(sim) + " --d-a 1.5 -o " + shell_quote(tmp / "out") + " --no-plots",
      tmp / "out", -1, {"--d-a"});
  expect_refused(
      "calibrate " + shell_quote(sim) + " --d-a 0 -o " + shell_quote(tmp / "out") + " --no-plots",
      tmp / "out", -1, {"--d-a"});
}

}  // namespace
