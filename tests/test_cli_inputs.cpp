// Hostile and malformed input files, run through the executable (issue 23 §5): each is refused
// quickly, naming the file, with exit 2 (bad input) and nothing written.
#include <algorithm>
#include <chrono>
#include <string>

#include <fmt/format.h>

#include "support.h"

namespace fs = std::filesystem;
using namespace polrig::test;

namespace {

class CliInputs : public PolrigTest {
 protected:
  CliInputs() : PolrigTest("polrig_test_cli_inputs_", "") {}

  // A small DoFP sky dataset (32 × 24 px, two stops) in tmp/`name`.
  fs::path dofp_dataset(const std::string& name) {
    const fs::path dir = tmp / name;
    ok("simulate " + shell_quote(std::string(POLRIG_SOURCE_DIR "/rigs/han2017-outdoor.yaml")) +
       " --set device.width_px=32 --set device.height_px=24 --set schedule.step_deg=180 -o " + shell_quote(dir));
    return dir;
  }

  // A small four-camera sky dataset (W16's static hour, three stops, 66 × 50 px cameras).
  fs::path four_camera_dataset(const std::string& name, const std::string& layers = "aop", int stops = 3) {
    const fs::path dir = tmp / name;
    ok("simulate " + shell_quote(std::string(POLRIG_SOURCE_DIR "/rigs/wang2016-static.yaml")) + " --layers " + layers +
       " --set schedule.step_deg=0 --set schedule.count=" + std::to_string(stops) + " --set schedule.dwell_s=1200"
       " --set device.cameras.noise=false --set device.cameras.width_px=66 --set device.cameras.height_px=50"
       " --set 'device.cameras.fx_px=[48, 48, 48, 48]' --set 'device.cameras.fy_px=[48, 48, 48, 48]'"
       " --set 'device.cameras.cx_px=[33, 33, 33, 33]' --set 'device.cameras.cy_px=[25, 25, 25, 25]' -o " +
       shell_quote(dir));
    return dir;
  }

  // Runs `args`, expects exit 2 with `text` on stderr and no folder tmp/out.
  void refused(const std::string& args, const std::string& text, int status = 2) {
    const Result r = polrig(args + " -o " + shell_quote(tmp / "out"));
    EXPECT_EQ(r.status, status) << args << "\n" << r.err;
    EXPECT_HAS(r.err, text);
    EXPECT_FALSE(fs::exists(tmp / "out")) << args;
  }
};

}  // namespace

// §5.1: a frame whose header claims 100000² px (40 GB a channel) is refused from its header, before
// its pixels are allocated: a stop's frame, DoFP truth.exr, --params and a four-camera stop.
TEST_F(CliInputs, AnExrClaimingAnotherSizeIsRefusedFromItsHeader) {
  const fs::path dofp = dofp_dataset("dofp");
  const fs::path frame = dofp / "frames" / "stop_0000.exr";
  const std::string good = read_file(frame);
  claim_exr_size(frame, 100000, 100000);
  refused("orient " + shell_quote(dofp), frame.string() + ": 100000 × 100000 px (expected 32 × 24)");
  write_file(frame, good);
  write_file(tmp / "params.exr", good);
  claim_exr_size(tmp / "params.exr", 100000, 100000);
  refused("orient " + shell_quote(dofp) + " --params " + shell_quote(tmp / "params.exr"),
          (tmp / "params.exr").string() + ": 100000 × 100000 px (expected 32 × 24)");
  claim_exr_size(dofp / "truth.exr", 100000, 100000);
  refused("orient " + shell_quote(dofp), (dofp / "truth.exr").string() + ": 100000 × 100000 px (expected 32 × 24)");
  refused("calibrate " + shell_quote(dofp) + " --method dofp",
          (dofp / "truth.exr").string() + ": 100000 × 100000 px (expected 32 × 24)");

  const fs::path four = four_camera_dataset("four");
  const fs::path stop = four / "frames" / "stop_0001.exr";
  claim_exr_size(stop, 100000, 100000);
  refused("locate " + shell_quote(four) + " --prior 29,113.5", stop.string() + ": 100000 × 100000 px (expected 66 × 50)");
}

namespace {

// Nested anchors ("billion laughs") under `key`: ten levels of ten aliases, 10^10 nodes once
// expanded, in 1 KB.
std::string alias_bomb(const std::string& key) {
  std::string y = key + ":\n  l0: &l0 [x, x, x, x, x, x, x, x, x, x]\n";
  for (int i = 1; i < 10; ++i) {
    y += fmt::format("  l{}: &l{} [", i, i);
    for (int j = 0; j < 10; ++j) y += fmt::format("{}*l{}", j ? ", " : "", i - 1);
    y += "]\n";
  }
  return y;
}

}  // namespace

// §5.2: a YAML alias bomb is refused within a second, naming the file and line, by every YAML
// reader (a params.yaml given to apply walked it for minutes); so is a YAML file of more than
// 1 MiB (a 100 MB scalar took half a minute), and a key given twice in calibration.yaml or
// truth.yaml (the rig and params readers already refused it).
TEST_F(CliInputs, YamlAliasBombsHugeFilesAndDuplicateKeysAreRefusedQuickly) {
  write_file(tmp / "v.csv", "V1,V2,V3\n0.1,0.2,0.3\n");
  const std::string expands = "the YAML expands to more than 2000000 nodes";
  // Refused before the document is built: the message says so (CTest's timeout catches a hang;
  // no timing here, speed belongs in bench/).
  const auto quickly = [&](const std::string& args, const std::string& text) { refused(args, text); };
  write_file(tmp / "bomb.yaml", alias_bomb("alpha_deg"));
  quickly("apply " + shell_quote(tmp / "bomb.yaml") + " " + shell_quote(tmp / "v.csv"), (tmp / "bomb.yaml").string() + ":");
  quickly("apply " + shell_quote(tmp / "bomb.yaml") + " " + shell_quote(tmp / "v.csv"), expands);
  // An alias inside its own anchor (yaml-cpp would build a cyclic node) is refused, not walked.
  write_file(tmp / "cycle.yaml", "alpha_deg: &a [*a]\n");
  quickly("apply " + shell_quote(tmp / "cycle.yaml") + " " + shell_quote(tmp / "v.csv"),
          (tmp / "cycle.yaml").string() + ":1:");
  quickly("apply " + shell_quote(tmp / "cycle.yaml") + " " + shell_quote(tmp / "v.csv"), "a cycle");
  write_file(tmp / "rig.yaml", alias_bomb("schedule"));
  quickly("simulate " + shell_quote(tmp / "rig.yaml"), expands);
  write_file(tmp / "truth-from.yaml", "device:\n  truth_from: bomb.yaml\n");
  quickly("simulate " + shell_quote(tmp / "truth-from.yaml"), expands);
  write_file(tmp / "cal.yaml", alias_bomb("cameras"));
  const fs::path four = four_camera_dataset("four");
  quickly("locate " + shell_quote(four) + " --prior 29,113.5 --calibration " + shell_quote(tmp / "cal.yaml"), expands);
  quickly("calibrate " + shell_quote(four) + " --method four-camera --geometry " + shell_quote(tmp / "cal.yaml"), expands);
  const std::string truth = read_file(four / "truth.yaml");
  write_file(four / "truth.yaml", alias_bomb("virtual_camera"));
  quickly("locate " + shell_quote(four) + " --prior 29,113.5", expands);

  // More than 1 MiB: refused by its size before it is parsed.
  const std::string huge = "alpha_deg: " + std::string(2 << 20, 'x') + "\n";
  write_file(tmp / "huge.yaml", huge);
  quickly("apply " + shell_quote(tmp / "huge.yaml") + " " + shell_quote(tmp / "v.csv"),
          (tmp / "huge.yaml").string() + ": cannot read the parameter file: " + std::to_string(huge.size()) +
              " bytes, more than the 1048576 bytes");

  // A key given twice in truth.yaml or calibration.yaml.
  write_file(four / "truth.yaml", truth + "height_px: 50\n");
  quickly("locate " + shell_quote(four) + " --prior 29,113.5",
          (four / "truth.yaml").string() + ":" + std::to_string(std::count(truth.begin(), truth.end(), '\n') + 1) +
              ": key 'height_px': duplicate key (first at line");
  write_file(tmp / "cal2.yaml", truth + "width_px: 66\n");
  quickly("locate " + shell_quote(four) + " --prior 29,113.5 --calibration " + shell_quote(tmp / "cal2.yaml"),
          "key 'width_px': duplicate key (first at line");
}

namespace {

// `text` with the first line that starts with `start` replaced by `line`, and that line's number.
std::pair<std::string, int> replace_line(const std::string& text, const std::string& start, const std::string& line) {
  std::string out;
  int n = 0, at = 0;
  for (const std::string& l : lines_of(text)) {
    ++n;
    const bool hit = at == 0 && l.rfind(start, 0) == 0;
    if (hit) at = n;
    out += (hit ? line : l) + "\n";
  }
  return {out, at};
}

}  // namespace

// §5.3: locate reads truth.yaml with the strict reader of calibration.yaml: virtual_camera's
// width_px: 1e12 (cast to int before), 64.5 px, cx_px: 1e308 and an unknown key are refused,
// naming the file, line, key and value.
TEST_F(CliInputs, TruthYamlIsReadStrictlyByLocate) {
  const fs::path four = four_camera_dataset("four");
  const std::string truth = read_file(four / "truth.yaml");
  const struct {
    const char* start;
    const char* line;
    const char* says;
  } cases[] = {
      {"  width_px:", "  width_px: 1e12", "key 'virtual_camera.width_px': expected an integer number of pixels in [2, 16384], got 1e12"},
      {"  height_px:", "  height_px: 64.5", "key 'virtual_camera.height_px': expected an integer number of pixels in [2, 16384], got 64.5"},
      {"  cx_px:", "  cx_px: 1e308", "key 'virtual_camera.cx_px': expected a principal point inside the image: [0, width_px] px, got 1e308"},
      {"  f_c_px:", "  f_c_pix: 48", "key 'virtual_camera.f_c_pix': unknown key"},
  };
  for (const auto& c : cases) {
    const auto [text, line] = replace_line(truth, c.start, c.line);
    ASSERT_GT(line, 0) << c.start;
    write_file(four / "truth.yaml", text);
    refused("locate " + shell_quote(four) + " --prior 29,113.5",
            fmt::format("{}:{}: {}", (four / "truth.yaml").string(), line, c.says));
  }
}

// §5.4: an error quotes a long value by its first 60 characters and its length, not whole (a 1 MB
// CSV cell gave a 1 MB line on stderr): a CSV cell, a YAML value of params.yaml and of a rig file.
TEST_F(CliInputs, LongValuesAreQuotedCut) {
  const std::string cell(1 << 20, '7');
  write_file(tmp / "v.csv", "V1,V2,V3\n0.1,0.2," + cell + "x\n");
  const std::string cut = std::string(60, '7') + "…(1048577 bytes)";
  write_file(tmp / "params.yaml", "alpha_deg: [" + std::string(500000, '1') + "x, 0, 0, 0, 0, 0]\n");
  write_file(tmp / "rig.yaml", "device:\n  d: " + std::string(500000, '9') + "x\n");
  write_file(tmp / "good.yaml", "alpha_deg: [0, 0, 0, 0, 0, 0]\nk_mV: [0, 0, 0]\nkv: [1, 1, 1]\n"
                                "kd: [0, 0, 0, 0, 0, 0]\nd_a: 0.5\n");
  const struct {
    std::string args, says;
  } cases[] = {
      {"apply " + shell_quote(tmp / "good.yaml") + " " + shell_quote(tmp / "v.csv"),
       "column 'V3': expected a finite number, got '" + cut + "'"},
      {"apply " + shell_quote(tmp / "params.yaml") + " " + shell_quote(tmp / "v.csv"),
       "key 'alpha_deg': expected a number, got '" + std::string(60, '1') + "…(500001 bytes)'"},
      {"simulate " + shell_quote(tmp / "rig.yaml"), "got '" + std::string(60, '9') + "…(500001 bytes)'"},
  };
  for (const auto& c : cases) {
    const Result r = polrig(c.args + " -o " + shell_quote(tmp / "out"));
    EXPECT_EQ(r.status, 2) << c.args;
    EXPECT_HAS(r.err, c.says);
    EXPECT_LT(r.err.size(), 600u) << c.args;
  }
}

// §5.5: every numeric option of every command refuses nan and inf when the command line is parsed
// (a usage error, exit 2, naming the option: docs/cli.md), as --step does; `orient --heading-prior
// nan` passed. The options are found in each command's --help (FLOAT): 30 in all.
TEST_F(CliInputs, EveryFloatOptionRefusesNanAndInf) {
  const std::vector<std::string> commands = {
      "simulate", "sweep", "run", "trace", "calibrate", "apply", "heading", "orient", "locate", "sky", "sky table",
      "spectral kd", "study cs", "study adc", "study calibration", "study heading", "study positioning", "rig show"};
  int checked = 0;
  for (const std::string& command : commands) {
    const Result help = polrig(command + " --help");
    if (help.status != 0) continue;  // not in this build
    for (const std::string& line : lines_of(help.out)) {
      const auto at = line.find("--");
      const auto type = line.find(" FLOAT");
      if (at == std::string::npos || type == std::string::npos || type < at) continue;
      std::string option = line.substr(at, type - at);
      if (const auto comma = option.find(','); comma != std::string::npos) option = option.substr(0, comma);
      for (const char* bad : {"nan", "inf"}) {
        const Result r = polrig(command + " " + option + " " + bad);
        EXPECT_EQ(r.status, 2) << command << " " << option << " " << bad << "\n" << r.err;
        // Refused for its value, not for a missing argument (also exit 2): "--OPTION: …, got nan".
        EXPECT_HAS(r.err, option + ": ");
        EXPECT_HAS(r.err, std::string("got ") + bad);
        ++checked;
      }
    }
  }
  EXPECT_GE(checked, 2 * 30);  // every FLOAT option was found
}

// §5.6: a missing or truncated frame is bad input data, exit 2, in orient and locate as in
// calibrate (docs/cli.md); it was exit 1 in orient and locate.
TEST_F(CliInputs, AMissingOrTruncatedFrameIsExit2Everywhere) {
  const fs::path dofp = dofp_dataset("dofp");
  const fs::path frame = dofp / "frames" / "stop_0001.exr";
  const std::string good = read_file(frame);
  write_file(frame, good.substr(0, good.size() / 2));
  refused("orient " + shell_quote(dofp), frame.string() + ": cannot read the EXR image");
  fs::remove(frame);
  refused("orient " + shell_quote(dofp), frame.string() + ": cannot read the EXR image");

  const fs::path four = four_camera_dataset("four");
  const fs::path stop = four / "frames" / "stop_0002.exr";
  const std::string whole = read_file(stop);
  write_file(stop, whole.substr(0, whole.size() / 2));
  refused("locate " + shell_quote(four) + " --prior 29,113.5", stop.string() + ": cannot read the EXR image");
  fs::remove(stop);
  refused("locate " + shell_quote(four) + " --prior 29,113.5", stop.string() + ": cannot read the EXR image");
}

// §5.7: locate on one sighting (Eq. 17 has two unknowns) wrote nan into fix.csv's cost_deg2 and
// residual_rms_deg with exit 0: it is refused, saying why.
TEST_F(CliInputs, LocateRefusesTooFewSightings) {
  const fs::path one = four_camera_dataset("one", "aop", 1);
  refused("locate " + shell_quote(one) + " --prior 29,113.5",
          "1 of 1 polarized stops gave a sun vector: the position fix (W16 Eq. 17) needs at least 2 sightings");
}

namespace {

// `csv` with cell `column` of data row 1 (file line 2) set to `value`.
void set_cell(const fs::path& csv, std::size_t column, const std::string& value) {
  std::vector<std::string> lines = lines_of(read_file(csv));
  std::vector<std::string> cells = split(lines.at(1));
  cells.at(column) = value;
  std::string row;
  for (std::size_t c = 0; c < cells.size(); ++c) row += (c ? "," : "") + cells[c];
  lines[1] = row;
  std::string text;
  for (const std::string& l : lines) text += l + "\n";
  write_file(csv, text);
}

}  // namespace

// §5.8: stops.csv's cells are checked where they are read, naming stops.csv:LINE and the column:
// frames=3000000000 (cast to int before, then a misleading exit 3), a bad utc and a negative
// level (only the folder was named) in a DoFP dataset; polarized: 7 in a four-camera one.
TEST_F(CliInputs, StopsCsvCellsAreCheckedNamingFileLineAndColumn) {
  const fs::path dofp = dofp_dataset("dofp");
  const fs::path csv = dofp / "stops.csv";
  const std::string good = read_file(csv);
  const struct {
    std::size_t column;
    const char* value;
    const char* says;
  } cases[] = {
      {7, "3000000000", "column frames: 3000000000 (expected a whole number in [1, 65536])"},
      {3, "2015-13-45T99:00:00Z", "column utc: '2015-13-45T99:00:00Z'"},
      {4, "-0.5", "column intensity: -0.5 (expected a number ≥ 0)"},
      {5, "7", "column polarized: 7 (expected 0 or 1)"},
  };
  for (const auto& c : cases) {
    write_file(csv, good);
    set_cell(csv, c.column, c.value);
    refused("orient " + shell_quote(dofp), csv.string() + ":2: " + c.says);
    refused("calibrate " + shell_quote(dofp) + " --method dofp", csv.string() + ":2: " + c.says);
  }
  const fs::path four = four_camera_dataset("four");
  set_cell(four / "stops.csv", 5, "7");
  refused("locate " + shell_quote(four) + " --prior 29,113.5",
          (four / "stops.csv").string() + ":2: column polarized: 7 (expected 0 or 1)");
}

// §5.9: a folder given where a YAML file is read (--calibration, --geometry; every YAML reader
// shares the check) is named as a directory, exit 2 ("basic_filebuf::underflow", exit 1, before);
// an empty --params, --calibration or --geometry is refused, not taken as absent.
TEST_F(CliInputs, FoldersAndEmptyNamesGivenAsFilesAreRefused) {
  const fs::path four = four_camera_dataset("four");
  fs::create_directories(tmp / "cal.yaml");
  const std::string directory = (tmp / "cal.yaml").string() + ": cannot read the calibration file: it is a directory";
  refused("locate " + shell_quote(four) + " --prior 29,113.5 --calibration " + shell_quote(tmp / "cal.yaml"), directory);
  refused("calibrate " + shell_quote(four) + " --method four-camera --geometry " + shell_quote(tmp / "cal.yaml"),
          directory);
  refused("locate " + shell_quote(four) + " --prior 29,113.5 --calibration ''", "--calibration '': expected a file name");
  refused("calibrate " + shell_quote(four) + " --method four-camera --geometry ''", "--geometry '': expected a file name");
  const fs::path dofp = dofp_dataset("dofp");
  refused("orient " + shell_quote(dofp) + " --params ''", "--params '': expected a file name");

}
