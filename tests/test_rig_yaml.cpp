// Rig files: parsing, overrides, every kind of error and the resolved-rig dump.
//
// Error messages are part of the interface: each names where the value came from (the file
// and 1-based line, or the --set argument), the key path and what was expected. The tests pin
// those pieces with exact substrings.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <array>
#include <cmath>
#include <functional>
#include <filesystem>
#include <limits>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "polrig/io/rig_yaml.h"
#include "polrig/rig/keys.h"
#include "polrig/rig/rig.h"
#include "support.h"

namespace fs = std::filesystem;
using polrig::LoadedRig;
using polrig::parse_rig;
using polrig::Rig;
using polrig::RigError;
using polrig::RigOverride;
using polrig::test::kDefaultRigFile;
using polrig::test::read_file;
using polrig::test::TempDir;
using polrig::test::write_file;

namespace {

constexpr const char* kOrigin = "rigs/test-rig.yaml";

std::vector<RigOverride> sets(std::initializer_list<const char*> args) {
  std::vector<RigOverride> out;
  for (const char* a : args) out.push_back(RigOverride::parse(a));
  return out;
}

// The RigError message of parsing `text` (as kOrigin); a test failure if nothing or something
// other than RigError is thrown.
std::string rig_error(std::string_view text, const std::vector<RigOverride>& overrides = {}) {
  try {
    parse_rig(text, kOrigin, overrides);
  } catch (const RigError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected polrig::RigError, got another exception: " << e.what()
                  << "\nfor the rig text:\n" << text;
    return "<not a RigError>";
  } catch (...) {
    ADD_FAILURE() << "expected polrig::RigError, got a non-std exception for:\n" << text;
    return "<not a RigError>";
  }
  ADD_FAILURE() << "expected polrig::RigError, nothing was thrown for the rig text:\n" << text;
  return "<nothing thrown>";
}

// Expects the error "<kOrigin>:<line>: key '<path>': <expected...>".
void expect_file_error(std::string_view text, int line, const std::string& path,
                       const std::string& expected) {
  const std::string msg = rig_error(text);
  EXPECT_STARTS(msg, std::string(kOrigin) + ":" + std::to_string(line) + ": key '" + path +
                         "': ");
  EXPECT_HAS(msg, expected);
}

Rig parse_ok(std::string_view text, const std::vector<RigOverride>& overrides = {}) {
  try {
    return parse_rig(text, kOrigin, overrides).rig;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "unexpected error: " << e.what() << "\nfor the rig text:\n" << text;
    return Rig{};
  }
}

// Field-by-field comparison of everything a rig file can set.
void expect_same_rig(const Rig& a, const Rig& b) {
  EXPECT_EQ(a.device.ring.L_photo, b.device.ring.L_photo);
  EXPECT_EQ(a.device.ring.beta_deg, b.device.ring.beta_deg);
  EXPECT_EQ(a.device.film_axis_deg, b.device.film_axis_deg);
  EXPECT_EQ(a.device.d, b.device.d);
  EXPECT_TRUE(a.device.truth == b.device.truth);
  EXPECT_EQ(a.device.truth.alpha_deg, b.device.truth.alpha_deg);
  EXPECT_EQ(a.device.truth.k_mV, b.device.truth.k_mV);
  EXPECT_EQ(a.device.truth.kv, b.device.truth.kv);
  EXPECT_EQ(a.device.truth.kd, b.device.truth.kd);
  EXPECT_EQ(a.source.model, b.source.model);
  EXPECT_EQ(a.source.cos4.L_o, b.source.cos4.L_o);
  EXPECT_EQ(a.source.cos4.E_0, b.source.cos4.E_0);
  EXPECT_EQ(a.source.polarizer_deg, b.source.polarizer_deg);
  EXPECT_EQ(a.eccentricity.L_IS, b.eccentricity.L_IS);
  EXPECT_EQ(a.eccentricity.alpha_IS, b.eccentricity.alpha_IS);
  EXPECT_EQ(a.eccentricity.L_S, b.eccentricity.L_S);
  EXPECT_EQ(a.eccentricity.alpha_S, b.eccentricity.alpha_S);
  EXPECT_EQ(a.schedule.start_deg, b.schedule.start_deg);
  EXPECT_EQ(a.schedule.step_deg, b.schedule.step_deg);
  EXPECT_EQ(a.schedule.stop_deg, b.schedule.stop_deg);
  EXPECT_EQ(a.schedule.angles_deg, b.schedule.angles_deg);
  EXPECT_EQ(a.schedule.samples_per_stop, b.schedule.samples_per_stop);
  EXPECT_EQ(a.electronics.volts_per_decade, b.electronics.volts_per_decade);
  EXPECT_EQ(a.electronics.adc_bits, b.electronics.adc_bits);
  EXPECT_EQ(a.electronics.vref_V, b.electronics.vref_V);
  EXPECT_EQ(a.electronics.noise_sigma_V, b.electronics.noise_sigma_V);
  EXPECT_EQ(a.seed, b.seed);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// The default rig and other valid files
// ---------------------------------------------------------------------------------------------

TEST(RigYaml, DefaultRigFileEqualsDefaultConstructedRig) {
  const LoadedRig loaded = polrig::load_rig(kDefaultRigFile);
  const Rig defaults;
  expect_same_rig(loaded.rig, defaults);
  EXPECT_TRUE(loaded.rig.device.truth == polrig::CalibrationParams::wang2019_indoor());
  EXPECT_EQ(loaded.rig.schedule.table_angles_deg().size(), 37u);
  EXPECT_EQ(loaded.rig.seed, 20190806u);
  EXPECT_EQ(loaded.origin, kDefaultRigFile);
  EXPECT_EQ(loaded.text, read_file(kDefaultRigFile));
  EXPECT_TRUE(loaded.overrides.empty());
  // Nothing that a file can set differs: the resolved dumps agree too.
  EXPECT_EQ(polrig::rig_to_yaml(loaded.rig), polrig::rig_to_yaml(defaults));
}

TEST(RigYaml, OneKeyFileKeepsEveryOtherDefault) {
  const Rig r = parse_ok("seed: 42\n");
  Rig expected;
  expected.seed = 42;
  expect_same_rig(r, expected);

  const Rig r2 = parse_ok("eccentricity:\n  L_S: 0.5\n");
  Rig expected2;
  expected2.eccentricity.L_S = 0.5;
  expect_same_rig(r2, expected2);
}

TEST(RigYaml, ExplicitAngleListReplacesStartStepStop) {
  const Rig r = parse_ok("schedule:\n  angles_deg: [0, 90, 180.5]\n  samples_per_stop: 3\n");
  EXPECT_EQ(r.schedule.angles_deg, (std::vector<double>{0, 90, 180.5}));
  EXPECT_EQ(r.schedule.table_angles_deg(), (std::vector<double>{0, 90, 180.5}));
  EXPECT_EQ(r.schedule.samples_per_stop, 3);
}

TEST(RigYaml, AcceptsBoundaryValues) {
  // Closed ends of the ranges are accepted; open ends are tested among the errors.
  const Rig r = parse_ok(
      "device:\n  truth:\n    kd: [0, 0, 0, 0, 0, -0.999]\n  d: 0.999999\n"
      "eccentricity:\n  L_IS: 0\n  L_S: 0\n"
      "electronics:\n  adc_bits: 31\n  noise_sigma_V: 0\n"
      "schedule:\n  samples_per_stop: 100000\n  start_deg: 10\n  stop_deg: 10\n"
      "seed: 18446744073709551615\n");
  EXPECT_EQ(r.device.truth.kd[5], -0.999);
  EXPECT_EQ(r.device.d, 0.999999);
  EXPECT_EQ(r.electronics.adc_bits, 31);
  EXPECT_EQ(r.electronics.noise_sigma_V, 0.0);
  EXPECT_EQ(r.schedule.samples_per_stop, 100000);
  EXPECT_EQ(r.schedule.table_angles_deg(), std::vector<double>{10.0});
  EXPECT_EQ(r.seed, std::numeric_limits<std::uint64_t>::max());
  EXPECT_EQ(parse_ok("electronics:\n  adc_bits: 2\n").electronics.adc_bits, 2);
  EXPECT_EQ(parse_ok("schedule:\n  samples_per_stop: 1\n").schedule.samples_per_stop, 1);
  EXPECT_EQ(parse_ok("seed: 0\n").seed, 0u);
}

// ---------------------------------------------------------------------------------------------
// Overrides
// ---------------------------------------------------------------------------------------------

TEST(RigOverrideParse, SplitsAtTheFirstEquals) {
  const RigOverride o = RigOverride::parse("device.truth.kv=[1, 1, 1]");
  EXPECT_EQ(o.path, "device.truth.kv");
  EXPECT_EQ(o.value, "[1, 1, 1]");
  EXPECT_EQ(o.text(), "--set device.truth.kv=[1, 1, 1]");
  const RigOverride o2 = RigOverride::parse("source.model=a=b");
  EXPECT_EQ(o2.path, "source.model");
  EXPECT_EQ(o2.value, "a=b");
  const RigOverride o3 = RigOverride::parse("device.d=");
  EXPECT_EQ(o3.path, "device.d");
  EXPECT_EQ(o3.value, "");
}

TEST(RigOverrideParse, WithoutEqualsThrows) {
  try {
    RigOverride::parse("device.d");
    FAIL() << "RigOverride::parse accepted an argument without '='";
  } catch (const RigError& e) {
    EXPECT_EQ(std::string(e.what()), "--set device.d: expected key.path=value");
  }
  try {
    RigOverride::parse("=0.5");
    FAIL() << "RigOverride::parse accepted an argument without a key";
  } catch (const RigError& e) {
    EXPECT_EQ(std::string(e.what()), "--set =0.5: expected key.path=value");
  }
}

TEST(RigYamlOverride, OverridesChangeScalarsAndLists) {
  const LoadedRig loaded =
      parse_rig(read_file(kDefaultRigFile), kOrigin,
                sets({"device.d=0.3", "device.truth.kv=[1,1,1]", "schedule.samples_per_stop=7",
                      "electronics.adc_bits=12", "seed=99", "source.model=cos4",
                      "device.beta_deg=[1, 2, 3, 4, 5, 6]", "eccentricity.L_IS=0.25"}));
  const Rig& r = loaded.rig;
  EXPECT_EQ(r.device.d, 0.3);
  EXPECT_EQ(r.device.truth.kv, (std::array<double, 3>{1, 1, 1}));
  EXPECT_EQ(r.schedule.samples_per_stop, 7);
  EXPECT_EQ(r.electronics.adc_bits, 12);
  EXPECT_EQ(r.seed, 99u);
  EXPECT_EQ(r.device.ring.beta_deg, (std::array<double, 6>{1, 2, 3, 4, 5, 6}));
  EXPECT_EQ(r.eccentricity.L_IS, 0.25);
  // Untouched keys keep the file's values.
  const Rig defaults;
  EXPECT_EQ(r.device.truth.k_mV, defaults.device.truth.k_mV);
  EXPECT_EQ(r.device.truth.kd, defaults.device.truth.kd);
  EXPECT_EQ(r.eccentricity.L_S, defaults.eccentricity.L_S);
  EXPECT_EQ(r.source.cos4.L_o, defaults.source.cos4.L_o);
  // The LoadedRig keeps the file text before overrides, and the overrides in order.
  EXPECT_EQ(loaded.text, read_file(kDefaultRigFile));
  EXPECT_EQ(loaded.origin, kOrigin);
  ASSERT_EQ(loaded.overrides.size(), 8u);
  EXPECT_EQ(loaded.overrides[0].path, "device.d");
  EXPECT_EQ(loaded.overrides[1].value, "[1,1,1]");
}

TEST(RigYamlOverride, OverridesCreateMissingSections) {
  const Rig r = parse_ok("seed: 1\n", sets({"device.truth.kv=[2, 2, 2]", "eccentricity.L_S=0.5",
                                            "device.d=0.25"}));
  EXPECT_EQ(r.seed, 1u);
  EXPECT_EQ(r.device.truth.kv, (std::array<double, 3>{2, 2, 2}));
  EXPECT_EQ(r.eccentricity.L_S, 0.5);
  EXPECT_EQ(r.device.d, 0.25);
  EXPECT_EQ(r.device.truth.kd, Rig{}.device.truth.kd);
}

TEST(RigYamlOverride, OverridesOnAnEmptyFile) {
  const Rig r = parse_ok("", sets({"seed=7"}));
  EXPECT_EQ(r.seed, 7u);
  // An empty or comment-only file is the default rig, as `{}` is; a scalar document is not.
  expect_same_rig(parse_ok(""), Rig{});
  expect_same_rig(parse_ok("# only a comment\n"), Rig{});
  const std::string msg = rig_error("42\n");
  EXPECT_STARTS(msg, std::string(kOrigin) + ": expected a mapping of rig sections");
}

TEST(RigYamlOverride, LaterSetWins) {
  EXPECT_EQ(parse_ok("device:\n  d: 0.5\n", sets({"device.d=0.3", "device.d=0.4"})).device.d,
            0.4);
  // An invalid value overridden by a later valid one is not an error...
  EXPECT_EQ(parse_ok("seed: 1\n", sets({"device.d=2", "device.d=0.4"})).device.d, 0.4);
  // ...and the error names the --set that gave the value that was used.
  const std::string msg = rig_error("seed: 1\n", sets({"device.d=0.4", "device.d=2"}));
  EXPECT_STARTS(msg, "--set device.d=2: key 'device.d': ");
  EXPECT_HAS(msg, "expected a degree of polarization in (0, 1), got 2");
}

// ---------------------------------------------------------------------------------------------
// Errors: syntax, unknown and duplicate keys
// ---------------------------------------------------------------------------------------------

TEST(RigYamlError, YamlSyntaxErrorNamesFileLineAndColumn) {
  // Line 3 opens a flow list that is never closed; yaml-cpp notices on line 4.
  const std::string msg = rig_error("seed: 1\ndevice:\n  beta_deg: [0, 1, 2\n  d: 0.5\n");
  EXPECT_STARTS(msg, std::string(kOrigin) + ":4:4: YAML syntax error: ");
  EXPECT_HAS(msg, "end of sequence flow not found");

  // A key indented less than its siblings: another syntax error, still file:line:col.
  const std::string msg2 = rig_error("device:\n  d: 0.5\n L_photo: 14\n");
  EXPECT_STARTS(msg2, std::string(kOrigin) + ":3:2: YAML syntax error: ");
}

TEST(RigYamlError, UnknownTopLevelKey) {
  expect_file_error("seed: 5\nsauce:\n  L_o: 20\n", 2, "sauce",
                    "unknown key (see docs/formats.md for the rig's keys)");
}

TEST(RigYamlError, UnknownKeyInsideSection) {
  expect_file_error("source:\n  model: cos4\n  L_0: 20\n", 3, "source.L_0",
                    "unknown key (did you mean 'source.L_o'?) (see docs/formats.md for the rig's keys)");
  expect_file_error("device:\n  truth:\n    kv: [1, 1, 1]\n    kx: 1\n", 4, "device.truth.kx",
                    "unknown key");
  // A leaf key used as a section.
  expect_file_error("device:\n  d:\n    value: 0.5\n", 2, "device.d",
                    "expected a degree of polarization in (0, 1)");
}

TEST(RigYamlError, UnknownKeyViaSet) {
  const std::string msg = rig_error("seed: 5\n", sets({"source.L_0=20"}));
  EXPECT_EQ(msg, "--set source.L_0=20: unknown key 'source.L_0' (did you mean 'source.L_o'?) (see "
                 "docs/formats.md for the rig's keys)");
  const std::string msg2 = rig_error("seed: 5\n", sets({"sauce.L_o=20"}));
  EXPECT_STARTS(msg2, "--set sauce.L_o=20: unknown key 'sauce.L_o'");
  // A section is not a settable key.
  const std::string msg3 = rig_error("seed: 5\n", sets({"device=1"}));
  EXPECT_STARTS(msg3, "--set device=1: unknown key 'device'");
}

TEST(RigYamlError, DuplicateKey) {
  expect_file_error("seed: 5\nsource:\n  L_o: 20\n  L_o: 30\n", 4, "source.L_o", "duplicate key");
  expect_file_error("seed: 5\nseed: 6\n", 2, "seed", "duplicate key");
  expect_file_error("source:\n  L_o: 20\nsource:\n  E_0: 1\n", 3, "source", "duplicate key");
}

TEST(RigYamlError, NonScalarKeyIsARigError) {
  // A complex (sequence) key is valid YAML; it must be reported as a rig error, not escape as
  // a yaml-cpp conversion exception.
  const std::string msg = rig_error("seed: 1\n? [a, b]\n: 1\n");
  EXPECT_STARTS(msg, std::string(kOrigin) + ":2");
}

TEST(RigYamlError, TopLevelNotAMapping) {
  EXPECT_EQ(rig_error("- 1\n- 2\n"),
            std::string(kOrigin) + ": expected a mapping of rig sections (device, source, "
                                   "eccentricity, schedule, electronics, seed)");
  EXPECT_STARTS(rig_error("just text\n"), std::string(kOrigin) + ": expected a mapping");
}

// ---------------------------------------------------------------------------------------------
// Errors: wrong types
// ---------------------------------------------------------------------------------------------

TEST(RigYamlError, StringWhereNumberExpected) {
  expect_file_error("device:\n  d: high\n", 2, "device.d",
                    "expected a degree of polarization in (0, 1), got 'high'");
  expect_file_error("seed: 1\nelectronics:\n  vref_V: 0.6V\n", 3, "electronics.vref_V",
                    "expected a voltage in [0.01, 100] V, got '0.6V'");
  expect_file_error("device:\n  beta_deg: [0, -60, x, -180, -240, -300]\n", 2, "device.beta_deg",
                    "expected 6 angles in [-360, 360] deg, got 'x'");
}

TEST(RigYamlError, ListOrMappingWhereScalarExpected) {
  expect_file_error("source:\n  L_o: [20, 30]\n", 2, "source.L_o",
                    "expected a length in [0.1, 1000] mm, got a list");
  expect_file_error("device:\n  d: [0.5]\n", 2, "device.d",
                    "expected a degree of polarization in (0, 1), got a list");
  expect_file_error("electronics:\n  adc_bits: [16]\n", 2, "electronics.adc_bits",
                    "expected an integer in [2, 31], got a list");
  expect_file_error("source:\n  model: [cos4]\n", 2, "source.model",
                    "expected \"cos4\", \"traced\" or \"sky\", got a list");
  expect_file_error("seed:\n  value: 3\n", 1, "seed",
                    "expected an unsigned 64-bit integer, got a mapping");
  expect_file_error("device:\n  d:\n", 2, "device.d",
                    "expected a degree of polarization in (0, 1), got nothing");
}

TEST(RigYamlError, ScalarWhereSectionExpected) {
  expect_file_error("eccentricity: 0.05\n", 1, "eccentricity",
                    "expected a section (a mapping of keys)");
  expect_file_error("device:\n  truth: [1, 2]\n", 2, "device.truth",
                    "expected a section (a mapping of keys)");
}

TEST(RigYamlError, ListOfWrongLength) {
  expect_file_error("device:\n  truth:\n    kv: [1.0, 1.0]\n", 3, "device.truth.kv",
                    "expected a list of 3 gains in [0.5, 2]");
  expect_file_error("device:\n  truth:\n    kv: [1.0, 1.0]\n", 3, "device.truth.kv",
                    "got 2 values");
  expect_file_error("device:\n  film_axes_deg: [0, 90, 60, 150, 120, 210, 0]\n", 2,
                    "device.film_axes_deg", "expected a list of 6 angles in [-360, 360] deg, got 7 values");
  expect_file_error("device:\n  truth:\n    kv: 1\n", 3, "device.truth.kv",
                    "expected a list of 3 gains in [0.5, 2]");
  expect_file_error("device:\n  truth:\n    kv: 1\n", 3, "device.truth.kv", "got '1'");
}

TEST(RigYamlError, ListOfWrongLengthMessageHasNoEmptyUnit) {
  // Keys without a unit must not print an empty "()" in the message.
  const std::string msg = rig_error("device:\n  truth:\n    kv: [1.0, 1.0]\n");
  EXPECT_LACKS(msg, "()");
}

TEST(RigYamlError, NonIntegerSamplesPerStop) {
  expect_file_error("schedule:\n  samples_per_stop: 3.5\n", 2, "schedule.samples_per_stop",
                    "expected an integer in [1, 100000], got '3.5'");
  expect_file_error("schedule:\n  samples_per_stop: forty\n", 2, "schedule.samples_per_stop",
                    "expected an integer in [1, 100000], got 'forty'");
}

TEST(RigYamlError, BadSeed) {
  expect_file_error("seed: -1\n", 1, "seed", "expected an unsigned 64-bit integer, got '-1'");
  expect_file_error("seed: lucky\n", 1, "seed", "expected an unsigned 64-bit integer, got 'lucky'");
  expect_file_error("seed: 1.5\n", 1, "seed", "expected an unsigned 64-bit integer, got '1.5'");
  expect_file_error("seed: 18446744073709551616\n", 1, "seed",
                    "expected an unsigned 64-bit integer, got '18446744073709551616'");
}

TEST(RigYamlError, SourceModelOtherThanCos4OrTraced) {
  // A traced source needs its scene; a scene needs the traced model.
  expect_file_error("source:\n  model: traced\n", 2, "source.model",
                    "expected source.scene with source.model traced");
  expect_file_error("source:\n  scene: scenes/jf500.yaml\n", 2, "source.scene",
                    "expected no value with source.model cos4 (only source.model traced reads it)");
  expect_file_error("source:\n  model: traced\n  scene: no/such/scene.yaml\n", 3, "source.scene",
                    "cannot load the scene: ");
  expect_file_error("source:\n  model: COS4\n", 2, "source.model",
                    "expected \"cos4\", \"traced\" or \"sky\", got 'COS4'");
}

// ---------------------------------------------------------------------------------------------
// Errors: unphysical values
// ---------------------------------------------------------------------------------------------

TEST(RigYamlError, NegativeLength) {
  expect_file_error("eccentricity:\n  L_IS: -1\n", 2, "eccentricity.L_IS",
                    "expected a length in [0, 100] mm, got -1");
  expect_file_error("seed: 1\neccentricity:\n  L_IS: 0.05\n  L_S: -0.5\n", 4, "eccentricity.L_S",
                    "expected a length in [0, 100] mm, got -0.5");
  expect_file_error("device:\n  L_photo: 0\n", 2, "device.L_photo", "expected a length in [0.1, 500] mm, got 0");
}

TEST(RigYamlError, ZeroSourceDistance) {
  expect_file_error("source:\n  L_o: 0\n", 2, "source.L_o",
                    "expected a length in [0.1, 1000] mm, got 0");
  expect_file_error("source:\n  E_0: -3\n", 2, "source.E_0", "expected an irradiance in [0.001, 100000] W/m^2, got -3");
}

TEST(RigYamlError, DegreeOfPolarizationOutsideOpenUnitInterval) {
  for (const char* v : {"0", "1", "1.5", "-0.1", "1.0"}) {
    SCOPED_TRACE(v);
    expect_file_error(std::string("seed: 1\ndevice:\n  d: ") + v + "\n", 3, "device.d",
                      std::string("expected a degree of polarization in (0, 1), got ") + v);
  }
}

TEST(RigYamlError, PolarizerCoefficientOutOfRange) {
  expect_file_error("device:\n  truth:\n    kd: [0, 0, 0.01, 0, 0, 0]\n", 3, "device.truth.kd",
                    "expected 6 values in (-1, 0], got 0.01");
  expect_file_error("device:\n  truth:\n    kd: [0, 0, 0, 0, 0, -1]\n", 3, "device.truth.kd",
                    "expected 6 values in (-1, 0], got -1");
}

TEST(RigYamlError, NonPositiveGain) {
  expect_file_error("device:\n  truth:\n    kv: [1, 0, 1]\n", 3, "device.truth.kv",
                    "expected 3 gains in [0.5, 2], got 0");
  expect_file_error("device:\n  truth:\n    kv: [1, 1, -1.02]\n", 3, "device.truth.kv",
                    "expected 3 gains in [0.5, 2], got -1.02");
}

TEST(RigYamlError, NonPositiveStep) {
  // Step 0 is a static time series, given with schedule.count only.
  expect_file_error("schedule:\n  step_deg: 0\n", 2, "schedule.step_deg",
                    "expected a step > 0 without schedule.count, got 0");
  expect_file_error("schedule:\n  step_deg: -10\n", 2, "schedule.step_deg",
                    "expected a step in [0, 360] deg, got -10");
}

TEST(RigYamlError, ElectronicsOutOfRange) {
  expect_file_error("electronics:\n  noise_sigma_V: -1e-4\n", 2, "electronics.noise_sigma_V",
                    "expected a standard deviation in [0, 1] V, got -1e-4");
  expect_file_error("electronics:\n  vref_V: 0\n", 2, "electronics.vref_V",
                    "expected a voltage in [0.01, 100] V, got 0");
  expect_file_error("electronics:\n  vref_V: -0.6\n", 2, "electronics.vref_V",
                    "expected a voltage in [0.01, 100] V, got -0.6");
  expect_file_error("electronics:\n  volts_per_decade: 0\n", 2, "electronics.volts_per_decade",
                    "expected a gain in [0.01, 10] V, got 0");
  for (const char* bits : {"1", "32", "0", "-16", "64"}) {
    SCOPED_TRACE(bits);
    expect_file_error(std::string("electronics:\n  adc_bits: ") + bits + "\n", 2,
                      "electronics.adc_bits",
                      std::string("expected an integer in [2, 31], got ") + bits);
  }
  expect_file_error("schedule:\n  samples_per_stop: 0\n", 2, "schedule.samples_per_stop",
                    "expected an integer in [1, 100000], got 0");
  expect_file_error("schedule:\n  samples_per_stop: 100001\n", 2, "schedule.samples_per_stop",
                    "expected an integer in [1, 100000], got 100001");
}

TEST(RigYamlError, NanAndInfinityAreRejected) {
  for (const char* v : {".nan", ".NaN", "nan", ".inf", "-.inf", "inf", "1e999"}) {
    SCOPED_TRACE(v);
    expect_file_error(std::string("source:\n  L_o: ") + v + "\n", 2, "source.L_o",
                      std::string("expected a length in [0.1, 1000] mm, got '") +
                          v + "'");
    // Keys that accept any angle still require a finite one.
    expect_file_error(std::string("eccentricity:\n  alpha_IS: ") + v + "\n", 2,
                      "eccentricity.alpha_IS", std::string("expected an angle in [-360, 360] deg, got '") + v +
                                                   "'");
  }
  expect_file_error("device:\n  beta_deg: [0, .nan, -120, -180, -240, -300]\n", 2,
                    "device.beta_deg", "expected 6 angles in [-360, 360] deg, got '.nan'");
  expect_file_error("schedule:\n  angles_deg: [0, .inf]\n", 2, "schedule.angles_deg",
                    "expected a list of 1 to 1e6 angles in [-3600, 3600] deg, got '.inf'");
}

// ---------------------------------------------------------------------------------------------
// Errors: rules across keys
// ---------------------------------------------------------------------------------------------

TEST(RigYamlError, StopBeforeStart) {
  expect_file_error("schedule:\n  start_deg: 10\n  step_deg: 5\n  stop_deg: 5\n", 4,
                    "schedule.stop_deg",
                    "expected an angle ≥ schedule.start_deg (10), got 5");
  // Only the start is in the file: the offending stop is the default; the message says so.
  const std::string msg = rig_error("schedule:\n  start_deg: 400\n");
  EXPECT_EQ(msg, std::string(kOrigin) +
                     " (default value): key 'schedule.stop_deg': expected an angle ≥ "
                     "schedule.start_deg (400), got 360 ('schedule.start_deg' from " +
                     std::string(kOrigin) + ":2)");
}

TEST(RigYamlError, TooManyStops) {
  expect_file_error("schedule:\n  step_deg: 1e-5\n", 2, "schedule.step_deg",
                    "expected at most 1e6 stops");
}

TEST(RigYamlError, PositiveBracketRuleIsUnreachableFromAFileButChecked) {
  // (1+kd)·d < 1 can only fail for kd > 0 or d ≥ 1, which the per-key checks reject first.
  EXPECT_EQ(parse_ok("device:\n  d: 0.999999\n  truth:\n    kd: [0, 0, 0, 0, 0, 0]\n").device.d,
            0.999999);
  // check_rig itself still guards a rig built in code.
  Rig r;
  r.device.truth.kd = {0, 0, 0, 0, 0, 0};
  r.device.d = 1.0;
  auto problem = polrig::check_rig(r);
  ASSERT_TRUE(problem.has_value());
  EXPECT_EQ(problem->path, "device.d");
  EXPECT_EQ(problem->message, "expected (1+kd_1)·d < 1, got 1");
  r.device.d = 0.9;
  r.device.truth.kd[3] = 0.2;
  problem = polrig::check_rig(r);
  ASSERT_TRUE(problem.has_value());
  EXPECT_EQ(problem->path, "device.d");
  EXPECT_HAS(problem->message, "expected (1+kd_4)·d < 1, got 1.08");
  EXPECT_FALSE(polrig::check_rig(Rig{}).has_value());
  // The stop < start rule of check_rig.
  Rig s;
  s.schedule.start_deg = 20;
  s.schedule.stop_deg = 10;
  problem = polrig::check_rig(s);
  ASSERT_TRUE(problem.has_value());
  EXPECT_EQ(problem->path, "schedule.stop_deg");
  EXPECT_EQ(problem->message, "expected an angle ≥ schedule.start_deg (20), got 10");
  // An explicit list makes start/stop irrelevant.
  s.schedule.angles_deg = {5};
  EXPECT_FALSE(polrig::check_rig(s).has_value());
}

TEST(RigYamlError, AnglesListTogetherWithStartStepStop) {
  for (const char* other : {"start_deg: 0", "step_deg: 10", "stop_deg: 360"}) {
    SCOPED_TRACE(other);
    const std::string key = std::string(other).substr(0, std::string(other).find(':'));
    expect_file_error(std::string("schedule:\n  ") + other + "\n  angles_deg: [0, 90, 180]\n", 3,
                      "schedule.angles_deg",
                      "expected either an explicit list or start/step/stop, not both "
                      "('schedule." + key + "' is also given)");
  }
  // The default rig file gives start/step/stop; a list given with --set replaces them.
  const Rig r = parse_ok(read_file(kDefaultRigFile), sets({"schedule.angles_deg=[0, 90]"}));
  EXPECT_EQ(r.schedule.table_angles_deg(), (std::vector<double>{0, 90}));
  // A --set of start/step/stop cannot be silently ignored under a file's explicit list.
  const std::string ignored =
      rig_error("schedule:\n  angles_deg: [0, 180]\n", sets({"schedule.step_deg=5"}));
  EXPECT_HAS(ignored, "expected either an explicit list or start/step/stop, not both");
  // Both forms among the overrides are still an error, naming the --set.
  const std::string msg = rig_error(
      read_file(kDefaultRigFile), sets({"schedule.angles_deg=[0, 90]", "schedule.step_deg=5"}));
  EXPECT_STARTS(msg, "--set schedule.angles_deg=[0, 90]: key 'schedule.angles_deg': ");
  EXPECT_HAS(msg, "expected either an explicit list or start/step/stop, not both");
}

TEST(RigYamlError, EmptyAnglesList) {
  expect_file_error("schedule:\n  angles_deg: []\n", 2, "schedule.angles_deg",
                    "expected a list of 1 to 1e6 angles in [-3600, 3600] deg, got an empty list");
  expect_file_error("schedule:\n  angles_deg: 90\n", 2, "schedule.angles_deg",
                    "expected a list of 1 to 1e6 angles in [-3600, 3600] deg, got '90'");
}

// Issue 8: 1.2 million explicit stops were accepted although start/step/stop stop at 1e6. The
// list is refused with its key and count; a rig built in code is refused by check_rig.
TEST(RigYamlError, MoreThanAMillionExplicitStops) {
  std::string text = "schedule:\n  angles_deg: [0";
  for (int i = 1; i < 1000001; ++i) text += ",0";
  text += "]\n";
  expect_file_error(text, 2, "schedule.angles_deg",
                    "expected a list of 1 to 1e6 angles in [-3600, 3600] deg, got 1000001 entries");
  Rig r;
  r.schedule.angles_deg.assign(1000001, 0.0);
  const auto problem = polrig::check_rig(r);
  ASSERT_TRUE(problem.has_value());
  EXPECT_EQ(problem->path, "schedule.angles_deg");
  EXPECT_EQ(problem->message, "expected at most 1e6 stops, got 1000001");
  r.schedule.angles_deg.resize(1000000);
  EXPECT_FALSE(polrig::check_rig(r).has_value());
}

// Issue 8: nesting deeper than yaml-cpp's guard was reported as "YAML syntax error: bad file".
TEST(RigYamlError, DeepNestingIsNamedWithFileAndLine) {
  const std::string flow = "seed: " + std::string(3000, '[') + std::string(3000, ']') + "\n";
  EXPECT_EQ(rig_error(flow), std::string(kOrigin) + ":1: the YAML nests deeper than the reader's "
                                                    "limit of 500 levels (a rig file nests 4 levels)");
  std::string block = "device:\n";
  for (int i = 1; i < 2000; ++i) block += std::string(2 * static_cast<std::size_t>(i), ' ') + "k:\n";
  const std::string msg = rig_error(block);
  EXPECT_STARTS(msg, std::string(kOrigin) + ":");
  EXPECT_HAS(msg, "the YAML nests deeper than the reader's limit");
  EXPECT_LACKS(msg, "bad file");
  const std::string deep_set = "seed=" + std::string(3000, '[');
  EXPECT_EQ(rig_error("seed: 1\n", sets({deep_set.c_str()})),
            "--set seed=" + std::string(3000, '[') + ": key 'seed': the value is not valid YAML: the "
            "YAML nests deeper than the reader's limit of 500 levels (a rig value nests at most 1 level)");
}

// ---------------------------------------------------------------------------------------------
// Errors: files
// ---------------------------------------------------------------------------------------------

TEST(RigYamlFile, MissingFileNamesThePath) {
  TempDir tmp("polrig_test_rig_yaml_");
  const fs::path missing = tmp.path() / "no-such-rig.yaml";
  try {
    polrig::load_rig(missing);
    FAIL() << "load_rig accepted a missing file";
  } catch (const RigError& e) {
    EXPECT_EQ(std::string(e.what()), missing.string() + ": cannot read the rig file: no such file");
  }
}

TEST(RigYamlFile, DirectoryIsNotARigFile) {
  TempDir tmp("polrig_test_rig_yaml_");
  try {
    polrig::load_rig(tmp.path());
    FAIL() << "load_rig accepted a directory";
  } catch (const RigError& e) {
    EXPECT_EQ(std::string(e.what()),
              tmp.path().string() + ": cannot read the rig file: it is a directory (expected a file)");
  }
}

TEST(RigYamlFile, ErrorsInAFileNameThePathAndLine) {
  TempDir tmp("polrig_test_rig_yaml_");
  const fs::path file = tmp.path() / "bad.yaml";
  write_file(file, "# a comment\nseed: 1\n\nsource:\n  L_o: -2\n");
  try {
    polrig::load_rig(file);
    FAIL() << "load_rig accepted L_o = -2";
  } catch (const RigError& e) {
    EXPECT_EQ(std::string(e.what()),
              file.string() + ":5: key 'source.L_o': expected a length in [0.1, 1000] mm, "
                              "got -2");
  }
  // load_rig applies overrides, and the error then names the --set.
  write_file(file, "seed: 1\n");
  EXPECT_EQ(polrig::load_rig(file, sets({"seed=3"})).rig.seed, 3u);
  try {
    polrig::load_rig(file, sets({"seed=x"}));
    FAIL() << "load_rig accepted seed=x";
  } catch (const RigError& e) {
    EXPECT_EQ(std::string(e.what()),
              "--set seed=x: key 'seed': expected an unsigned 64-bit integer, got 'x'");
  }
}

// ---------------------------------------------------------------------------------------------
// Errors: overrides
// ---------------------------------------------------------------------------------------------

TEST(RigYamlOverrideError, WrongTypeNamesTheSetNotTheFileLine) {
  const std::string msg = rig_error("seed: 1\ndevice:\n  d: 0.5\n", sets({"device.d=abc"}));
  EXPECT_EQ(msg, "--set device.d=abc: key 'device.d': expected a degree of polarization in "
                 "(0, 1), got 'abc'");
  EXPECT_LACKS(msg, kOrigin);

  const std::string msg2 = rig_error("seed: 1\n", sets({"device.truth.kv=[1, 1]"}));
  EXPECT_STARTS(msg2, "--set device.truth.kv=[1, 1]: key 'device.truth.kv': expected a list of "
                      "3 gains in [0.5, 2]");
  EXPECT_HAS(msg2, "got 2 values");

  const std::string msg3 = rig_error("seed: 1\n", sets({"schedule.samples_per_stop=3.5"}));
  EXPECT_EQ(msg3, "--set schedule.samples_per_stop=3.5: key 'schedule.samples_per_stop': "
                  "expected an integer in [1, 100000], got '3.5'");

  const std::string msg4 = rig_error("seed: 1\n", sets({"source.L_o=-1"}));
  EXPECT_EQ(msg4, "--set source.L_o=-1: key 'source.L_o': expected a length in [0.1, 1000] mm, "
            "got -1");

  const std::string msg5 = rig_error("seed: 1\n", sets({"source.model=fisheye"}));
  EXPECT_EQ(msg5, "--set source.model=fisheye: key 'source.model': expected \"cos4\", "
                  "\"traced\" or \"sky\", got 'fisheye'");
}

TEST(RigYamlOverrideError, ValueThatIsNotYaml) {
  const std::string msg = rig_error("seed: 1\n", sets({"device.truth.kv=[1, 1"}));
  EXPECT_STARTS(msg, "--set device.truth.kv=[1, 1: key 'device.truth.kv': the value is not valid "
                     "YAML: ");
}

TEST(RigYamlOverrideError, SetIntoAKeyTheFileGivesAScalar) {
  const std::string msg = rig_error("device: 0.5\n", sets({"device.d=0.5"}));
  EXPECT_EQ(msg, "--set device.d=0.5: key 'device': the file gives it a value, expected a "
                 "section");
  const std::string msg2 =
      rig_error("device:\n  truth: [1, 2]\n", sets({"device.truth.kv=[1, 1, 1]"}));
  EXPECT_EQ(msg2, "--set device.truth.kv=[1, 1, 1]: key 'device.truth': the file gives it a "
                  "value, expected a section");
}

TEST(RigYamlOverrideError, FileErrorsElsewhereStillNameTheFileLine) {
  // An override of one key does not hide the line of an error in another key.
  const std::string msg =
      rig_error("seed: 1\ndevice:\n  d: 5\n", sets({"device.truth.kv=[1, 1, 1]"}));
  EXPECT_EQ(msg, std::string(kOrigin) +
                     ":3: key 'device.d': expected a degree of polarization in (0, 1), got 5");
}

// ---------------------------------------------------------------------------------------------
// rig_to_yaml
// ---------------------------------------------------------------------------------------------

namespace {
YAML::Node find_path(const YAML::Node& root, std::string_view path) {
  YAML::Node node = YAML::Clone(root);
  std::stringstream ss{std::string(path)};
  for (std::string part; std::getline(ss, part, '.');) {
    if (!node.IsMap() || !node[part]) return YAML::Node(YAML::NodeType::Undefined);
    YAML::Node child = node[part];
    node.reset(child);
  }
  return node;
}
}  // namespace

TEST(RigToYaml, RoundTripOfTheDefaultRig) {
  const Rig defaults;
  const std::string text = polrig::rig_to_yaml(defaults);
  const Rig back = parse_ok(text);
  expect_same_rig(back, defaults);
  EXPECT_EQ(polrig::rig_to_yaml(back), text);
  // The resolved dump of the shipped rig file is the same text.
  EXPECT_EQ(polrig::rig_to_yaml(polrig::load_rig(kDefaultRigFile).rig), text);
}

TEST(RigToYaml, RoundTripWithExplicitAngles) {
  Rig r;
  r.schedule.angles_deg = {0, 12.5, 90, 359.999, -45};
  const std::string text = polrig::rig_to_yaml(r);
  EXPECT_LACKS(text, "start_deg");
  EXPECT_LACKS(text, "step_deg");
  EXPECT_LACKS(text, "stop_deg");
  EXPECT_HAS(text, "angles_deg");
  const Rig back = parse_ok(text);
  EXPECT_EQ(back.schedule.angles_deg, r.schedule.angles_deg);
  expect_same_rig(back, r);
  EXPECT_EQ(polrig::rig_to_yaml(back), text);
}

TEST(RigToYaml, RoundTripIsExactForAwkwardNumbers) {
  Rig r;
  r.device.d = 0.1 + 0.2;  // 0.30000000000000004
  r.electronics.noise_sigma_V = 1.234567890123e-9;
  r.eccentricity.alpha_S = 1.0 / 3.0;
  r.eccentricity.L_IS = 1e-300;
  r.source.cos4.E_0 = 1e5 / 3.0;
  r.source.polarizer_deg = -0.0;
  r.device.truth.k_mV = {-1.0 / 7.0, 2.0 / 3.0, 999.999999999};
  r.seed = std::numeric_limits<std::uint64_t>::max();
  r.electronics.adc_bits = 31;
  const std::string text = polrig::rig_to_yaml(r);
  const Rig back = parse_ok(text);
  expect_same_rig(back, r);
  EXPECT_EQ(polrig::rig_to_yaml(back), text);
}

TEST(RigToYaml, EveryKeyIsWritten) {
  const std::string text = polrig::rig_to_yaml(Rig{});
  const YAML::Node root = YAML::Load(text);
  for (const polrig::RigKey& k : polrig::rig_keys()) {
    SCOPED_TRACE(std::string(k.path));
    const YAML::Node n = find_path(root, k.path);
    if (k.path == "schedule.angles_deg" || k.path == "device.truth_from" || k.path == "source.scene" ||
        k.path == "schedule.count") {  // schedule.count 0: unset
      EXPECT_FALSE(n.IsDefined()) << "an empty list or path is omitted";
      continue;
    }
    if (k.path == "device.kind") {  // the default instrument: left out, so old rig.yaml files stay as they were
      EXPECT_FALSE(n.IsDefined());
      continue;
    }
    if (!k.read_by_instrument("six-photodiode")) {  // the camera's keys
      EXPECT_FALSE(n.IsDefined()) << "a key its instrument does not read is omitted";
      continue;
    }
    if (!k.read_by_source("cos4")) {  // the sky's keys: the default rig's source does not read them
      EXPECT_FALSE(n.IsDefined()) << "a key its source does not read is omitted";
      continue;
    }
    EXPECT_TRUE(n.IsDefined()) << "missing from rig_to_yaml:\n" << text;
    if (k.kind == polrig::RigKey::Kind::RealArray) EXPECT_TRUE(n.IsSequence());
    else EXPECT_TRUE(n.IsScalar());
  }
  // With an explicit list, the list is written and start/step/stop are not.
  Rig r;
  r.schedule.angles_deg = {1, 2};
  const YAML::Node root2 = YAML::Load(polrig::rig_to_yaml(r));
  EXPECT_TRUE(find_path(root2, "schedule.angles_deg").IsSequence());
  EXPECT_FALSE(find_path(root2, "schedule.start_deg").IsDefined());
  EXPECT_TRUE(find_path(root2, "schedule.samples_per_stop").IsDefined());
}

TEST(RigToYaml, OnlyKnownKeysAreWritten) {
  // Every leaf of the dump is a key of the table (so the dump always loads back).
  const YAML::Node root = YAML::Load(polrig::rig_to_yaml(Rig{}));
  std::vector<std::string> leaves;
  std::function<void(const YAML::Node&, const std::string&)> walk = [&](const YAML::Node& n,
                                                                       const std::string& pre) {
    for (auto it = n.begin(); it != n.end(); ++it) {
      const std::string path = (pre.empty() ? "" : pre + ".") + it->first.as<std::string>();
      if (it->second.IsMap()) walk(it->second, path);
      else leaves.push_back(path);
    }
  };
  walk(root, "");
  for (const std::string& p : leaves) EXPECT_NE(polrig::find_rig_key(p), nullptr) << p;
  std::size_t cos4_keys = 0;
  for (const polrig::RigKey& k : polrig::rig_keys())
    cos4_keys += k.read_by_source("cos4") && k.read_by_instrument("six-photodiode") ? 1 : 0;
  // All the default (cos4, six-photodiode) rig's keys but the empty list and paths (source.scene is
  // traced's), schedule.count (0: unset) and device.kind (the default instrument is not written).
  EXPECT_EQ(leaves.size(), cos4_keys - 4);
}
