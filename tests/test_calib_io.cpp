// Reading calibration inputs and outputs: measured CSV files and dataset folders (DataError
// naming file:line and column), params.yaml (exact round trip and errors), a rig's
// device.truth_from, and calibrate()'s refusals of data it cannot calibrate.
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <tuple>
#include <vector>

#include <fmt/format.h>

#include "polrig/calib/fit.h"
#include "polrig/calib/pipeline.h"
#include "polrig/calib/preprocess.h"
#include "polrig/io/measured.h"
#include "polrig/io/params_yaml.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/rig/rig.h"
#include "polrig/sim/simulate.h"
#include "support.h"

namespace polrig {
namespace {
namespace fs = std::filesystem;

using test::write_file;

// The message of the exception of type E that `f` throws; a test failure (and "") if it throws
// nothing or something else.
template <class E>
std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "threw the wrong exception type: " << e.what();
    return "";
  }
  ADD_FAILURE() << "did not throw";
  return "";
}

bool same_bits(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}
template <std::size_t N>
::testing::AssertionResult SameBits(const char* a_expr, const char* b_expr,
                                    const std::array<double, N>& a, const std::array<double, N>& b) {
  for (std::size_t i = 0; i < N; ++i)
    if (!same_bits(a[i], b[i]))
      return ::testing::AssertionFailure()
             << a_expr << "[" << i << "] = " << fmt::format("{}", a[i]) << " but " << b_expr
             << "[" << i << "] = " << fmt::format("{}", b[i]);
  return ::testing::AssertionSuccess();
}

// A fresh temporary folder per test, removed afterwards.
class CalibIo : public ::testing::Test {
 protected:
  test::TempDir temp_dir{"polrig_test_calib_io_"};
  const fs::path tmp = temp_dir.path();
  // Writes tmp/NAME and returns its path.
  fs::path file(const std::string& name, const std::string& text) {
    write_file(tmp / name, text);
    return tmp / name;
  }
};

// The default rig's stops as StopVoltages (V_mean), labelled "stop N".
std::vector<StopVoltages> default_stops(const Rig& rig = Rig{}) {
  const Simulation sim = simulate(rig);
  std::vector<StopVoltages> out;
  for (std::size_t n = 0; n < sim.stops.size(); ++n)
    out.push_back({sim.stops[n].theta_R_deg, sim.stops[n].V_mean, fmt::format("stop {}", n)});
  return out;
}

CalibrationResult cs_result() {
  CalibrationOptions o;
  o.method = CalibrationMethod::CentralSymmetry;
  o.d_a = 0.55;
  return calibrate(default_stops(), o);
}

const std::string kHeader = "theta_R_deg,V1,V2,V3\n";

// ---------------------------------------------------------------------------------------------
// CSV files: errors name file:line and the column
// ---------------------------------------------------------------------------------------------

TEST_F(CalibIo, MissingFileIsADataErrorNamingThePath) {
  const fs::path p = tmp / "nope.csv";
  const std::string e = error_of<DataError>([&] { read_measured(p); });
  EXPECT_EQ(e, p.string() + ": cannot read the file: no such file");
  const std::string e2 = error_of<DataError>([&] { CsvFile::read(p); });
  EXPECT_EQ(e2, e);
}

TEST_F(CalibIo, EmptyFileIsADataError) {
  const fs::path p = file("empty.csv", "");
  const std::string e = error_of<DataError>([&] { read_measured(p); });
  EXPECT_HAS(e, p.string() + ": the file is empty");
  // Only comments and blank lines: still no header.
  const fs::path c = file("comments.csv", "# a comment\n\n   \n# another\n");
  EXPECT_HAS(error_of<DataError>([&] { read_measured(c); }), c.string() + ": the file is empty");
}

TEST_F(CalibIo, HeaderOnlyIsADataError) {
  const fs::path p = file("header.csv", kHeader);
  EXPECT_EQ(error_of<DataError>([&] { read_measured(p); }),
            p.string() + ": no data rows after the header");
  const fs::path v = file("vheader.csv", "V1,V2,V3\n# nothing\n\n");
  EXPECT_EQ(error_of<DataError>([&] { read_voltages(v); }),
            v.string() + ": no data rows after the header");
}

TEST_F(CalibIo, MissingColumnNamesTheColumn) {
  const fs::path p = file("nov2.csv", "theta_R_deg,V1,V3\n0,0.1,0.2\n");
  const std::string e = error_of<DataError>([&] { read_measured(p); });
  EXPECT_HAS(e, p.string() + ":1: missing column 'V2'");
  const fs::path t = file("notheta.csv", "V1,V2,V3\n0.1,0.2,0.3\n");
  EXPECT_HAS(error_of<DataError>([&] { read_measured(t); }),
             t.string() + ":1: missing column 'theta_R_deg'");
}

TEST_F(CalibIo, MissingColumnNamesTheHeaderLineAfterComments) {
  // The header is on line 3, after a comment and a blank line: the message names line 3.
  const fs::path c = file("late.csv", "# c\n\ntheta_R_deg,V1,V2\n0,1,2\n");
  EXPECT_HAS(error_of<DataError>([&] { read_measured(c); }), c.string() + ":3: missing column 'V3'");
  const CsvFile f = CsvFile::read(c);
  EXPECT_HAS(error_of<DataError>([&] { f.column("V4"); }), c.string() + ":3: missing column 'V4'");
}

TEST_F(CalibIo, RowWithTooFewFieldsNamesTheLine) {
  const fs::path p = file("short.csv", kHeader + "0,0.1,0.2,0.3\n10,0.1,0.2\n");
  EXPECT_EQ(error_of<DataError>([&] { read_measured(p); }),
            p.string() + ":3: expected 4 fields as in the header, got 3");
  const fs::path l = file("long.csv", kHeader + "0,0.1,0.2,0.3,9\n");
  EXPECT_EQ(error_of<DataError>([&] { read_measured(l); }),
            l.string() + ":2: expected 4 fields as in the header, got 5");
}

TEST_F(CalibIo, BadNumbersNameFileLineAndColumn) {
  struct Case {
    std::string body;  // data lines after the header (line 1)
    int line;
    std::string column, cell;
  };
  const std::vector<Case> cases = {
      {"0,0.1,0.2,0.3\n10,0.1,0.2,0.3\n20,abc,0.2,0.3\n", 4, "V1", "abc"},
      {"0,0.1,nan,0.3\n", 2, "V2", "nan"},
      {"0,0.1,0.2,inf\n", 2, "V3", "inf"},
      {"0,0.1,0.2,-inf\n", 2, "V3", "-inf"},
      {"0,0.1,0.2,0.3\n,0.1,0.2,0.3\n", 3, "theta_R_deg", ""},
      {"0,0.1,0.2,0.3\n10,0.1,,0.3\n", 3, "V2", ""},
      {"0,0.1,0.2,0.3\n10,0.1,0.2,\n", 3, "V3", ""},
      {"0,12abc,0.2,0.3\n", 2, "V1", "12abc"},
      {"0,0.1,0.2,1e999\n", 2, "V3", "1e999"},
      // Comments and blank lines count as lines.
      {"# comment\n0,0.1,0.2,0.3\n\n10,0.1,0.2,0.3\n# x\n20,0.1,0.2,oops\n", 7, "V3", "oops"},
  };
  for (std::size_t k = 0; k < cases.size(); ++k) {
    SCOPED_TRACE(cases[k].body);
    const fs::path p = file(fmt::format("bad{}.csv", k), kHeader + cases[k].body);
    EXPECT_EQ(error_of<DataError>([&] { read_measured(p); }),
              fmt::format("{}:{}: column '{}': expected a finite number, got '{}'", p.string(),
                          cases[k].line, cases[k].column, cases[k].cell));
  }
}

TEST_F(CalibIo, CrlfCommentsBlankLinesExtraColumnsAndAnyColumnOrder) {
  const fs::path p = file("crlf.csv",
                          "# exported by a logger\r\n"                  // 1
                          "\r\n"                                        // 2
                          "V3,note,V1,theta_R_deg,V2,extra\r\n"         // 3
                          "0.3,first,0.1,0,0.2,x\r\n"                   // 4
                          "# pause\r\n"                                 // 5
                          "   \r\n"                                     // 6
                          "-0.25,second,1e-3,10.5,+0.125,y\r\n");       // 7
  const MeasuredData d = read_measured(p);
  EXPECT_EQ(d.origin, p.string());
  EXPECT_FALSE(d.rig.has_value());
  ASSERT_EQ(d.stops.size(), 2u);
  EXPECT_EQ(d.stops[0].theta_R_deg, 0.0);
  EXPECT_EQ(d.stops[0].V, (std::array<double, 3>{0.1, 0.2, 0.3}));
  EXPECT_EQ(d.stops[0].label, p.string() + ":4");
  EXPECT_EQ(d.stops[1].theta_R_deg, 10.5);
  EXPECT_EQ(d.stops[1].V, (std::array<double, 3>{1e-3, 0.125, -0.25}));
  EXPECT_EQ(d.stops[1].label, p.string() + ":7");

  const CsvFile f = CsvFile::read(p);
  EXPECT_EQ(f.header, (std::vector<std::string>{"V3", "note", "V1", "theta_R_deg", "V2", "extra"}));
  EXPECT_EQ(f.line, (std::vector<int>{4, 7}));
  EXPECT_EQ(f.column("theta_R_deg"), 3u);
  EXPECT_FALSE(f.find_column("V4").has_value());
  EXPECT_HAS(error_of<DataError>([&] { f.column("V4"); }), "missing column 'V4'");
  // A text column is fine until someone asks for it as a number.
  EXPECT_EQ(error_of<DataError>([&] { f.number(1, 1); }),
            p.string() + ":7: column 'note': expected a finite number, got 'second'");
}

// The fuzzers' entry point (fuzz/fuzz_measured_csv.cpp) reads text exactly as the file reader.
TEST_F(CalibIo, ParseMeasuredCsvReadsTheTextAsTheFileReaderReadsTheFile) {
  const std::string text = "# c\r\nV2,theta_R_deg,V1,V3\r\n0.2,0,0.1,0.3\n\n0.5,10.5,-1e-3,+0.125\n";
  const fs::path p = file("same.csv", text);
  const MeasuredData a = read_measured(p);
  const MeasuredData b = parse_measured_csv(text, p.string(), true);
  ASSERT_EQ(b.stops.size(), a.stops.size());
  for (std::size_t i = 0; i < a.stops.size(); ++i) {
    EXPECT_EQ(b.stops[i].theta_R_deg, a.stops[i].theta_R_deg);
    EXPECT_EQ(b.stops[i].V, a.stops[i].V);
    EXPECT_EQ(b.stops[i].label, a.stops[i].label);
  }
  EXPECT_EQ(error_of<DataError>([&] { parse_measured_csv("V1,V2\n1,2\n", "x.csv", false); }),
            "x.csv:1: missing column 'V3' (see docs/formats.md, \"Measured data\")");
  EXPECT_TRUE(std::isnan(parse_measured_csv("V1,V2,V3\n1,2,3\n", "x.csv", false).stops[0].theta_R_deg));
}

TEST_F(CalibIo, ReadMeasuredReadsADatasetFolderAndItsRig) {
  Rig rig;
  rig.device.d = 0.3;
  rig.seed = 7;
  rig.electronics.volts_per_decade = 0.45;
  const Simulation sim = simulate(rig);
  std::string text = "stop,theta_R_deg,theta_deg,d,V1,V2,V3,V1_std\n";
  for (std::size_t n = 0; n < sim.stops.size(); ++n) {
    const Stop& s = sim.stops[n];
    text += fmt::format("{},{},{},{},{},{},{},{}\n", n, s.theta_R_deg, s.light.theta_deg,
                        s.light.d, s.V_mean[0], s.V_mean[1], s.V_mean[2], s.V_std[0]);
  }
  const fs::path dir = tmp / "dataset";
  fs::create_directories(dir);
  write_file(dir / "stops.csv", text);
  write_file(dir / "rig.yaml", rig_to_yaml(rig));

  const MeasuredData d = read_measured(dir);
  EXPECT_EQ(d.origin, (dir / "stops.csv").string());
  ASSERT_TRUE(d.rig.has_value());
  EXPECT_EQ(d.rig->device.d, 0.3);
  EXPECT_EQ(d.rig->seed, 7u);
  EXPECT_EQ(d.rig->electronics.volts_per_decade, 0.45);
  EXPECT_EQ(rig_to_yaml(*d.rig), rig_to_yaml(rig));
  ASSERT_EQ(d.stops.size(), 37u);
  for (std::size_t n = 0; n < d.stops.size(); ++n) {
    SCOPED_TRACE(n);
    EXPECT_EQ(d.stops[n].theta_R_deg, sim.stops[n].theta_R_deg);
    EXPECT_EQ(d.stops[n].V, sim.stops[n].V_mean);  // shortest round-trip text: exact
    EXPECT_EQ(d.stops[n].label, fmt::format("{}:{}", (dir / "stops.csv").string(), n + 2));
  }

  // Without rig.yaml: the stops, no rig.
  fs::remove(dir / "rig.yaml");
  EXPECT_FALSE(read_measured(dir).rig.has_value());
  // A folder without stops.csv names the file it looked for.
  const fs::path empty = tmp / "no-stops";
  fs::create_directories(empty);
  EXPECT_HAS(error_of<DataError>([&] { read_measured(empty); }),
             (empty / "stops.csv").string() + ": cannot read the file");
  // A broken rig.yaml in the dataset is a RigError naming it.
  write_file(dir / "rig.yaml", "device:\n  d: 3\n");
  const std::string e = error_of<RigError>([&] { read_measured(dir); });
  EXPECT_HAS(e, (dir / "rig.yaml").string() + ":2: key 'device.d'");
}

TEST_F(CalibIo, ReadVoltagesAcceptsAFileWithoutTheta) {
  const fs::path p = file("v.csv", "V1,V2,V3\n0.1,0.2,0.3\n-0.1,-0.2,-0.3\n");
  const MeasuredData d = read_voltages(p);
  ASSERT_EQ(d.stops.size(), 2u);
  EXPECT_TRUE(std::isnan(d.stops[0].theta_R_deg));
  EXPECT_TRUE(std::isnan(d.stops[1].theta_R_deg));
  EXPECT_EQ(d.stops[1].V, (std::array<double, 3>{-0.1, -0.2, -0.3}));
  EXPECT_EQ(d.stops[1].label, p.string() + ":3");
  // With theta_R_deg it is read; read_measured insists on it.
  const fs::path q = file("vt.csv", "V1,V2,V3,theta_R_deg\n0.1,0.2,0.3,45\n");
  EXPECT_EQ(read_voltages(q).stops.at(0).theta_R_deg, 45.0);
  EXPECT_HAS(error_of<DataError>([&] { read_measured(p); }),
             p.string() + ":1: missing column 'theta_R_deg'");
  // V columns are still required, and a bad theta is still an error.
  const fs::path r = file("nov1.csv", "V2,V3\n0.1,0.2\n");
  EXPECT_HAS(error_of<DataError>([&] { read_voltages(r); }), r.string() + ":1: missing column 'V1'");
  const fs::path s = file("badtheta.csv", "V1,V2,V3,theta_R_deg\n0.1,0.2,0.3,abc\n");
  EXPECT_EQ(error_of<DataError>([&] { read_voltages(s); }),
            s.string() + ":2: column 'theta_R_deg': expected a finite number, got 'abc'");
}

// ---------------------------------------------------------------------------------------------
// params.yaml
// ---------------------------------------------------------------------------------------------

TEST_F(CalibIo, ParamsYamlRoundTripsBitForBit) {
  const CalibrationResult r = cs_result();
  // The result is a real calibration, not the theory values.
  EXPECT_NE(r.params.kd, CalibrationParams{}.kd);
  EXPECT_EQ(r.d_a, 0.55);
  for (double vdec : {0.5, 1.0 / 3.0, 0.1 + 0.2}) {
    SCOPED_TRACE(vdec);
    const std::string text = params_to_yaml(r, vdec);
    EXPECT_HAS(text, "method: cs\n");
    EXPECT_HAS(text, "d_a: 0.55\n");
    const fs::path p = file("params.yaml", text);
    const LoadedParams back = read_params_yaml(p);
    EXPECT_PRED_FORMAT2(SameBits, back.params.alpha_deg, r.params.alpha_deg);
    EXPECT_PRED_FORMAT2(SameBits, back.params.k_mV, r.params.k_mV);
    EXPECT_PRED_FORMAT2(SameBits, back.params.kv, r.params.kv);
    EXPECT_PRED_FORMAT2(SameBits, back.params.kd, r.params.kd);
    EXPECT_TRUE(same_bits(back.d_a, r.d_a));
    EXPECT_TRUE(same_bits(back.volts_per_decade, vdec)) << fmt::format("{}", back.volts_per_decade);
    EXPECT_TRUE(back.params == r.params);
  }
}

class ParamsErrors : public CalibIo {
 protected:
  // Line numbers: d_a 1, volts_per_decade 2, alpha_deg 3, k_mV 4, kv 5, kd 6.
  std::vector<std::string> lines = {
      "d_a: 0.55",
      "volts_per_decade: 0.5",
      "alpha_deg: [0.75, 0.55, -117.6, -116.5, 123.07, 120.7]",
      "k_mV: [-10.15, 7.92, -9.45]",
      "kv: [1.0224, 1.0081, 1.0183]",
      "kd: [-0.0438, -0.0365, -0.0457, -0.0492, -0.0555, -0.0166]",
  };
  fs::path write(const std::vector<std::string>& l) {
    std::string text;
    for (const std::string& s : l) text += s + "\n";
    return file("params.yaml", text);
  }
  // The error for the file with line `n` (1-based) replaced (or removed when `text` is empty).
  std::string error_with(int n, const std::string& text) {
    std::vector<std::string> l = lines;
    if (text.empty())
      l.erase(l.begin() + (n - 1));
    else
      l[static_cast<std::size_t>(n - 1)] = text;
    const fs::path p = write(l);
    return error_of<DataError>([&] { read_params_yaml(p); });
  }
  std::string path() const { return (tmp / "params.yaml").string(); }
};

TEST_F(ParamsErrors, TheBaseFileLoads) {
  const LoadedParams p = read_params_yaml(write(lines));
  EXPECT_EQ(p.d_a, 0.55);
  EXPECT_EQ(p.params.kv, (std::array<double, 3>{1.0224, 1.0081, 1.0183}));
  EXPECT_EQ(p.params.alpha_deg[2], -117.6);
  EXPECT_EQ(p.params.kd[5], -0.0166);
}

TEST_F(ParamsErrors, ParseParamsYamlReadsTheTextAsTheFileReaderReadsTheFile) {
  std::string text;
  for (const std::string& s : lines) text += s + "\n";
  const LoadedParams a = read_params_yaml(write(lines));
  const LoadedParams b = parse_params_yaml(text, path());
  EXPECT_TRUE(b.params == a.params);
  EXPECT_EQ(b.d_a, a.d_a);
  EXPECT_EQ(b.volts_per_decade, a.volts_per_decade);
  text.replace(text.find("d_a: 0.55"), 9, "d_a: 1.5");
  EXPECT_EQ(error_of<DataError>([&] { parse_params_yaml(text, "p.yaml"); }),
            "p.yaml:1: key 'd_a': expected a value in (0, 1) (a degree of polarization), got 1.5");
}

TEST_F(ParamsErrors, UnknownKey) {
  std::vector<std::string> l = lines;
  l.insert(l.begin() + 2, "bogus: 1");  // line 3
  const fs::path p = write(l);
  EXPECT_EQ(error_of<DataError>([&] { read_params_yaml(p); }),
            path() + ":3: key 'bogus': unknown key");
}

TEST_F(ParamsErrors, MissingKeys) {
  EXPECT_EQ(error_with(6, ""), path() + ": missing key 'kd'");
  EXPECT_EQ(error_with(1, ""), path() + ": missing key 'd_a'");
  EXPECT_EQ(error_with(3, ""), path() + ": missing key 'alpha_deg'");
}

TEST_F(ParamsErrors, WrongListLength) {
  EXPECT_EQ(error_with(5, "kv: [1, 1]"), path() + ":5: key 'kv': expected a list of 3 numbers");
  EXPECT_EQ(error_with(6, "kd: [0, 0, 0, 0, 0, 0, 0]"),
            path() + ":6: key 'kd': expected a list of 6 numbers");
  EXPECT_EQ(error_with(4, "k_mV: 3"), path() + ":4: key 'k_mV': expected a list of 3 numbers");
}

TEST_F(ParamsErrors, NotANumber) {
  EXPECT_EQ(error_with(4, "k_mV: [-10.15, abc, -9.45]"),
            path() + ":4: key 'k_mV': expected a number, got 'abc'");
  EXPECT_EQ(error_with(1, "d_a: half"), path() + ":1: key 'd_a': expected a number, got 'half'");
  EXPECT_HAS(error_with(3, "alpha_deg: [0, 0, .nan, 0, 0, 0]"),
             path() + ":3: key 'alpha_deg': expected a value in [-720, 720] (");
  EXPECT_HAS(error_with(3, "alpha_deg: [0, 0, .nan, 0, 0, 0]"), "got .nan");
}

TEST_F(ParamsErrors, DaOutsideTheOpenUnitInterval) {
  for (const char* v : {"0", "1", "1.5", "-0.2"}) {
    SCOPED_TRACE(v);
    EXPECT_EQ(error_with(1, std::string("d_a: ") + v),
              path() + ":1: key 'd_a': expected a value in (0, 1) (a degree of polarization), got " + v);
  }
}

TEST_F(ParamsErrors, EveryValueHasAPhysicalRange) {
  // Issue 8 §3.3: volts_per_decade = 1e-300 was accepted and apply wrote −nan angles.
  const std::vector<std::tuple<int, std::string, std::string>> cases = {
      {2, "volts_per_decade: 1e-300", ":2: key 'volts_per_decade': expected a value in [0.01, 10] "},
      {2, "volts_per_decade: 0", ":2: key 'volts_per_decade': expected a value in [0.01, 10] "},
      {2, "volts_per_decade: 1e300", "got 1e300"},
      {3, "alpha_deg: [0.75, 0.55, -117.6, 1e300, 123.07, 120.7]",
       ":3: key 'alpha_deg': expected a value in [-720, 720] "},
      {4, "k_mV: [-10.15, 7.92, 2000]", ":4: key 'k_mV': expected a value in [-1000, 1000] "},
      {5, "kv: [1, 0, 1]", ":5: key 'kv': expected a value in [0.5, 2] "},
      {5, "kv: [1, 1, -1]", "got -1"},
      {6, "kd: [0, 0, -1, 0, 0, 0]", ":6: key 'kd': expected a value in (-1, 1) "},
  };
  for (const auto& [line, text, want] : cases) {
    SCOPED_TRACE(text);
    EXPECT_HAS(error_with(line, text), want);
  }
  // c_m = (1 + kd_m)·d_a must stay below 1 (Eq. 15's domain).
  EXPECT_HAS(error_with(6, "kd: [0, 0, 0, 0.9, 0, 0]"),
             ":6: key 'kd': kd_4 = 0.9 with d_a = 0.55 gives (1 + kd)·d_a ≥ 1");
}

TEST_F(ParamsErrors, ListElementsAreNamedOnTheirOwnLine) {
  std::vector<std::string> l = lines;
  l[4] = "kv:\n  - 1\n  - 5\n  - 1";  // lines 5..8; the bad element on line 7
  const fs::path p = write(l);
  EXPECT_HAS(error_of<DataError>([&] { read_params_yaml(p); }),
             path() + ":7: key 'kv': expected a value in [0.5, 2]");
}

TEST_F(ParamsErrors, DuplicateKeysNameBothLines) {
  // Issue 8 §3.10: yaml-cpp keeps both entries and returns the first; the file is ambiguous.
  std::vector<std::string> l = lines;
  l.push_back("kv: [1, 1, 1]");  // line 7 repeats line 5
  const fs::path p = write(l);
  EXPECT_EQ(error_of<DataError>([&] { read_params_yaml(p); }),
            path() + ":7: key 'kv': duplicate key (first at line 5)");
  // In a nested mapping too.
  l = lines;
  l.push_back("fit:\n  iterations: 5\n  observations: 57\n  iterations: 6");
  const fs::path q = write(l);
  EXPECT_EQ(error_of<DataError>([&] { read_params_yaml(q); }),
            path() + ":10: key 'iterations': duplicate key (first at line 8)");
}

TEST_F(ParamsErrors, YamlSyntaxErrorAndMissingFile) {
  const std::string e = error_with(5, "kv: [1, 1, 1]]");
  EXPECT_HAS(e, path() + ":5:");
  EXPECT_HAS(e, "YAML syntax error");
  const fs::path none = tmp / "missing" / "params.yaml";
  EXPECT_EQ(error_of<DataError>([&] { read_params_yaml(none); }),
            none.string() + ": cannot read the parameter file: no such file");
}

// ---------------------------------------------------------------------------------------------
// device.truth_from
// ---------------------------------------------------------------------------------------------

TEST_F(CalibIo, TruthFromLoadsTheParamsNextToTheRigFile) {
  const CalibrationResult r = cs_result();
  write_file(tmp / "params.yaml", params_to_yaml(r, 0.5));
  const fs::path rig_file = file("rig.yaml", "device: {truth_from: params.yaml}\nseed: 3\n");
  const Rig rig = load_rig(rig_file).rig;
  EXPECT_TRUE(rig.device.truth == r.params);
  EXPECT_TRUE(rig.device.truth_from.empty());
  EXPECT_FALSE(rig.device.truth == CalibrationParams::wang2019_indoor());
  EXPECT_EQ(rig.seed, 3u);

  // rig_to_yaml writes the values themselves, and they load back identically.
  const std::string text = rig_to_yaml(rig);
  EXPECT_EQ(text.find("truth_from"), std::string::npos) << text;
  EXPECT_HAS(text, "truth:");
  const Rig back = parse_rig(text, "resolved").rig;
  EXPECT_TRUE(back.device.truth == r.params);
  EXPECT_EQ(rig_to_yaml(back), text);

  // The path is relative to the rig file, not to the working directory.
  const fs::path sub = tmp / "sub";
  fs::create_directories(sub);
  write_file(sub / "rig.yaml", "device:\n  truth_from: ../params.yaml\n");
  EXPECT_TRUE(load_rig(sub / "rig.yaml").rig.device.truth == r.params);
}

TEST_F(CalibIo, TruthFromAndTruthKeysExcludeEachOther) {
  write_file(tmp / "params.yaml", params_to_yaml(cs_result(), 0.5));
  const fs::path rig_file =
      file("rig.yaml", "device:\n  truth_from: params.yaml\n  truth:\n    kv: [1, 1, 1]\n");
  const std::string e = error_of<RigError>([&] { load_rig(rig_file); });
  EXPECT_HAS(e, rig_file.string() + ":2: key 'device.truth_from'");
  EXPECT_HAS(e, "device.truth.kv");
  // The same through an override.
  const fs::path plain = file("plain.yaml", "device:\n  truth_from: params.yaml\n");
  const std::string o = error_of<RigError>(
      [&] { load_rig(plain, {RigOverride::parse("device.truth.kd=[0, 0, 0, 0, 0, 0]")}); });
  EXPECT_HAS(o, "device.truth_from");
  EXPECT_HAS(o, "device.truth.kd");
}

TEST_F(CalibIo, TruthFromMissingOrBadParamsIsARigError) {
  const fs::path rig_file = file("rig.yaml", "seed: 1\ndevice: {truth_from: nothere.yaml}\n");
  const std::string e = error_of<RigError>([&] { load_rig(rig_file); });
  EXPECT_HAS(e, rig_file.string() + ":2: key 'device.truth_from'");
  EXPECT_HAS(e, (tmp / "nothere.yaml").string());
  // A params file with an error: the message carries the params file's own file:line.
  write_file(tmp / "bad.yaml", "d_a: 0.55\nalpha_deg: [0, 0, 0, 0, 0, 0]\nk_mV: [0, 0, 0]\n"
                               "kv: [1, 0, 1]\nkd: [0, 0, 0, 0, 0, 0]\n");
  const fs::path bad_rig = file("bad-rig.yaml", "device: {truth_from: bad.yaml}\n");
  const std::string b = error_of<RigError>([&] { load_rig(bad_rig); });
  EXPECT_HAS(b, "device.truth_from");
  EXPECT_HAS(b, (tmp / "bad.yaml").string() + ":4: key 'kv': expected a value in [0.5, 2]");
}

TEST_F(CalibIo, TruthFromGivesARigThatRigToYamlCanWriteAndReload) {
  // A calibration decoupled with a d_a below the light's d gives kd > 0 (params.yaml accepts
  // kd > −1), while a rig's device.truth.kd must lie in (−1, 0]. Whatever the loader decides,
  // the rig it returns must survive rig_to_yaml → parse_rig (the dataset's rig.yaml is written
  // that way): either truth_from refuses kd > 0 naming kd, or the round trip works.
  write_file(tmp / "params.yaml",
             "d_a: 0.5\nalpha_deg: [0, 0, -120, -120, 120, 120]\nk_mV: [0, 0, 0]\n"
             "kv: [1, 1, 1]\nkd: [0.05, 0, 0, 0, 0, 0]\n");
  const fs::path rig_file = file("rig.yaml", "device: {truth_from: params.yaml, d: 0.5}\n");
  Rig rig;
  try {
    rig = load_rig(rig_file).rig;
  } catch (const RigError& e) {
    EXPECT_HAS(std::string(e.what()), "kd");
    return;
  }
  const std::string text = rig_to_yaml(rig);
  try {
    const Rig back = parse_rig(text, "rig_to_yaml output").rig;
    EXPECT_TRUE(back.device.truth == rig.device.truth);
  } catch (const RigError& e) {
    ADD_FAILURE() << "a rig loaded with device.truth_from does not load back from rig_to_yaml: "
                  << e.what();
  }
}

// ---------------------------------------------------------------------------------------------
// calibrate(): data it cannot calibrate
// ---------------------------------------------------------------------------------------------

// The fit summary of a calibration that must not be usable; a test failure if it is.
FitSummary failure_of(const std::vector<StopVoltages>& stops, const CalibrationOptions& o) {
  const CalibrationResult r = calibrate(stops, o);
  EXPECT_FALSE(r.usable()) << "calibrated: " << r.fit.summary.brief_report();
  return r.fit.summary;
}

TEST(CalibrateData, TooFewStops) {
  std::vector<StopVoltages> stops = default_stops();
  stops.resize(5);
  CalibrationOptions o;
  o.method = CalibrationMethod::Section;
  o.d_a = 0.55;
  const FitSummary e = failure_of(stops, o);
  EXPECT_EQ(e.termination, FitTermination::TooFewObservations);
  EXPECT_HAS(e.message, "5 stops to fit");
  EXPECT_HAS(e.message, "at least 6");
  // Paired stops giving 5 CS points: 0..40° and 180..220°.
  std::vector<StopVoltages> all = default_stops(), paired;
  for (std::size_t n : {0, 1, 2, 3, 4, 18, 19, 20, 21, 22}) paired.push_back(all[n]);
  o.method = CalibrationMethod::CentralSymmetry;
  const FitSummary c = failure_of(paired, o);
  EXPECT_EQ(c.termination, FitTermination::TooFewObservations);
  EXPECT_HAS(c.message, "5 CS points to fit");
  EXPECT_HAS(c.message, "at least 6");
  // Six stops are enough for the count check: the outcome, if a failure, is not about the count.
  stops = std::vector<StopVoltages>(all.begin(), all.begin() + 6);
  o.method = CalibrationMethod::Section;
  const CalibrationResult r = calibrate(stops, o);
  EXPECT_NE(r.fit.summary.termination, FitTermination::TooFewObservations);
  EXPECT_EQ(r.fit.summary.message.find("at least 6"), std::string::npos) << r.fit.summary.message;
}

TEST(CalibrateData, TheFittedMaskFollowsTheRowsOfRepeatedStops) {
  // Every stop recorded twice: repeated stops are averaged before pairing, so the 74 rows give
  // the 19 CS points of one turn, not 76 copies. Keeping the 12 steepest per voltage marks
  // exactly 12 of the 19 points per voltage, one mask entry per observation row.
  std::vector<StopVoltages> stops = default_stops(), twice = stops;
  twice.insert(twice.end(), stops.begin(), stops.end());
  CalibrationOptions o;
  o.method = CalibrationMethod::CentralSymmetryNoncontinuous;
  o.d_a = 0.55;
  o.noncontinuous = {1.0, 12};
  const CalibrationResult r = calibrate(twice, o);
  ASSERT_TRUE(r.usable()) << r.fit.summary.brief_report();
  ASSERT_EQ(r.points.size(), 19u);
  EXPECT_EQ(r.fit.summary.observations, 36);
  for (int i = 0; i < 3; ++i) {
    int fitted = 0;
    for (bool b : r.fitted[static_cast<std::size_t>(i)]) fitted += b ? 1 : 0;
    EXPECT_EQ(fitted, 12) << "V" << i + 1;
  }
}

TEST(CalibrateData, UnpairedStopIsNamedForCentralSymmetry) {
  std::vector<StopVoltages> stops = default_stops();  // 0..360 in 10° steps: all paired
  StopVoltages odd = stops[18];
  odd.theta_R_deg = 185;
  odd.label = "my.csv:39";
  stops.push_back(odd);
  for (CalibrationMethod m :
       {CalibrationMethod::CentralSymmetry, CalibrationMethod::CentralSymmetryNoncontinuous}) {
    SCOPED_TRACE(std::string(method_name(m)));
    CalibrationOptions o;
    o.method = m;
    o.d_a = 0.55;
    const std::string e = error_of<CalibrationError>([&] { calibrate(stops, o); });
    EXPECT_HAS(e, "my.csv:39 (theta_R = 185°) has no partner 180° away");
  }
  // The section method does not need pairs.
  CalibrationOptions o;
  o.method = CalibrationMethod::Section;
  o.d_a = 0.55;
  EXPECT_NO_THROW(calibrate(stops, o));
}

// Unpolarized light (d = 0): every voltage is the pair's offset k_i, whatever θ_R.
std::vector<StopVoltages> unpolarized_stops(const std::array<double, 3>& k_mV) {
  std::vector<StopVoltages> stops;
  for (int n = 0; n <= 36; ++n) {
    StopVoltages s{10.0 * n, {0, 0, 0}, fmt::format("stop {}", n)};
    for (int i = 0; i < 3; ++i) s.V[i] = k_mV[i] * 1e-3;
    stops.push_back(s);
  }
  return stops;
}

void expect_too_small(const std::vector<StopVoltages>& stops) {
  for (CalibrationMethod m : kAllMethods) {
    SCOPED_TRACE(std::string(method_name(m)));
    CalibrationOptions o;
    o.method = m;
    o.d_a = 0.55;
    const FitSummary s = failure_of(stops, o);
    EXPECT_EQ(s.termination, FitTermination::RankDeficient);
    EXPECT_HAS(s.message, "too small");
    EXPECT_LACKS(s.message, "nan");
  }
}

TEST(CalibrateData, ASwingBeyondAnyPolarizationIsNotNan) {
  // Issue 8 §3.10: volts_per_decade = 1e-300 made 10^(swing/v) overflow, and the message said
  // "degree of polarization is about -nan". The swing is named instead.
  for (CalibrationMethod m : kAllMethods) {
    SCOPED_TRACE(std::string(method_name(m)));
    CalibrationOptions o;
    o.method = m;
    o.d_a = 0.55;
    o.volts_per_decade = 1e-300;
    const FitSummary s = failure_of(default_stops(), o);
    EXPECT_EQ(s.termination, FitTermination::OutsideDomain);
    EXPECT_HAS(s.message, "more than any degree of polarization below 1 can give");
    EXPECT_LACKS(s.message, "nan");
    EXPECT_LACKS(s.brief_report(), "-nan");
  }
}

TEST(CalibrateData, UnpolarizedLightWithoutOffsetsIsTooSmallToCalibrate) {
  expect_too_small(unpolarized_stops({0, 0, 0}));
}

TEST(CalibrateData, UnpolarizedLightWithTheRigsOffsetsIsTooSmallToCalibrate) {
  // The default rig's device under unpolarized light: V_i = k_i (−10.15, 7.92, −9.45 mV).
  expect_too_small(unpolarized_stops(CalibrationParams::wang2019_indoor().k_mV));
}

}  // namespace
}  // namespace polrig
