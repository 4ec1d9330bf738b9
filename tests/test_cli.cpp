// End-to-end tests of the polrig executable: each test runs the real program in a fresh
// temporary folder and inspects the files it writes (or does not write).
#include <gtest/gtest.h>
#include <yaml-cpp/binary.h>
#include <yaml-cpp/yaml.h>

#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "polrig/io/rig_yaml.h"
#include "polrig/io/sweep_h5.h"
#include "polrig/io/sweep_state.h"
#include "polrig/rig/rig.h"
#include "support.h"

namespace fs = std::filesystem;
using namespace polrig::test;

namespace {

const std::string& kRig = kDefaultRigFile;

class Cli : public PolrigTest {
 protected:
  Cli() : PolrigTest("polrig_test_cli_", "") {}

  // Entries of `parent` that are staging or backup folders of `name`.
  static std::vector<std::string> leftovers(const fs::path& parent, const std::string& name) {
    return entries_where(parent, [&](const std::string& f) {
      return f.rfind("." + name + ".partial-", 0) == 0 || f.rfind("." + name + ".old-", 0) == 0;
    });
  }
};

std::string dir_arg(const fs::path& p) { return shell_quote(p); }

// Two sweep.h5 files hold the same values, bit for bit, in every column (their manifests
// may differ: another command line).
void expect_same_sweep_columns(const fs::path& a, const fs::path& b, std::size_t points) {
  const polrig::SweepH5Reader ra(a), rb(b);
  std::vector<double> va(points), vb(points);
  for (int i = 1; i <= 3; ++i)
    for (const char* c : {"bsd_mV", "asd_mV", "asd_bsd_pct", "mean_br_mV", "mean_mr_mV", "eq6_mV", "eq6_dev_pct"}) {
      const std::string name = "pair" + std::to_string(i) + "_" + c;
      ra.read(name, 0, va);
      rb.read(name, 0, vb);
      EXPECT_EQ(std::memcmp(va.data(), vb.data(), points * sizeof(double)), 0) << name << " differs";
    }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// simulate
// ---------------------------------------------------------------------------------------------

TEST_F(Cli, SimulateWritesStopsCsv) {
  const fs::path out = tmp / "sim";
  const Result r = ok("simulate " + shell_quote(kRig) + " -o " + dir_arg(out) + " --no-plots");
  EXPECT_HAS(r.out, "wrote " + out.string());
  const Csv csv = read_csv(out / "stops.csv");
  EXPECT_EQ(lines_of(read_file(out / "stops.csv"))[0].rfind("stop,theta_R_deg,theta_deg,d,", 0),
            0u)
      << read_file(out / "stops.csv").substr(0, 200);
  const std::set<std::string> columns(csv.header.begin(), csv.header.end());
  for (const char* c : {"V1", "V2", "V3"}) EXPECT_TRUE(columns.count(c)) << "no column " << c;
  ASSERT_EQ(csv.rows.size(), 37u);
  for (std::size_t i = 0; i < csv.rows.size(); ++i) {
    SCOPED_TRACE(i);
    ASSERT_EQ(csv.rows[i].size(), csv.header.size());
    EXPECT_EQ(std::stod(csv.rows[i][0]), static_cast<double>(i));
    EXPECT_DOUBLE_EQ(std::stod(csv.rows[i][1]), 10.0 * static_cast<double>(i));
  }
  // --no-plots: no PNG files.
  EXPECT_FALSE(fs::exists(out / "voltages.png"));
  EXPECT_FALSE(fs::exists(out / "deviations.png"));
  EXPECT_TRUE(leftovers(tmp, "sim").empty());
}

TEST_F(Cli, SimulateIsIndependentOfThreadCount) {
  const fs::path a = tmp / "t1", b = tmp / "t2", c = tmp / "t2-nosamples";
  ok("simulate " + shell_quote(kRig) + " -o " + dir_arg(a) + " --no-plots --samples --threads 1");
  ok("simulate " + shell_quote(kRig) + " -o " + dir_arg(b) + " --no-plots --samples --threads 2");
  ok("simulate " + shell_quote(kRig) + " -o " + dir_arg(c) + " --no-plots --threads 2");
  const std::string stops = read_file(a / "stops.csv");
  ASSERT_FALSE(stops.empty());
  EXPECT_EQ(stops, read_file(b / "stops.csv")) << "stops.csv differs between 1 and 2 threads";
  EXPECT_EQ(stops, read_file(c / "stops.csv")) << "stops.csv depends on --samples";
  const std::string samples = read_file(a / "samples.csv");
  ASSERT_FALSE(samples.empty());
  EXPECT_EQ(samples, read_file(b / "samples.csv")) << "samples.csv differs between 1 and 2 threads";
  EXPECT_FALSE(fs::exists(c / "samples.csv"));
  const Csv csv = read_csv(a / "samples.csv");
  EXPECT_EQ(csv.header, (std::vector<std::string>{"stop", "theta_R_deg", "sample", "V1", "V2",
                                                  "V3"}));
  EXPECT_EQ(csv.rows.size(), 37u * 40u);
  // The rig files in both datasets are identical too.
  EXPECT_EQ(read_file(a / "rig.yaml"), read_file(b / "rig.yaml"));
}

TEST_F(Cli, SimulateWithPlotsWritesPngFiles) {
  if (!gnuplot_present()) GTEST_SKIP() << "gnuplot is not installed";
  const fs::path out = tmp / "plots";
  ok("simulate " + shell_quote(kRig) + " -o " + dir_arg(out));
  for (const char* png : {"voltages.png", "deviations.png"}) {
    SCOPED_TRACE(png);
    ASSERT_TRUE(fs::exists(out / png));
    EXPECT_TRUE(starts_with_png_signature(out / png));
  }
  const YAML::Node manifest = YAML::LoadFile((out / "manifest.yaml").string());
  EXPECT_TRUE(manifest["files"]["voltages.png"].IsMap());
  EXPECT_TRUE(manifest["files"]["deviations.png"].IsMap());
}

TEST_F(Cli, ManifestRecordsEverythingNeededToReproduce) {
  const fs::path out = tmp / "sim";
  ok("simulate " + shell_quote(kRig) + " -o " + dir_arg(out) +
     " --no-plots --set seed=7 --set device.d=0.3");
  ASSERT_TRUE(fs::exists(out / "manifest.yaml"));
  const YAML::Node m = YAML::LoadFile((out / "manifest.yaml").string());
  for (const char* key : {"git_revision", "version", "seed", "rig_text", "rig_resolved", "files"}) {
    SCOPED_TRACE(key);
    EXPECT_TRUE(m[key].IsDefined()) << "manifest.yaml has no '" << key << "'";
  }
  EXPECT_FALSE(m["git_revision"].as<std::string>("").empty());
  EXPECT_FALSE(m["version"].as<std::string>("").empty());
  EXPECT_EQ(m["seed"].as<std::uint64_t>(0), 7u);
  EXPECT_EQ(m["rig_text"].as<std::string>(""), read_file(kRig));
  EXPECT_EQ(m["rig_resolved"].as<std::string>(""), read_file(out / "rig.yaml"));
  EXPECT_EQ(m["rig_file"].as<std::string>(""), kRig);
  ASSERT_TRUE(m["overrides"].IsSequence());
  ASSERT_EQ(m["overrides"].size(), 2u);
  EXPECT_EQ(m["overrides"][0].as<std::string>(), "seed=7");
  EXPECT_EQ(m["overrides"][1].as<std::string>(), "device.d=0.3");
  EXPECT_HAS(m["command"].as<std::string>(""), "polrig simulate");
  ASSERT_TRUE(m["files"].IsMap());
  EXPECT_EQ(m["files"]["stops.csv"]["schema"].as<int>(0), 1);
  EXPECT_TRUE(m["files"]["rig.yaml"].IsMap());
  // Nothing in the manifest depends on the time of the run: two runs give the same manifest
  // up to the output folder in the command line.
  const fs::path out2 = tmp / "sim2";
  ok("simulate " + shell_quote(kRig) + " -o " + dir_arg(out2) +
     " --no-plots --set seed=7 --set device.d=0.3");
  std::string m2 = read_file(out2 / "manifest.yaml");
  const std::string from = out2.string(), to = out.string();
  for (auto pos = m2.find(from); pos != std::string::npos; pos = m2.find(from, pos + to.size()))
    m2.replace(pos, from.size(), to);
  EXPECT_EQ(read_file(out / "manifest.yaml"), m2);
}

TEST_F(Cli, ManifestRigTextIsTheFileTextExactly) {
  // rig_text is documented as the rig file's text: it must survive any valid rig file, also
  // one without a final newline, with trailing blank lines or with an indented first line.
  const std::vector<std::pair<std::string, std::string>> files = {
      {"no-final-newline.yaml", "seed: 5"},
      {"trailing-blank-lines.yaml", "seed: 5\n\n\n"},
      {"indented.yaml", "  seed: 5\n  device:\n    d: 0.4\n"},
  };
  for (const auto& [name, text] : files) {
    SCOPED_TRACE(name);
    write_file(tmp / name, text);
    const fs::path out = tmp / ("out-" + name);
    ok("simulate " + shell_quote(tmp / name) + " -o " + dir_arg(out) + " --no-plots");
    const YAML::Node m = YAML::LoadFile((out / "manifest.yaml").string());
    EXPECT_EQ(m["rig_text"].as<std::string>("<missing>"), text);
  }
}

// Issue 8: a NUL byte in a rig comment truncated manifest.yaml, and Latin-1 bytes came back as
// U+FFFD. The stored text must be the bytes read: as a YAML string when YAML holds them, else
// in base64 (rig_text_base64); and the dataset still reproduces itself from its rig.yaml.
TEST_F(Cli, ManifestStoresAnyRigTextByteForByte) {
  const std::vector<std::pair<std::string, std::string>> files = {
      {"nul.yaml", std::string("# a NUL \0 in a comment\nseed: 5\n", 31)},
      {"latin1.yaml", "# caf\xe9, \xb5m: Latin-1\nseed: 5\n"},
      {"control.yaml", "# bell \a, escape \x1b, CR\r\nseed: 5\n"},
      {"utf8.yaml", "# θ_R in °, µm\nseed: 5\n"},
  };
  for (const auto& [name, text] : files) {
    SCOPED_TRACE(name);
    ASSERT_EQ(text.find("seed: 5"), text.size() - 8);
    write_file(tmp / name, text);
    ASSERT_EQ(read_file(tmp / name), text);
    const fs::path out = tmp / ("out-" + name), again = tmp / ("again-" + name);
    ok("simulate " + shell_quote(tmp / name) + " -o " + dir_arg(out) + " --no-plots");
    const std::string manifest = read_file(out / "manifest.yaml");
    EXPECT_HAS(manifest, "rig_resolved:");  // the manifest is whole
    const YAML::Node m = YAML::Load(manifest);
    std::string stored;
    if (m["rig_text_base64"]) {
      EXPECT_FALSE(m["rig_text"]) << "both forms";
      const std::vector<unsigned char> bytes = YAML::DecodeBase64(m["rig_text_base64"].as<std::string>());
      stored.assign(bytes.begin(), bytes.end());
    } else {
      stored = m["rig_text"].as<std::string>("<missing>");
    }
    EXPECT_EQ(stored, text);
    ok("simulate " + shell_quote(out / "rig.yaml") + " -o " + dir_arg(again) + " --no-plots");
    EXPECT_EQ(read_file(again / "stops.csv"), read_file(out / "stops.csv"));
  }
  // Text YAML holds stays readable: rig_text, not base64.
  EXPECT_TRUE(YAML::LoadFile((tmp / "out-utf8.yaml" / "manifest.yaml").string())["rig_text"]);
  EXPECT_TRUE(YAML::LoadFile((tmp / "out-latin1.yaml" / "manifest.yaml").string())["rig_text_base64"]);
}

// Usage errors exit 2 naming the word, with the nearest known name when one is near.
TEST_F(Cli, UsageErrorsNameTheWordAndSuggestTheNearestName) {
  Result r = polrig("simualte " + shell_quote(kRig) + " -o " + shell_quote(tmp / "a"));
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, "unknown command 'simualte' (did you mean 'simulate'?)");
  r = polrig("study cz " + shell_quote(kRig) + " -o " + shell_quote(tmp / "a"));
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, "polrig study: unknown command 'cz' (did you mean 'cs'?)");
  r = polrig("simulate " + shell_quote(kRig) + " --sampels -o " + shell_quote(tmp / "a"));
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, "polrig simulate: unknown option '--sampels' (did you mean '--samples'?)");
  r = polrig("simulate " + shell_quote(kRig) + " --threads 0 -o " + shell_quote(tmp / "a"));
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, "--threads");
  // --set takes one KEY=VALUE: `-o` after it is refused as such, not read as its value.
  r = polrig("simulate " + shell_quote(kRig) + " --set -o " + shell_quote(tmp / "a"));
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, "--set");
  EXPECT_HAS(r.err, "expected key.path=value");
  EXPECT_LACKS(r.err, "--out is required");
  // A misspelt rig key, on the command line and in a file.
  r = polrig("simulate " + shell_quote(kRig) + " --set eccentricity.L_SI=0.1 -o " + shell_quote(tmp / "a"));
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, "unknown key 'eccentricity.L_SI' (did you mean 'eccentricity.L_IS'?)");
  write_file(tmp / "typo.yaml", "eccentricity:\n  alhpa_S: 10\n");
  r = polrig("rig show " + shell_quote(tmp / "typo.yaml"));
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, "did you mean 'eccentricity.alpha_S'?");
  // Far from every name: no guess.
  r = polrig("frobnicate -o " + shell_quote(tmp / "a"));
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, "unknown command 'frobnicate'");
  EXPECT_LACKS(r.err, "did you mean");
  EXPECT_FALSE(fs::exists(tmp / "a"));
  // Help and version are not errors.
  EXPECT_EQ(polrig("--help").status, 0);
  EXPECT_EQ(polrig("simulate --help").status, 0);
  EXPECT_EQ(polrig("--version").status, 0);
}

// A study adc that would run for hours is refused before it starts, with the size it would take.
TEST_F(Cli, StudyAdcRefusesWorkBeyondItsBound) {
  Result r = polrig("study adc --d 0.1:0.9:1e8 -o " + shell_quote(tmp / "a"));
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, "100000000 values of d; at most 1000000");
  r = polrig("study adc --d 0.1:0.9:100000 --step 0.001 -o " + shell_quote(tmp / "a"));
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, "1.8e+10 θ steps; at most 2e+09");
  EXPECT_FALSE(fs::exists(tmp / "a"));
}

TEST_F(Cli, RigShowAndRigKeys) {
  const Result show = ok("rig show " + shell_quote(kRig) + " --set device.d=0.3");
  const polrig::Rig shown = polrig::parse_rig(show.out, "rig show").rig;
  EXPECT_EQ(shown.device.d, 0.3);
  polrig::Rig expected = polrig::load_rig(kRig).rig;
  expected.device.d = 0.3;
  EXPECT_EQ(show.out, polrig::rig_to_yaml(expected));

  const Result bad = polrig("rig show " + shell_quote(kRig) + " --set device.d=3");
  EXPECT_NE(bad.status, 0);
  EXPECT_HAS(bad.err, "--set device.d=3: key 'device.d': expected a degree of polarization");

  const Result keys = ok("rig keys");
  EXPECT_HAS(keys.out, "| key | unit | default | accepts | meaning | why this range | read by | sources | instruments |");
  EXPECT_HAS(keys.out, "| six-photodiode |\n");  // device.L_photo: the six-photodiode sensor's
  EXPECT_HAS(keys.out, "| `device.width_px` |");
  EXPECT_HAS(keys.out, "| simulate | cos4 |");  // source.polarizer_deg: read by simulate, and by the cos4 model only
  EXPECT_HAS(keys.out, "| `device.d` |");
  EXPECT_HAS(keys.out, "| `eccentricity.L_IS` | mm | 0.05 |");
  EXPECT_HAS(keys.out, "| `seed` |");
}

TEST_F(Cli, RigYamlInTheDatasetLoadsBackToTheSameRig) {
  const fs::path out = tmp / "sim";
  ok("simulate " + shell_quote(kRig) + " -o " + dir_arg(out) + " --no-plots");
  const polrig::Rig original = polrig::load_rig(kRig).rig;
  const polrig::Rig back = polrig::load_rig(out / "rig.yaml").rig;
  EXPECT_TRUE(back.device.truth == original.device.truth);
  EXPECT_EQ(back.device.d, original.device.d);
  EXPECT_EQ(back.device.ring.beta_deg, original.device.ring.beta_deg);
  EXPECT_EQ(back.device.film_axis_deg, original.device.film_axis_deg);
  EXPECT_EQ(back.source.cos4.L_o, original.source.cos4.L_o);
  EXPECT_EQ(back.source.cos4.E_0, original.source.cos4.E_0);
  EXPECT_EQ(back.eccentricity.L_IS, original.eccentricity.L_IS);
  EXPECT_EQ(back.eccentricity.L_S, original.eccentricity.L_S);
  EXPECT_EQ(back.eccentricity.alpha_S, original.eccentricity.alpha_S);
  EXPECT_EQ(back.schedule.table_angles_deg(), original.schedule.table_angles_deg());
  EXPECT_EQ(back.schedule.samples_per_stop, original.schedule.samples_per_stop);
  EXPECT_EQ(back.electronics.noise_sigma_V, original.electronics.noise_sigma_V);
  EXPECT_EQ(back.electronics.adc_bits, original.electronics.adc_bits);
  EXPECT_EQ(back.seed, original.seed);
  EXPECT_EQ(polrig::rig_to_yaml(back), polrig::rig_to_yaml(original));
}

TEST_F(Cli, DatasetReproducesItself) {
  // With overrides, so that the dataset's rig.yaml (not the original file) carries them.
  const fs::path first = tmp / "first", again = tmp / "again";
  ok("simulate " + shell_quote(kRig) + " -o " + dir_arg(first) +
     " --no-plots --samples --set seed=11 --set eccentricity.L_S=0.3 --set "
     "'device.truth.kv=[1, 1.01, 0.99]'");
  ok("simulate " + shell_quote((first / "rig.yaml").string()) + " -o " + dir_arg(again) +
     " --no-plots --samples");
  const std::string stops = read_file(first / "stops.csv");
  ASSERT_FALSE(stops.empty());
  EXPECT_EQ(stops, read_file(again / "stops.csv"));
  EXPECT_EQ(read_file(first / "samples.csv"), read_file(again / "samples.csv"));
  EXPECT_EQ(read_file(first / "rig.yaml"), read_file(again / "rig.yaml"));
  // And the overrides did change the data (the test is not vacuous).
  const fs::path plain = tmp / "plain";
  ok("simulate " + shell_quote(kRig) + " -o " + dir_arg(plain) + " --no-plots");
  EXPECT_NE(stops, read_file(plain / "stops.csv"));
}

// ---------------------------------------------------------------------------------------------
// studies, sweep, run
// ---------------------------------------------------------------------------------------------

TEST_F(Cli, StudyCsWritesDeviationsAndSummary) {
  const fs::path out = tmp / "cs";
  ok("study cs " + shell_quote(kRig) + " -o " + dir_arg(out) + " --no-plots");
  const Csv dev = read_csv(out / "deviations.csv");
  EXPECT_EQ(dev.header,
            (std::vector<std::string>{"theta_R_deg", "pair", "dv_br_mV", "dv_mr_mV"}));
  ASSERT_EQ(dev.rows.size(), 1080u);
  for (std::size_t k = 0; k < dev.rows.size(); ++k) {
    ASSERT_EQ(dev.rows[k].size(), 4u) << "row " << k;
    ASSERT_EQ(std::stoi(dev.rows[k][1]), static_cast<int>(k / 360) + 1) << "row " << k;
  }
  const Csv sum = read_csv(out / "summary.csv");
  EXPECT_EQ(sum.header, (std::vector<std::string>{"pair", "bsd_mV", "asd_mV", "mean_br_mV",
                                                  "mean_mr_mV", "eq6_mV"}));
  ASSERT_EQ(sum.rows.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(sum.rows[i][0], std::to_string(i + 1));
  EXPECT_TRUE(fs::exists(out / "manifest.yaml"));
  EXPECT_TRUE(fs::exists(out / "rig.yaml"));
}

TEST_F(Cli, SweepWritesTheGridAndIsIndependentOfThreadCount) {
  const std::string grids =
      " --grid eccentricity.L_S=0.001:1:5 --grid eccentricity.L_IS=0.001:1:4";
  const fs::path a = tmp / "sw1", b = tmp / "sw2";
  ok("sweep " + shell_quote(kRig) + grids + " -o " + dir_arg(a) + " --no-plots --csv --threads 1");
  ok("sweep " + shell_quote(kRig) + grids + " -o " + dir_arg(b) + " --no-plots --csv --threads 2");
  const Csv csv = read_csv(a / "sweep.csv");
  ASSERT_GE(csv.header.size(), 3u);
  EXPECT_EQ(csv.header[0], "eccentricity.L_S");
  EXPECT_EQ(csv.header[1], "eccentricity.L_IS");
  EXPECT_EQ(csv.header[2], "pair1_bsd_mV");
  ASSERT_EQ(csv.rows.size(), 20u);
  // Row-major, the last axis fastest; both ends exact.
  EXPECT_EQ(csv.rows.front()[0], "0.001");
  EXPECT_EQ(csv.rows.front()[1], "0.001");
  EXPECT_EQ(csv.rows[3][0], "0.001");
  EXPECT_EQ(csv.rows[3][1], "1");
  EXPECT_EQ(csv.rows[4][0], "0.25075");
  EXPECT_EQ(csv.rows.back()[0], "1");
  EXPECT_EQ(csv.rows.back()[1], "1");
  for (const auto& row : csv.rows) EXPECT_EQ(row.size(), csv.header.size());
  EXPECT_EQ(read_file(a / "sweep.csv"), read_file(b / "sweep.csv"))
      << "sweep.csv differs between 1 and 2 threads";
  expect_same_sweep_columns(a / "sweep.h5", b / "sweep.h5", 20);
}

TEST_F(Cli, SweepWithoutCsvWritesOnlyTheHdf5File) {
  const fs::path out = tmp / "h5only";
  ok("sweep " + shell_quote(kRig) + " --grid eccentricity.L_S=0.001:1:5 -o " + dir_arg(out) + " --no-plots");
  EXPECT_TRUE(fs::exists(out / "sweep.h5"));
  EXPECT_FALSE(fs::exists(out / "sweep.csv"));
  const YAML::Node m = YAML::LoadFile((out / "manifest.yaml").string());
  EXPECT_TRUE(m["files"]["sweep.h5"]);
  EXPECT_FALSE(m["files"]["sweep.csv"]);
}

TEST_F(Cli, SweepOfOneKeyOnTwoAxesNamesTheSecondAxisByItsPosition) {
  const fs::path out = tmp / "twice";
  ok("sweep " + shell_quote(kRig) + " --grid eccentricity.alpha_S=0:10:3 --grid eccentricity.alpha_S=5:15:2 -o " +
     dir_arg(out) + " --no-plots");
  const polrig::SweepH5Reader r(out / "sweep.h5");
  std::vector<double> first(3), second(2);
  r.read("eccentricity.alpha_S", 0, first);
  r.read("eccentricity.alpha_S (axis 2)", 0, second);
  EXPECT_EQ(first, (std::vector<double>{0, 5, 10}));
  EXPECT_EQ(second, (std::vector<double>{5, 15}));
}

// A sweep long enough for several progress reports (200,000 grid points on one thread, seconds).
const std::string kLongSweep = " --grid eccentricity.L_S=0.001:1:400 --grid eccentricity.L_IS=0.001:1:500 --no-plots --threads 1";

TEST_F(Cli, NoProgressLineWhenStderrIsNotATerminal) {
  // ok() sends stderr to a file: nothing may appear there but errors and notes.
  const Result r = ok("sweep " + shell_quote(kRig) + kLongSweep + " -o " + dir_arg(tmp / "sw"));
  EXPECT_EQ(r.err, "");
  EXPECT_EQ(r.out, "wrote " + (tmp / "sw").string() + "\n");
}

TEST_F(Cli, ProgressLineOnATerminalUnlessQuiet) {
  // `script` gives the program a pseudo-terminal as stdin, stdout and stderr.
  if (std::system("command -v script >/dev/null 2>&1") != 0) GTEST_SKIP() << "no `script` to make a terminal";
  const auto on_terminal = [&](const std::string& args, const fs::path& log) {
    const std::string cmd = "script -qec " + shell_quote(shell_quote(kPolrigExe) + " " + args) + " /dev/null > " + shell_quote(log);
    EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
    return read_file(log);
  };
  const std::string shown = on_terminal("sweep " + shell_quote(kRig) + kLongSweep + " -o " + dir_arg(tmp / "a"), tmp / "a.log");
  EXPECT_HAS(shown, "\rpolrig: sweep: grid points  100 %");  // the last report, with the time taken
  EXPECT_HAS(shown, "wrote " + (tmp / "a").string());
  const std::string quiet = on_terminal("sweep " + shell_quote(kRig) + kLongSweep + " --quiet -o " + dir_arg(tmp / "b"), tmp / "b.log");
  EXPECT_EQ(quiet.find("polrig: sweep"), std::string::npos) << quiet;
  EXPECT_HAS(quiet, "wrote " + (tmp / "b").string());
  expect_same_sweep_columns(tmp / "a" / "sweep.h5", tmp / "b" / "sweep.h5", 200000);
}

TEST_F(Cli, StageTimesWhenAsked) {
  // POLRIG_STAGE_TIMES: the sweep's stage, then the command's total, which contains it; on one
  // core the stage's CPU time cannot exceed its wall time (by more than the clocks' ticks).
  // The command on one core (the affinity is inherited): its sink's writer thread shares it.
  const fs::path log = tmp / "stages.csv";
  cpu_set_t all, one;
  ASSERT_EQ(::sched_getaffinity(0, sizeof all, &all), 0);
  CPU_ZERO(&one);
  for (int c = 0; c < CPU_SETSIZE; ++c)
    if (CPU_ISSET(c, &all)) {
      CPU_SET(c, &one);
      break;
    }
  ASSERT_EQ(::sched_setaffinity(0, sizeof one, &one), 0);
  ::setenv("POLRIG_STAGE_TIMES", log.c_str(), 1);
  const Result r = ok("sweep " + shell_quote(kRig) + kLongSweep + " -o " + dir_arg(tmp / "sw"));
  ::unsetenv("POLRIG_STAGE_TIMES");
  ASSERT_EQ(::sched_setaffinity(0, sizeof all, &all), 0);
  EXPECT_EQ(r.err, "");
  const Csv csv = read_csv(log);
  EXPECT_EQ(csv.header, (std::vector<std::string>{"stage", "wall_s", "cpu_s"}));
  ASSERT_GE(csv.rows.size(), 2u);
  EXPECT_EQ(csv.rows.back()[0], "(total)");
  const auto stage = std::find_if(csv.rows.begin(), csv.rows.end(),
                                  [](const std::vector<std::string>& row) { return row[0] == "sweep: grid points"; });
  ASSERT_NE(stage, csv.rows.end());
  const double wall = std::stod((*stage)[1]), cpu = std::stod((*stage)[2]);
  EXPECT_GT(wall, 0.1);  // 200,000 points on one thread
  EXPECT_LE(wall, std::stod(csv.rows.back()[1]));
  EXPECT_LE(cpu, 1.02 * wall + 0.01);
  // Counted, not zero: another test may share the core (under the sanitizers, -j2, it took 49 %).
  EXPECT_GT(cpu, 0.1 * wall);
  // Without the variable, no file.
  fs::remove(log);
  ok("sweep " + shell_quote(kRig) + " --grid eccentricity.L_S=0.001:1:5 --no-plots -o " + dir_arg(tmp / "sw2"));
  EXPECT_FALSE(fs::exists(log));
}

TEST_F(Cli, StudyAdcWritesAccuracyLimits) {
  const fs::path out = tmp / "adc";
  ok("study adc --d 0.05,0.5 -o " + dir_arg(out) + " --no-plots");
  const Csv csv = read_csv(out / "accuracy_limit.csv");
  EXPECT_EQ(csv.header, (std::vector<std::string>{"d", "vmax_mV", "limit_deg"}));
  ASSERT_EQ(csv.rows.size(), 2u);
  EXPECT_EQ(csv.rows[0][0], "0.05");
  EXPECT_EQ(csv.rows[1][0], "0.5");
  // A larger d gives larger voltages and a finer accuracy limit.
  EXPECT_GT(std::stod(csv.rows[1][1]), std::stod(csv.rows[0][1]));
  EXPECT_LT(std::stod(csv.rows[1][2]), std::stod(csv.rows[0][2]));
  EXPECT_TRUE(fs::exists(out / "manifest.yaml"));
}

TEST_F(Cli, RunWritesSimulateCsAndAdc) {
  const fs::path out = tmp / "run";
  const std::string plots = gnuplot_present() ? "" : " --no-plots";
  const Result r = ok("run " + shell_quote(kRig) + " -o " + dir_arg(out) + plots);
  EXPECT_HAS(r.out, "CS study at the rig's eccentricity");
  for (const char* sub : {"simulate", "cs", "adc"}) {
    SCOPED_TRACE(sub);
    EXPECT_TRUE(fs::is_directory(out / sub));
    EXPECT_TRUE(fs::exists(out / sub / "manifest.yaml"));
  }
  EXPECT_EQ(read_csv(out / "simulate" / "stops.csv").rows.size(), 37u);
  EXPECT_EQ(read_csv(out / "cs" / "deviations.csv").rows.size(), 1080u);
  EXPECT_EQ(read_csv(out / "cs" / "summary.csv").rows.size(), 3u);
  EXPECT_EQ(read_csv(out / "adc" / "accuracy_limit.csv").rows.size(), 19u);
  if (plots.empty()) {
    EXPECT_TRUE(starts_with_png_signature(out / "simulate" / "voltages.png"));
    EXPECT_TRUE(starts_with_png_signature(out / "cs" / "cs_deviations.png"));
    EXPECT_TRUE(starts_with_png_signature(out / "adc" / "accuracy_limit.png"));
  }
  // The parts equal the standalone commands' output.
  const fs::path sim = tmp / "sim", cs = tmp / "cs";
  ok("simulate " + shell_quote(kRig) + " -o " + dir_arg(sim) + " --no-plots");
  ok("study cs " + shell_quote(kRig) + " -o " + dir_arg(cs) + " --no-plots");
  EXPECT_EQ(read_file(out / "simulate" / "stops.csv"), read_file(sim / "stops.csv"));
  EXPECT_EQ(read_file(out / "cs" / "deviations.csv"), read_file(cs / "deviations.csv"));
  EXPECT_EQ(read_file(out / "cs" / "summary.csv"), read_file(cs / "summary.csv"));
  EXPECT_TRUE(leftovers(tmp, "run").empty());
}

TEST_F(Cli, RelativeAndTrailingSlashOutputPaths) {
  ok("simulate " + shell_quote(kRig) + " -o rel/out --no-plots", "cd " + shell_quote(tmp) + " && ");
  EXPECT_TRUE(fs::exists(tmp / "rel" / "out" / "stops.csv"));
  EXPECT_TRUE(leftovers(tmp / "rel", "out").empty());
  ok("simulate " + shell_quote(kRig) + " -o " + shell_quote(tmp.string() + "/slash/") +
     " --no-plots");
  EXPECT_TRUE(fs::exists(tmp / "slash" / "stops.csv"));
  EXPECT_TRUE(leftovers(tmp, "slash").empty());
}

// ---------------------------------------------------------------------------------------------
// Bad input writes nothing
// ---------------------------------------------------------------------------------------------

TEST_F(Cli, BadInputWritesNothing) {
  write_file(tmp / "unknown-key.yaml", "seed: 1\nsource:\n  L_0: 20\n");
  // The traced rig with one line of its scene (scenes/jf500.yaml) replaced.
  int scenes = 0;
  const auto traced_rig = [&](const std::string& from, const std::string& to) {
    std::string scene = read_file(POLRIG_SOURCE_DIR "/scenes/jf500.yaml");
    const std::size_t at = scene.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    scene.replace(at, from.size(), to);
    const std::string n = std::to_string(scenes++);
    write_file(tmp / ("scene" + n + ".yaml"), scene);
    write_file(tmp / ("traced" + n + ".yaml"), "source: {model: traced, scene: scene" + n + ".yaml}\n");
    return tmp / ("traced" + n + ".yaml");
  };
  struct Case {
    std::string name;
    std::string args;      // without -o
    std::string expected;  // in stderr
  };
  const std::string missing = (tmp / "missing-rig.yaml").string();
  const std::vector<Case> cases = {
      {"missing rig file", "simulate " + shell_quote(missing),
       missing + ": cannot read the rig file: no such file"},
      {"unknown key in the rig file", "simulate " + shell_quote(tmp / "unknown-key.yaml"),
       (tmp / "unknown-key.yaml").string() + ":3: key 'source.L_0': unknown key"},
      {"--set unknown key", "simulate " + shell_quote(kRig) + " --set source.L_0=20",
       "--set source.L_0=20: unknown key 'source.L_0'"},
      {"--set negative distance", "simulate " + shell_quote(kRig) + " --set source.L_o=-1",
       "--set source.L_o=-1: key 'source.L_o': expected a length in [0.1, 1000] mm, got -1"},
      {"--set without =", "study cs " + shell_quote(kRig) + " --set source.L_o",
       "--set: expected key.path=value (e.g. eccentricity.L_S=0.05), got 'source.L_o'"},
      {"bad --grid key", "sweep " + shell_quote(kRig) + " --grid eccentricity.L_X=0:1:3",
       "--grid eccentricity.L_X=0:1:3: unknown key 'eccentricity.L_X'"},
      {"--grid with count 0", "sweep " + shell_quote(kRig) + " --grid eccentricity.L_S=0:1:0",
       "--grid eccentricity.L_S=0:1:0: count: expected a whole number in [1, 1e8], got '0'"},
      {"--grid value out of range", "sweep " + shell_quote(kRig) + " --grid device.d=0.5:1.5:3",
       "key 'device.d': expected a degree of polarization in (0, 1)"},
      {"--grid point breaks a rule",
       "sweep " + shell_quote(kRig) + " --grid schedule.start_deg=0:400:3",
       "key 'schedule.stop_deg': expected an angle ≥ schedule.start_deg"},
      {"study adc --d 1.5", "study adc --d 1.5",
       "--d 1.5: expected degrees of polarization in (0, 1), got 1.5"},
      {"run with a bad rig", "run " + shell_quote(tmp / "unknown-key.yaml"), "key 'source.L_0'"},
      // Issue 8 item 4: extremes that wrote NaN or inf with exit 0 are outside the keys' ranges.
      {"study cs with L_S = 1e300", "study cs " + shell_quote(kRig) + " --set eccentricity.L_S=1e300",
       "--set eccentricity.L_S=1e300: key 'eccentricity.L_S': expected a length in [0, 100] mm, got 1e300"},
      {"run with L_IS = 1e300", "run " + shell_quote(kRig) + " --set eccentricity.L_IS=1e300",
       "key 'eccentricity.L_IS': expected a length in [0, 100] mm, got 1e300"},
      {"study cs with L_o = 1e-300", "study cs " + shell_quote(kRig) + " --set source.L_o=1e-300",
       "key 'source.L_o': expected a length in [0.1, 1000] mm, got 1e-300"},
      {"simulate with volts_per_decade = 1e300",
       "simulate " + shell_quote(kRig) + " --set electronics.volts_per_decade=1e300",
       "key 'electronics.volts_per_decade': expected a gain in [0.01, 10] V, got 1e300"},
      {"sweep over L_photo up to 1e300", "sweep " + shell_quote(kRig) + " --grid device.L_photo=1:1e300:3",
       "--grid device.L_photo=1:1e300:3: key 'device.L_photo': expected a length in [0.1, 500] mm"},
      {"run with kv = 1e300", "run " + shell_quote(kRig) + " --set 'device.truth.kv=[1e300, 1, 1]'",
       "key 'device.truth.kv': expected 3 gains in [0.5, 2], got 1e300"},
      // Issue 8 item 1: scene values the tracer cannot represent.
      {"scene sphere 1e20 m", "study cs " + shell_quote(traced_rig("diameter: 500", "diameter: 1e20")),
       "key 'sphere.diameter': expected a length in [10, 10000] mm, got 1e20"},
      {"scene lamp of 1e300 W", "study cs " + shell_quote(traced_rig("power: 100", "power: 1e300")),
       "key 'lamps[0].power': expected a power in [0.001, 10000] W, got 1e300"},
      {"scene baffle normal of 1e300",
       "study cs " + shell_quote(traced_rig("normal: [0, 0.399, 0.917]", "normal: [0, 1e300, 0.917]")),
       "key 'baffles[0].normal': expected a direction of length in [1e-6, 1e6]"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    // The output folder's parent does not exist either: nothing may be created.
    const fs::path parent = tmp / "nested";
    const fs::path out = parent / "out";
    const Result r = polrig(c.args + " -o " + dir_arg(out) + " --no-plots");
    EXPECT_NE(r.status, 0) << r.err;
    EXPECT_HAS(r.err, "polrig: error: ");
    EXPECT_HAS(r.err, c.expected);
    EXPECT_FALSE(fs::exists(out)) << "the output folder was written";
    EXPECT_FALSE(fs::exists(parent)) << "the output folder's parent was created";
    EXPECT_TRUE(leftovers(parent, "out").empty());
    EXPECT_TRUE(leftovers(tmp, "out").empty());
    EXPECT_EQ(r.out.find("wrote"), std::string::npos) << r.out;
    std::error_code ec;
    fs::remove_all(parent, ec);
  }
}

// Issue 8 item 5: nan and inf passed CLI::Range (`study adc --step nan` wrote zeros, exit 0).
TEST_F(Cli, NumericOptionsRefuseNanAndInfinity) {
  write_file(tmp / "v.csv", "V1,V2,V3\n0.1,0.2,0.3\n");
  const std::string rig = shell_quote(kRig);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"study adc --step nan", "--step: expected a finite number in [0.0001, 10] deg, got nan"},
      {"study adc --step inf", "--step: expected a finite number in [0.0001, 10] deg, got inf"},
      {"study adc --step -inf", "--step: expected a finite number in [0.0001, 10] deg, got -inf"},
      {"study calibration " + rig + " --L-IS-max nan", "--L-IS-max: expected a finite number in [0, 100] mm, got nan"},
      {"study calibration " + rig + " --L-S-max inf", "--L-S-max: expected a finite number in [0, 100] mm, got inf"},
      {"study calibration " + rig + " --nc-threshold nan", "--nc-threshold: expected a finite number in [0, 1], got nan"},
      {"calibrate " + shell_quote(tmp / "v.csv") + " --nc-threshold inf", "--nc-threshold: expected a finite number in [0, 1], got inf"},
      {"calibrate " + shell_quote(tmp / "v.csv") + " --d-a nan", "--d-a: expected a degree of polarization in (0, 1), got nan"},
      {"study cs " + rig + " --steps nan", "--steps: expected an even number"},
      {"study calibration " + rig + " --trials nan", "--trials: "},
      {"--threads inf study adc", "--threads: "},
      {"study adc --d nan", "--d nan: value: expected a finite number, got 'nan'"},
  };
  for (const auto& [args, expected] : cases) {
    SCOPED_TRACE(args);
    const fs::path out = tmp / "out";
    const Result r = polrig(args + " -o " + dir_arg(out) + " --no-plots");
    EXPECT_NE(r.status, 0);
    EXPECT_HAS(r.err, expected);
    EXPECT_FALSE(fs::exists(out));
    EXPECT_TRUE(leftovers(tmp, "out").empty());
  }
}

TEST_F(Cli, FailureAfterStagingLeavesNothing) {
  // A gnuplot that passes the availability check but fails to plot: the error comes after the
  // staging folder was filled with CSV files.
  const fs::path bin = tmp / "fakebin";
  fs::create_directories(bin);
  write_file(bin / "gnuplot",
             "#!/bin/sh\nif [ \"$1\" = --version ]; then echo 'gnuplot 5.4'; exit 0; fi\n"
             "echo 'fake gnuplot: cannot plot' >&2\nexit 3\n");
  fs::permissions(bin / "gnuplot", fs::perms::owner_all | fs::perms::group_read |
                                       fs::perms::group_exec | fs::perms::others_read |
                                       fs::perms::others_exec);
  const fs::path parent = tmp / "nested" / "deeper";
  const fs::path out = parent / "out";
  const std::string path_env =
      "PATH=" + shell_quote(bin.string() + ":" + std::getenv("PATH")) + " ";
  const Result r = polrig("simulate " + shell_quote(kRig) + " -o " + dir_arg(out), path_env);
  EXPECT_NE(r.status, 0);
  EXPECT_HAS(r.err, "gnuplot failed");
  EXPECT_HAS(r.err, "fake gnuplot: cannot plot");
  EXPECT_FALSE(fs::exists(out));
  EXPECT_TRUE(leftovers(parent, "out").empty());
  EXPECT_FALSE(fs::exists(tmp / "nested")) << "created parent folders were left behind";

  // The same failure with an existing output folder and --force keeps the old folder.
  const fs::path keep = tmp / "keep";
  fs::create_directories(keep);
  write_file(keep / "marker.txt", "old");
  const Result r2 =
      polrig("simulate " + shell_quote(kRig) + " -o " + dir_arg(keep) + " --force", path_env);
  EXPECT_NE(r2.status, 0);
  EXPECT_EQ(read_file(keep / "marker.txt"), "old");
  EXPECT_FALSE(fs::exists(keep / "stops.csv"));
  EXPECT_TRUE(leftovers(tmp, "keep").empty());
}

TEST_F(Cli, BadOutputNamesGetClearMessagesAndLeaveNothing) {
  const std::string cmd = "study adc --no-plots -o ";
  Result r = polrig(cmd + "''");
  EXPECT_NE(r.status, 0);
  EXPECT_HAS(r.err, "polrig: error: -o/--out '': expected the output folder's name");
  EXPECT_LACKS(r.err, "filesystem error");

  fs::create_symlink(tmp / "missing-target", tmp / "dangling");
  r = polrig(cmd + dir_arg(tmp / "dangling"));
  EXPECT_NE(r.status, 0);
  EXPECT_HAS(r.err, "-o/--out " + (tmp / "dangling").string() + ": ");
  EXPECT_HAS(r.err, "the output folder exists (a symbolic link to '" +
                        (tmp / "missing-target").string() + "', which does not exist)");
  EXPECT_LACKS(r.err, "filesystem error");
  EXPECT_TRUE(fs::is_symlink(tmp / "dangling"));
  EXPECT_TRUE(leftovers(tmp, "dangling").empty());

  // 245 bytes: a legal folder name whose staging folder name is too long. The parents it
  // would need are not created.
  const fs::path out = tmp / "new" / "deeper" / std::string(245, 'n');
  r = polrig(cmd + dir_arg(out));
  EXPECT_NE(r.status, 0);
  EXPECT_HAS(r.err, "the folder name is 245 bytes long; at most");
  EXPECT_FALSE(fs::exists(tmp / "new")) << "a parent folder was left behind";
}

namespace {
// Starts polrig with default signal dispositions (a shell's background job would ignore
// SIGINT), its output to /dev/null (stderr to `err`); returns its pid.
pid_t spawn_polrig(const std::vector<std::string>& args, bool ignore_hangup, const std::string& err = "/dev/null") {
  std::vector<std::string> argv_s{kPolrigExe};
  argv_s.insert(argv_s.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : argv_s) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_addopen(&files, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&files, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  sigset_t defaults, none;
  sigemptyset(&defaults);
  for (int sig : {SIGINT, SIGTERM, SIGHUP})
    if (!(ignore_hangup && sig == SIGHUP)) sigaddset(&defaults, sig);
  sigemptyset(&none);
  posix_spawnattr_setsigdefault(&attr, &defaults);
  posix_spawnattr_setsigmask(&attr, &none);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK);
  // nohup: SIGHUP ignored from the start (exec keeps an ignored disposition).
  struct sigaction ign {}, old {};
  ign.sa_handler = SIG_IGN;
  if (ignore_hangup) sigaction(SIGHUP, &ign, &old);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, argv[0], &files, &attr, argv.data(), environ);
  if (ignore_hangup) sigaction(SIGHUP, &old, nullptr);
  posix_spawn_file_actions_destroy(&files);
  posix_spawnattr_destroy(&attr);
  return rc == 0 ? pid : -1;
}

bool wait_for_staging(const fs::path& parent) {
  for (int i = 0; i < 400; ++i) {
    if (fs::exists(parent))
      for (const auto& e : fs::directory_iterator(parent))
        if (e.path().filename().string().find("partial") != std::string::npos) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  }
  return false;
}
}  // namespace

TEST_F(Cli, AnInterruptedRunLeavesNothing) {
  // Ctrl-C (SIGINT), a kill (SIGTERM) or a hang-up during a long study: the staging folder and
  // the parent folders polrig created are removed, and the process ends by the signal.
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
    SCOPED_TRACE(sig);
    const fs::path parent = tmp / "made" / "for";
    const pid_t pid = spawn_polrig({"study", "calibration", kRig, "--trials", "10000000", "-o",
                                    (parent / "out").string(), "--no-plots"}, false);
    ASSERT_GT(pid, 0);
    ASSERT_TRUE(wait_for_staging(parent));
    ::kill(pid, sig);
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(WIFSIGNALED(status)) << "polrig did not end by the signal";
    EXPECT_EQ(WTERMSIG(status), sig);
    EXPECT_FALSE(fs::exists(tmp / "made")) << "the staging folder or its parents were left behind";
  }
}

TEST_F(Cli, AHangUpIgnoredByNohupStaysIgnored) {
  // Under nohup SIGHUP is ignored when polrig starts; it must stay so (the run goes on), and a
  // later SIGTERM still cleans up.
  const fs::path parent = tmp / "nohup";
  const pid_t pid = spawn_polrig({"study", "calibration", kRig, "--trials", "10000000", "-o",
                                  (parent / "out").string(), "--no-plots"}, true);
  ASSERT_GT(pid, 0);
  ASSERT_TRUE(wait_for_staging(parent));
  ::kill(pid, SIGHUP);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  int status = 0;
  EXPECT_EQ(::waitpid(pid, &status, WNOHANG), 0) << "SIGHUP ended a run started under nohup";
  ::kill(pid, SIGTERM);
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM);
  EXPECT_FALSE(fs::exists(parent)) << "the staging folder or its parents were left behind";
}

// ---- resuming an interrupted sweep

namespace {
// 200,000 points on one thread: long enough to interrupt after a checkpoint.
std::vector<std::string> resumable_sweep(const fs::path& out) {
  return {"sweep", kRig, "--grid", "eccentricity.L_S=0.001:1:400", "--grid", "eccentricity.L_IS=0.001:1:500",
          "--csv", "--threads", "1", "-o", out.string()};
}
std::string joined(const std::vector<std::string>& args) {
  std::string s;
  for (const std::string& a : args) {
    if (!s.empty()) s += ' ';
    s += shell_quote(a);
  }
  return s;
}
fs::path staging_of(const fs::path& out) { return out.parent_path() / ("." + out.filename().string() + ".resumable"); }

// Waits until the staging folder's progress record shows a completed block (more than `after`
// points), then sends `sig` and waits for the process. Returns the points the record held, or 0
// if the run ended first.
std::size_t interrupt_after_a_checkpoint(pid_t pid, const fs::path& out, int sig, std::size_t after = 0) {
  std::size_t done = 0;
  for (int i = 0; i < 20000 && done <= after; ++i) {
    try {
      if (const auto s = polrig::read_sweep_state(staging_of(out))) done = s->points_done;
    } catch (const std::exception&) {  // read while it was renamed
    }
    if (done <= after) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ::kill(pid, sig);
  int status = 0;
  ::waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == sig) << "the sweep ended before the signal";
  return done;
}

std::set<std::string> names_in(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}
}  // namespace

// CTest label "slow" (the suite's name starts with Slow): each runs sweeps of thousands of points
// several times, and is run once, in the full suite.
class SlowCliResume : public Cli {};

TEST_F(SlowCliResume, AnInterruptedSweepResumesToTheSameBytes) {
  // The reference: an uninterrupted run, written to the same -o (the manifest records it).
  const fs::path out = tmp / "runs" / "sweep", ref = tmp / "reference";
  ok(joined(resumable_sweep(out)));
  fs::rename(out, ref);
  for (int sig : {SIGKILL, SIGINT}) {
    SCOPED_TRACE(sig);
    const fs::path err = tmp / "interrupted.txt";
    const pid_t pid = spawn_polrig(resumable_sweep(out), false, err.string());
    ASSERT_GT(pid, 0);
    const std::size_t done = interrupt_after_a_checkpoint(pid, out, sig);
    ASSERT_GT(done, 0u);
    ASSERT_LT(done, 200000u);
    EXPECT_FALSE(fs::exists(out));
    ASSERT_TRUE(fs::exists(staging_of(out) / "sweep.h5")) << "the interrupted run's staging folder was removed";

    // Not resumed by accident: the same command refuses, naming the staging folder.
    const Result again = polrig(joined(resumable_sweep(out)));
    EXPECT_NE(again.status, 0);
    EXPECT_HAS(again.err, staging_of(out).string());
    EXPECT_HAS(again.err, "--resume continues it; --force starts over");

    std::vector<std::string> resume = resumable_sweep(out);
    resume.push_back("--resume");
    if (sig == SIGKILL) {
      ok(joined(resume));
    } else {  // Ctrl-C says what it kept, where, how big, and the command that continues it
      const std::string said = read_file(err);
      EXPECT_HAS(said, "kept in " + staging_of(out).string() + " (");
      EXPECT_HAS(said, " MB)");
      const std::string tag = "polrig: to continue it, in " + fs::current_path().string() + ": polrig ";
      const auto at = said.find(tag);
      ASSERT_NE(at, std::string::npos) << said;
      const std::string command = said.substr(at + tag.size(), said.find('\n', at) - at - tag.size());
      EXPECT_HAS(command, " --resume");
      ok(command);
    }
    EXPECT_FALSE(fs::exists(staging_of(out)));
    ASSERT_EQ(names_in(out), names_in(ref));
    for (const std::string& name : names_in(ref))
      EXPECT_TRUE(read_file(out / name) == read_file(ref / name)) << name << " differs from the uninterrupted run's";
    fs::remove_all(out);
  }
}

TEST_F(SlowCliResume, ResumingRefusesOtherInputsAndForceStartsOver) {
  const fs::path out = tmp / "sweep";
  const pid_t pid = spawn_polrig(resumable_sweep(out), false);
  ASSERT_GT(pid, 0);
  ASSERT_GT(interrupt_after_a_checkpoint(pid, out, SIGKILL), 0u);
  std::vector<std::string> other = resumable_sweep(out);
  other.insert(other.end(), {"--steps", "36", "--set", "eccentricity.L_S=0.2", "--resume"});
  const Result r = polrig(joined(other));
  EXPECT_NE(r.status, 0);
  EXPECT_HAS(r.err, "--resume: the interrupted run in " + staging_of(out).string() + " was started with another");
  EXPECT_HAS(r.err, "steps (--steps)");
  EXPECT_HAS(r.err, "overrides (--set)");
  EXPECT_EQ(r.err.find("grid (--grid)"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(staging_of(out) / polrig::kSweepStateFile)) << "a refused resume must keep the progress";
  // A sweep.csv cut short after its checkpoint is refused, not padded with zero bytes.
  const fs::path csv = staging_of(out) / "sweep.csv";
  fs::resize_file(csv, 10);
  std::vector<std::string> same = resumable_sweep(out);
  same.push_back("--resume");
  const Result cut = polrig(joined(same));
  EXPECT_NE(cut.status, 0);
  EXPECT_HAS(cut.err, csv.string() + ": 10 bytes, shorter than its last checkpoint");
  EXPECT_HAS(cut.err, "pass --force without --resume to start over");
  EXPECT_EQ(fs::file_size(csv), 10u);
  // --force without --resume starts over (and finishes).
  std::vector<std::string> force = resumable_sweep(out);
  force.insert(force.end(), {"--steps", "8", "--force"});
  ok(joined(force));
  EXPECT_FALSE(fs::exists(staging_of(out)));
  EXPECT_FALSE(fs::exists(out / polrig::kSweepStateFile));
}

// Issue 23 item 10: --resume checks the progress record against sweep.h5 and sweep.csv before
// continuing them. A sweep.h5 of an earlier checkpoint (its later points never written: they
// became 0.0 in the finished folder) and a record whose points_done or csv_bytes was changed by
// hand gave a wrong folder with exit 0; each is refused, naming the file, and the progress kept.
TEST_F(SlowCliResume, ResumingRefusesFilesThatDoNotMatchTheRecord) {
  const fs::path out = tmp / "sweep", staging = staging_of(out);
  const fs::path h5 = staging / "sweep.h5", csv = staging / "sweep.csv", record = staging / polrig::kSweepStateFile;
  std::vector<std::string> resume = resumable_sweep(out);
  resume.push_back("--resume");
  pid_t pid = spawn_polrig(resumable_sweep(out), false);
  ASSERT_GT(pid, 0);
  const std::size_t first = interrupt_after_a_checkpoint(pid, out, SIGKILL);
  ASSERT_GT(first, 0u);
  const std::string early_h5 = read_file(h5);
  pid = spawn_polrig(resume, false);  // on to a later checkpoint
  ASSERT_GT(pid, 0);
  const std::size_t later = interrupt_after_a_checkpoint(pid, out, SIGKILL, first);
  ASSERT_GT(later, first);
  ASSERT_LT(later, 200000u);
  const std::string good_h5 = read_file(h5), good_record = read_file(record);

  const auto refused = [&](const std::string& says) {
    const Result r = polrig(joined(resume));
    EXPECT_EQ(r.status, 1) << r.err;
    EXPECT_HAS(r.err, "--resume: " + says);
    EXPECT_HAS(r.err, "pass --force without --resume to start over");
    EXPECT_FALSE(fs::exists(out));
    EXPECT_TRUE(fs::exists(record)) << "a refused resume must keep the progress";
  };
  // `key: VALUE` of the record replaced.
  const auto record_with = [&](const std::string& key, const std::string& value) {
    std::string text;
    for (const std::string& line : lines_of(good_record))
      text += (line.rfind(key + ": ", 0) == 0 ? key + ": " + value : line) + "\n";
    EXPECT_NE(text, good_record) << key;
    write_file(record, text);
  };
  const auto number_in_record = [&](const std::string& key) {
    for (const std::string& line : lines_of(good_record))
      if (line.rfind(key + ": ", 0) == 0) return std::stoull(line.substr(key.size() + 2));
    ADD_FAILURE() << key << " not in the record";
    return 0ull;
  };

  write_file(h5, early_h5);
  refused(h5.string() + ": its first " + std::to_string(later) + " points are not those " + record.string() + " counts");
  write_file(h5, good_h5);

  record_with("points_done", std::to_string(later - 1));
  refused(h5.string() + ": its first " + std::to_string(later - 1) + " points are not those");
  record_with("points_done", "999999999");
  refused(record.string() + ": points_done 999999999, but the grid has 200000 points");
  const std::uint64_t csv_bytes = number_in_record("csv_bytes");
  record_with("csv_bytes", std::to_string(csv_bytes - 1));
  refused(csv.string() + ": its first " + std::to_string(csv_bytes - 1) + " bytes are not the header and the " +
          std::to_string(later) + " lines");
  EXPECT_GE(fs::file_size(csv), csv_bytes) << "a refused resume must not cut sweep.csv";

  // The record as written resumes.
  write_file(record, good_record);
  ok(joined(resume));
  EXPECT_FALSE(fs::exists(staging));
  EXPECT_TRUE(fs::exists(out / "sweep.h5"));
}

TEST_F(Cli, ABadPointAfterACheckpointLeavesNothingToResume) {
  // schedule.start_deg first: its bad value (400, past stop_deg) starts at point 4096, in the
  // second block, after the first block's progress record; twelve more axes skip the corners.
  const fs::path out = tmp / "bad";
  std::string grid = " --grid schedule.start_deg=0:400:2";
  for (int k = 0; k < 12; ++k) grid += " --grid eccentricity.alpha_S=0:1:2";
  const Result r = polrig("sweep " + shell_quote(kRig) + grid + " --steps 4 --no-plots --threads 1 -o " + dir_arg(out));
  EXPECT_EQ(r.status, 2) << r.err;
  EXPECT_HAS(r.err, "schedule.start_deg=400");
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(staging_of(out))) << "resuming would only meet the same point again";
}

TEST_F(Cli, AResumableStagingFolderWithALeftoverRenameProbeResumes) {
  const fs::path out = tmp / "sweep";
  const pid_t pid = spawn_polrig(resumable_sweep(out), false);
  ASSERT_GT(pid, 0);
  ASSERT_GT(interrupt_after_a_checkpoint(pid, out, SIGKILL), 0u);
  fs::create_directory(staging_of(out) / ".rename-probe-a");  // as a kill while probing leaves it
  std::vector<std::string> resume = resumable_sweep(out);
  resume.push_back("--resume");
  ok(joined(resume));
  EXPECT_FALSE(fs::exists(staging_of(out)));
  EXPECT_FALSE(fs::exists(out / ".rename-probe-a"));
}

TEST_F(Cli, ResumeWithNothingToResumeIsAnError) {
  const fs::path out = tmp / "nothing";
  const Result r = polrig("sweep " + shell_quote(kRig) + " --grid eccentricity.L_S=0:1:3 --no-plots --resume -o " + dir_arg(out));
  EXPECT_NE(r.status, 0);
  EXPECT_HAS(r.err, "--resume: there is no interrupted run of " + out.string() + " to continue");
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(staging_of(out)));
}

TEST_F(Cli, ExistingOutputFolderNeedsForce) {
  const fs::path out = tmp / "existing";
  fs::create_directories(out / "sub");
  write_file(out / "marker.txt", "old content");
  write_file(out / "sub" / "x.txt", "x");

  const Result r = polrig("simulate " + shell_quote(kRig) + " -o " + dir_arg(out) + " --no-plots");
  EXPECT_NE(r.status, 0);
  EXPECT_HAS(r.err, out.string() + ": the output folder exists");
  EXPECT_HAS(r.err, "--force");
  EXPECT_EQ(read_file(out / "marker.txt"), "old content");
  EXPECT_EQ(read_file(out / "sub" / "x.txt"), "x");
  EXPECT_FALSE(fs::exists(out / "stops.csv"));
  EXPECT_TRUE(leftovers(tmp, "existing").empty());

  ok("simulate " + shell_quote(kRig) + " -o " + dir_arg(out) + " --no-plots --force");
  EXPECT_FALSE(fs::exists(out / "marker.txt")) << "--force must replace the folder, not merge";
  EXPECT_FALSE(fs::exists(out / "sub"));
  EXPECT_EQ(read_csv(out / "stops.csv").rows.size(), 37u);
  EXPECT_TRUE(leftovers(tmp, "existing").empty());
}
