// The instrument seam (instrument/instrument.h): the factory and its flags, the device.kind key
// and the keys each instrument reads, the rig files of both instruments, the capability errors
// of the library and the CLI, and byte-identical outputs for the six-photodiode rigs whether or not
// they name their instrument.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "polrig/calib/rig_options.h"
#include "polrig/instrument/instrument.h"
#include "polrig/io/measured.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/rig/keys.h"
#include "polrig/rig/rig.h"
#include "polrig/sim/simulate.h"
#include "polrig/study/calibration_trials.h"
#include "polrig/study/cs.h"
#include "polrig/study/heading_trials.h"
#include "polrig/study/sweep.h"
#include "support.h"

namespace fs = std::filesystem;
using namespace polrig;
using polrig::test::kDefaultRigFile;
using polrig::test::read_file;
using polrig::test::shell_quote;
using polrig::test::write_file;

namespace {

const std::string kIndoor = POLRIG_SOURCE_DIR "/rigs/han2017-indoor.yaml";
const std::string kOutdoor = POLRIG_SOURCE_DIR "/rigs/han2017-outdoor.yaml";

template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const RigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected a RigError";
  return {};
}

Rig camera_rig() { return load_rig(kIndoor).rig; }

// ---- the factory ------------------------------------------------------------------------

TEST(InstrumentFactory, KindsAndFlags) {
  const auto kinds = instrument_kinds();
  ASSERT_EQ(kinds.size(), 4u);
  EXPECT_EQ(kinds[0], "six-photodiode");
  EXPECT_EQ(kinds[1], "dofp-camera");
  EXPECT_EQ(kinds[2], "four-camera");
  EXPECT_EQ(kinds[3], "unit-array");
  for (std::string_view kind : kinds) EXPECT_EQ(make_instrument(kind)->kind(), kind);

  const auto six = make_instrument("six-photodiode");
  EXPECT_TRUE(six->has(Instrument::kPairVoltages));
  EXPECT_FALSE(six->has(Instrument::kFrames));
  EXPECT_EQ(six, six_photodiode_instrument());
  const auto camera = make_instrument("dofp-camera");
  EXPECT_TRUE(camera->has(Instrument::kFrames));
  EXPECT_FALSE(camera->has(Instrument::kPairVoltages));

  EXPECT_THROW(make_instrument("camera"), std::invalid_argument);
  EXPECT_THROW(make_instrument(""), std::invalid_argument);
  EXPECT_EQ(kinds_with(Instrument::kPairVoltages), "six-photodiode");
  EXPECT_EQ(kinds_with(Instrument::kFrames), "dofp-camera four-camera");
  EXPECT_EQ(kinds_with(Instrument::kMosaic), "dofp-camera");
  EXPECT_EQ(kinds_with(Instrument::kCameraArray), "four-camera");
  EXPECT_EQ(kinds_with(Instrument::kUnitArray), "unit-array");
  // W16's four cameras take frames but have no mosaic: the DoFP-only commands refuse them.
  const auto four = make_instrument("four-camera");
  EXPECT_TRUE(four->has(Instrument::kFrames));
  EXPECT_TRUE(four->has(Instrument::kCameraArray));
  EXPECT_FALSE(four->has(Instrument::kMosaic));
  EXPECT_FALSE(four->has(Instrument::kPairVoltages));
}

TEST(InstrumentFactory, EveryFlagHasOneNameAndText) {
  std::set<std::string_view> names;
  unsigned all = 0;
  for (const InstrumentFlagInfo& f : instrument_flags()) {
    EXPECT_TRUE(names.insert(f.name).second) << f.name;
    EXPECT_FALSE(f.text.empty());
    all |= f.flag;
  }
  // Every flag some instrument has is named (Python's Rig.can knows it).
  for (std::string_view kind : instrument_kinds())
    EXPECT_EQ(make_instrument(kind)->flags() & ~all, 0u) << kind;
}

TEST(InstrumentFactory, ADefaultRigIsTheSixPhotodiodeSensor) {
  const Rig rig;
  EXPECT_EQ(rig.device_kind, kDefaultDeviceKind);
  EXPECT_EQ(rig.instrument().kind(), rig.device_kind);
}

TEST(InstrumentFactory, ARigBuiltInCodeHasItsKindsInstrument) {
  // One source of truth: setting device_kind alone changes what the rig can do (no second field
  // to forget), and an unknown kind is an error when the instrument is asked for.
  Rig rig;
  for (std::string_view kind : instrument_kinds()) {
    rig.device_kind = std::string(kind);
    EXPECT_EQ(rig.instrument().kind(), kind);
    EXPECT_EQ(rig.instrument().flags(), make_instrument(kind)->flags());
  }
  rig.device_kind = "dofp-camera";
  EXPECT_TRUE(rig.instrument().has(Instrument::kFrames));
  EXPECT_FALSE(rig.instrument().has(Instrument::kPairVoltages));
  EXPECT_EQ(instrument_problem(rig, Instrument::kFrames, "orient"), std::nullopt);
  EXPECT_NE(instrument_problem(rig, Instrument::kPairVoltages, "study cs"), std::nullopt);
  rig.device_kind = "six-photodiode";
  EXPECT_EQ(instrument_problem(rig, Instrument::kPairVoltages, "study cs"), std::nullopt);
  rig.device_kind = "spectrometer";
  EXPECT_THROW((void)rig.instrument(), std::invalid_argument);
}

// ---- the keys ---------------------------------------------------------------------------

TEST(InstrumentKeys, EveryKeyNamesKnownInstruments) {
  const auto kinds = instrument_kinds();
  for (const RigKey& k : rig_keys()) {
    bool any = false;
    for (std::string_view kind : kinds) any = any || k.read_by_instrument(kind);
    EXPECT_TRUE(any) << k.path << " is read by no instrument: '" << k.instruments << "'";
    // Every name in the list is a kind.
    std::string_view list = k.instruments;
    while (!list.empty()) {
      const std::size_t e = std::min(list.find(' '), list.size());
      EXPECT_NE(std::find(kinds.begin(), kinds.end(), list.substr(0, e)), kinds.end()) << k.path;
      list.remove_prefix(std::min(e + 1, list.size()));
    }
  }
}

TEST(InstrumentKeys, DeviceKeysBelongToOneInstrumentButKindAndD) {
  for (const RigKey& k : rig_keys()) {
    if (!k.path.starts_with("device.")) continue;
    SCOPED_TRACE(std::string(k.path));
    const bool six = k.read_by_instrument("six-photodiode"), cam = k.read_by_instrument("dofp-camera"),
               four = k.read_by_instrument("four-camera"), units = k.read_by_instrument("unit-array");
    if (k.path == "device.kind" || k.path == "device.d") {
      EXPECT_TRUE(six && cam && four && units);
    } else if (k.path.starts_with("device.truth.") || k.path == "device.film_axes_deg") {
      // The six-photodiode sensor's parameters: also every unit's of a unit array.
      EXPECT_EQ(k.instruments, "six-photodiode unit-array");
    } else {
      EXPECT_EQ(int(six) + int(cam) + int(four) + int(units), 1);
      // The unit array's keys are under device.units.
      if (units) {
        EXPECT_TRUE(k.path.starts_with("device.units."));
      }
      // The four cameras' keys are under device.cameras (device.width_px is the DoFP camera's).
      if (four) {
        EXPECT_TRUE(k.path.starts_with("device.cameras."));
      }
    }
  }
  for (const char* p : {"schedule.unpolarized_levels", "schedule.intensities"})
    EXPECT_EQ(find_rig_key(p)->instruments, "dofp-camera four-camera") << p;
  EXPECT_EQ(find_rig_key("schedule.frames_per_stop")->instruments, "dofp-camera");
  EXPECT_EQ(find_rig_key("schedule.samples_per_stop")->instruments, "six-photodiode unit-array");
  EXPECT_EQ(find_rig_key("electronics.adc_bits")->instruments, "six-photodiode unit-array");
}

// Every field of DofpCameraSpec has its key: the key's accessor reaches that very field.
TEST(InstrumentKeys, EveryCameraSettingHasAKey) {
  Rig r;
  DofpCameraSpec& c = r.camera;
  const auto addr_of = [&](const char* path) -> const void* {
    const RigKey* k = find_rig_key(path);
    if (!k) return nullptr;
    switch (k->kind) {
      case RigKey::Kind::Real: return &k->real(r);
      case RigKey::Kind::Integer: return &k->integer(r);
      case RigKey::Kind::Bool: return &k->boolean(r);
      case RigKey::Kind::RealArray: return k->array(r).data();
      default: return nullptr;
    }
  };
  EXPECT_EQ(addr_of("device.width_px"), &c.width_px);
  EXPECT_EQ(addr_of("device.height_px"), &c.height_px);
  EXPECT_EQ(addr_of("device.pixel_um"), &c.pixel_um);
  EXPECT_EQ(addr_of("device.focal_mm"), &c.focal_mm);
  EXPECT_EQ(addr_of("device.vignetting"), &c.vignetting);
  EXPECT_EQ(addr_of("device.mosaic_deg"), c.mosaic_deg.data());
  EXPECT_EQ(addr_of("device.gain_DN"), &c.gain_DN);
  EXPECT_EQ(addr_of("device.gain_spread"), &c.gain_spread);
  EXPECT_EQ(addr_of("device.mosaic_gain"), c.mosaic_gain.data());
  EXPECT_EQ(addr_of("device.offset_DN"), &c.offset_DN);
  EXPECT_EQ(addr_of("device.offset_spread_DN"), &c.offset_spread_DN);
  EXPECT_EQ(addr_of("device.k"), c.k.data());
  EXPECT_EQ(addr_of("device.eps_deg"), c.eps_deg.data());
  EXPECT_EQ(addr_of("device.k_spread"), &c.k_spread);
  EXPECT_EQ(addr_of("device.eps_spread_deg"), &c.eps_spread_deg);
  EXPECT_EQ(addr_of("device.misregistration_dx_px"), &c.misregistration_dx_px);
  EXPECT_EQ(addr_of("device.misregistration_dy_px"), &c.misregistration_dy_px);
  EXPECT_EQ(addr_of("device.misregistration_rotation_deg"), &c.misregistration_rotation_deg);
  EXPECT_EQ(addr_of("device.extinction_ratio"), &c.extinction_ratio);
  EXPECT_EQ(addr_of("device.noise"), &c.noise);
  EXPECT_EQ(addr_of("device.electrons_per_DN"), &c.electrons_per_DN);
  EXPECT_EQ(addr_of("device.read_noise_DN"), &c.read_noise_DN);
  EXPECT_EQ(addr_of("device.adc_bits"), &c.adc_bits);
  // Every camera key has a reason for its range (or is a bool).
  for (const RigKey& k : rig_keys())
    if (k.instruments == "dofp-camera" && k.kind != RigKey::Kind::Bool) {
      EXPECT_FALSE(k.why.empty()) << k.path;
    }
}

TEST(InstrumentKeys, CameraKeysCheckTheirValues) {
  const std::string head = "device: {kind: dofp-camera}\n";
  const auto bad = [&](const std::string& key, const std::string& value) {
    return error_of([&] { parse_rig(head, "cam.yaml", {{key, value}}); });
  };
  EXPECT_HAS(bad("device.width_px", "641"), "key 'device.width_px': expected an even integer in [2, 16384], got 641");
  EXPECT_HAS(bad("device.height_px", "0"), "expected an even integer in [2, 16384], got 0");
  EXPECT_HAS(bad("device.noise", "yes"), "key 'device.noise': expected true or false, got 'yes'");
  EXPECT_HAS(bad("device.vignetting", "1"), "expected true or false, got '1'");
  EXPECT_HAS(bad("device.k", "[1, 1, 1.5, 1]"), "key 'device.k': expected 4 efficiencies in [0, 1], got 1.5");
  EXPECT_HAS(bad("device.mosaic_gain", "[1, 1.06, 0, 1]"), "key 'device.mosaic_gain': expected 4 gain factors in [0.5, 2], got 0");
  EXPECT_HAS(bad("device.mosaic_gain", "[1, 1]"), "key 'device.mosaic_gain'");
  EXPECT_HAS(bad("device.adc_bits", "25"), "expected an integer in [1, 16], got 25");
  EXPECT_HAS(bad("schedule.intensities", "[1, 0]"), "key 'schedule.intensities'");
  EXPECT_HAS(bad("schedule.frames_per_stop", "0"), "expected an integer in [1, 999], got 0");
  const Rig r = parse_rig(head, "x", {{"device.noise", "false"}, {"device.vignetting", "true"},
                                                         {"device.width_px", "64"}}).rig;
  EXPECT_FALSE(r.camera.noise);
  EXPECT_TRUE(r.camera.vignetting);
  EXPECT_EQ(r.camera.width_px, 64);
}

// `polrig rig keys` is a Markdown table: no text of a key may hold its column separator.
TEST(InstrumentKeys, NoKeyTextBreaksTheKeyTable) {
  for (const RigKey& k : rig_keys())
    for (std::string_view t : {std::string_view(k.expects), k.doc, k.why, k.unit})
      EXPECT_EQ(t.find('|'), std::string_view::npos) << k.path << ": " << t;
}

// ---- loading ----------------------------------------------------------------------------

TEST(InstrumentRigFiles, Han2017IndoorLoads) {
  const Rig r = camera_rig();
  EXPECT_EQ(r.device_kind, "dofp-camera");
  EXPECT_TRUE(r.instrument().has(Instrument::kFrames));
  EXPECT_EQ(r.camera.width_px, 640);
  EXPECT_EQ(r.camera.height_px, 480);
  // f_c = focal/pitch = 405.4 px (spec §2.1).
  EXPECT_NEAR(r.camera.focal_mm / r.camera.pixel_um * 1000, 405.4, 0.05);
  EXPECT_EQ(r.schedule.table_angles_deg().size(), 79u);  // 0 → 359.08° in 4.6036° steps
  EXPECT_NEAR(r.schedule.table_angles_deg().back(), 359.08, 0.001);
  ASSERT_EQ(r.schedule.unpolarized_levels.size(), 30u);
  EXPECT_EQ(r.schedule.unpolarized_levels.front(), 0.0);
  EXPECT_EQ(r.schedule.unpolarized_levels.back(), 1.0);
  for (std::size_t i = 1; i < 30; ++i)  // 1720 cd/m² in 29 steps of about 60 cd/m²
    EXPECT_NEAR((r.schedule.unpolarized_levels[i] - r.schedule.unpolarized_levels[i - 1]) * 1720, 59.31, 0.01);
  EXPECT_EQ(r.schedule.intensities, (std::vector<double>{1, 0.5, 0.25, 0.1, 0.05, 0.025}));
  EXPECT_EQ(r.schedule.frames_per_stop, 5);
}

TEST(InstrumentRigFiles, Han2017OutdoorLoads) {
  const Rig r = load_rig(kOutdoor).rig;
  EXPECT_EQ(r.device_kind, "dofp-camera");
  EXPECT_TRUE(r.light->has(Source::kTimeDependent));
  EXPECT_EQ(r.schedule.table_angles_deg().size(), 40u);  // 0 → 359.08° in 9.2072° steps
  EXPECT_NEAR(r.schedule.table_angles_deg().back(), 359.08, 0.001);
  EXPECT_EQ(r.schedule.frames_per_stop, 1);
  EXPECT_EQ(r.source.sky.first_stop_utc.substr(0, 10), "2017-05-28");
  EXPECT_EQ(r.source.sky.sky.model.P_max.constant, 0.65);
}

TEST(InstrumentRigFiles, ASixPhotodiodeKeyInACameraRigIsRefused) {
  // The file's line, the key and both instruments are named, as for a key its source does not read.
  const std::string text = "device:\n  kind: dofp-camera\n  L_photo: 14\n";
  EXPECT_EQ(error_of([&] { parse_rig(text, "cam.yaml"); }),
            "cam.yaml:3: key 'device.L_photo': expected no value with device.kind dofp-camera (only "
            "device.kind six-photodiode reads it)");
  EXPECT_HAS(error_of([&] { load_rig(kIndoor, {{"device.truth.kv", "[1, 1, 1]"}}); }),
             "--set device.truth.kv=[1, 1, 1]: key 'device.truth.kv': expected no value with device.kind dofp-camera");
  EXPECT_HAS(error_of([&] { load_rig(kIndoor, {{"electronics.vref_V", "1"}}); }),
             "key 'electronics.vref_V': expected no value with device.kind dofp-camera");
  EXPECT_HAS(error_of([&] { load_rig(kOutdoor, {{"eccentricity.L_S", "0.1"}}); }),
             "key 'eccentricity.L_S': expected no value with device.kind dofp-camera");
  EXPECT_HAS(error_of([&] { load_rig(kIndoor, {{"source.L_o", "20"}}); }),
             "key 'source.L_o': expected no value with device.kind dofp-camera");
  EXPECT_NO_THROW(load_rig(kOutdoor, {{"sky.E_0", "2"}}));  // a pixel's intensity for the sky's radiance 1
  // And a camera key in a six-photodiode rig.
  EXPECT_EQ(error_of([&] { parse_rig("device:\n  d: 0.5\n  focal_mm: 3\n", "six.yaml"); }),
            "six.yaml:3: key 'device.focal_mm': expected no value with device.kind six-photodiode (only "
            "device.kind dofp-camera reads it)");
  EXPECT_HAS(error_of([&] { parse_rig("device: {kind: camera}\n", "x.yaml"); }),
             "x.yaml:1: key 'device.kind': expected \"six-photodiode\", \"dofp-camera\", \"four-camera\" or \"unit-array\", got 'camera'");
}

TEST(InstrumentRigFiles, TheEffectiveRigLoadsBackAndLeavesTheDefaultKindOut) {
  for (const std::string& file : {kIndoor, kOutdoor}) {
    const Rig r = load_rig(file).rig;
    const std::string text = rig_to_yaml(r);
    EXPECT_HAS(text, "device:\n  kind: dofp-camera\n");
    EXPECT_LACKS(text, "L_photo");
    EXPECT_LACKS(text, "electronics");
    EXPECT_LACKS(text, "samples_per_stop");
    const Rig back = parse_rig(text, "back").rig;
    EXPECT_EQ(back.device_kind, "dofp-camera");
    EXPECT_EQ(rig_to_yaml(back), text);
  }
  const std::string six = rig_to_yaml(Rig{});
  EXPECT_LACKS(six, "kind");
  EXPECT_LACKS(six, "width_px");
  EXPECT_LACKS(six, "intensities");
  // Naming the default instrument changes nothing in the effective rig.
  EXPECT_EQ(rig_to_yaml(parse_rig("device: {kind: six-photodiode}\n", "x").rig), six);
}

TEST(InstrumentRigFiles, ACopyKeepsItsInstrument) {
  const Rig r = camera_rig();
  const Rig copy = r;
  EXPECT_EQ(&copy.instrument(), &r.instrument());
  EXPECT_EQ(copy.device_kind, "dofp-camera");
  Rig assigned;
  assigned = r;
  EXPECT_TRUE(assigned.instrument().has(Instrument::kFrames));
}

// ---- capabilities ---------------------------------------------------------------------

TEST(InstrumentCapabilities, TheMessageNamesWhatIsNeededAndWhoHasIt) {
  const Rig cam = camera_rig();
  EXPECT_EQ(instrument_problem(cam, Instrument::kPairVoltages, "study cs", "rigs/x.yaml"),
            "rigs/x.yaml: study cs needs pair voltages (device.kind six-photodiode); device.kind "
            "dofp-camera has none");
  EXPECT_EQ(instrument_problem(cam, Instrument::kPairVoltages, "study cs"),
            "study cs needs pair voltages (device.kind six-photodiode); device.kind dofp-camera has none");
  EXPECT_FALSE(instrument_problem(cam, Instrument::kFrames, "orient").has_value());
  EXPECT_EQ(instrument_problem(Rig{}, Instrument::kMosaic, "orient", "r.yaml"),
            "r.yaml: orient needs a polarizer mosaic (device.kind dofp-camera); device.kind six-photodiode has none");
  Rig four;
  four.device_kind = "four-camera";
  EXPECT_EQ(instrument_problem(four, Instrument::kMosaic, "calibrate --method dofp", "r.yaml"),
            "r.yaml: calibrate --method dofp needs a polarizer mosaic (device.kind dofp-camera); device.kind "
            "four-camera has none");
  EXPECT_FALSE(instrument_problem(Rig{}, Instrument::kPairVoltages, "study cs").has_value());
  EXPECT_THROW(require_instrument(cam, Instrument::kPairVoltages, "x"), RigError);
  EXPECT_NO_THROW(require_instrument(cam, Instrument::kFrames, "x"));
}

// The library's studies ask themselves, so that every caller (the CLI, Python) is refused alike.
TEST(InstrumentCapabilities, TheLibraryRefusesACameraWherePairVoltagesAreNeeded) {
  const Rig cam = camera_rig();
  EXPECT_HAS(error_of([&] { simulate(cam); }), "simulate needs pair voltages");
  EXPECT_HAS(error_of([&] { light_at_pose(cam, 0); }), "needs pair voltages");
  EXPECT_HAS(error_of([&] { cs_study(cam, CsTurn(8)); }), "study cs needs pair voltages");
  EXPECT_HAS(error_of([&] { check_grid(cam, {GridAxis::parse("eccentricity.L_S=0:1:2")}); }),
             "sweep needs pair voltages");
  EXPECT_HAS(error_of([&] { calibration_options(cam, 0.5, NoncontinuousRule{}); }),
             "an Eq. 15 calibration needs pair voltages");
  EXPECT_HAS(error_of([&] { trial_settings_for(cam, 1, std::nullopt, std::nullopt, CalibrationOptions{}); }),
             "study calibration needs pair voltages");
  EXPECT_HAS(error_of([&] { heading_trials(cam, HeadingStudySettings{}); }), "study heading needs pair voltages");
}

TEST(InstrumentCapabilities, ASweepAxisTheInstrumentDoesNotReadIsRefused) {
  EXPECT_EQ(error_of([&] { check_grid(Rig{}, {GridAxis::parse("device.focal_mm=1:2:2")}); }),
            "--grid device.focal_mm=1:2:2: device.kind six-photodiode does not read 'device.focal_mm' "
            "(only device.kind dofp-camera does); it cannot be swept");
}

TEST(InstrumentCapabilities, ADatasetOfACameraIsNoVoltageDataset) {
  const polrig::test::TempDir tmp("polrig_test_instrument_");
  write_file(tmp.path() / "rig.yaml", rig_to_yaml(camera_rig()));
  write_file(tmp.path() / "stops.csv", "stop,theta_R_deg\n0,0\n");
  const std::string rig_yaml = (tmp.path() / "rig.yaml").string();
  EXPECT_EQ(error_of([&] { read_measured(tmp.path()); }),
            rig_yaml + ": calibrate needs pair voltages (device.kind six-photodiode); device.kind "
                       "dofp-camera has none");
  EXPECT_HAS(error_of([&] { read_voltages(tmp.path()); }), rig_yaml + ": apply needs pair voltages");
}

// ---- the CLI --------------------------------------------------------------------------

class InstrumentCli : public polrig::test::PolrigTest {
 protected:
  InstrumentCli() : PolrigTest("polrig_test_instrument_cli_", "logs") {}
};

TEST_F(InstrumentCli, CommandsThatNeedPairVoltagesRefuseACameraRigAndWriteNothing) {
  const std::string cam = shell_quote(kIndoor);
  const fs::path out = tmp / "out";
  const std::vector<std::pair<std::string, std::string>> commands = {
      // (simulate takes frames from a camera rig: tests/test_dofp.cpp, python/tests/test_dofp.py)
      {"study cs " + cam, "study cs"}, {"study adc " + cam, "study adc"},
      {"run " + cam, "run"}, {"sweep " + cam + " --grid eccentricity.L_S=0:1:2", "sweep"},
      {"study calibration " + cam + " --trials 1", "study calibration"},
      {"study heading " + shell_quote(kOutdoor) + " --trials 1", "study heading"}};
  for (const auto& [command, what] : commands) {
    SCOPED_TRACE(command);
    const Result r = polrig(command + " -o " + shell_quote(out));
    EXPECT_EQ(r.status, 2);
    EXPECT_HAS(r.err, ": " + what + " needs pair voltages (device.kind six-photodiode); device.kind "
                                    "dofp-camera has none");
    EXPECT_FALSE(fs::exists(out));
  }
  // calibrate: a dataset whose rig.yaml is a camera's, and --rig a camera rig.
  const fs::path data = tmp / "data";
  fs::create_directories(data);
  write_file(data / "rig.yaml", rig_to_yaml(camera_rig()));
  write_file(data / "stops.csv", "stop,theta_R_deg\n0,0\n");
  Result r = polrig("calibrate " + shell_quote(data) + " -o " + shell_quote(out));
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, (data / "rig.yaml").string() + ": calibrate --method cs-nc needs pair voltages");
  ok("simulate " + shell_quote(kDefaultRigFile) + " --no-plots -o " + shell_quote(tmp / "sim"));
  r = polrig("calibrate " + shell_quote(tmp / "sim") + " --rig " + cam + " -o " + shell_quote(out));
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, kIndoor + ": calibrate --method cs-nc needs pair voltages");
  ok("calibrate " + shell_quote(tmp / "sim") + " --no-plots -o " + shell_quote(tmp / "cal"));
  r = polrig("apply " + shell_quote(tmp / "cal" / "params.yaml") + " " + shell_quote(data) + " -o " + shell_quote(out));
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, (data / "rig.yaml").string() + ": apply needs pair voltages");
  EXPECT_FALSE(fs::exists(out));
}

// A rig that names its instrument (device.kind: six-photodiode) gives byte for byte the data
// files and the rig.yaml of the same rig without it: the rigs written before the camera keep
// their outputs. Only the manifest's rig_text and command differ.
TEST_F(InstrumentCli, NamingTheDefaultInstrumentChangesNoOutput) {
  const std::string original = read_file(kDefaultRigFile);
  const fs::path named = tmp / "named.yaml";
  ASSERT_TRUE(original.starts_with("#"));
  const std::size_t device = original.find("device:\n");
  ASSERT_NE(device, std::string::npos);
  write_file(named, original.substr(0, device + 8) + "  kind: six-photodiode\n" + original.substr(device + 8));
  ASSERT_EQ(load_rig(named).rig.device_kind, "six-photodiode");
  const fs::path copy = tmp / "wang2019-indoor.yaml";
  write_file(copy, original);
  for (const std::string& cmd : {std::string("simulate"), std::string("study cs --steps 64")}) {
    SCOPED_TRACE(cmd);
    const fs::path a = tmp / ("a" + std::to_string(cmd.size())), b = tmp / ("b" + std::to_string(cmd.size()));
    ok(cmd + " " + shell_quote(copy) + " --no-plots -o " + shell_quote(a));
    ok(cmd + " " + shell_quote(named) + " --no-plots -o " + shell_quote(b));
    std::vector<std::string> files;
    for (const auto& e : fs::directory_iterator(a)) files.push_back(e.path().filename().string());
    std::vector<std::string> files_b;
    for (const auto& e : fs::directory_iterator(b)) files_b.push_back(e.path().filename().string());
    std::sort(files.begin(), files.end());
    std::sort(files_b.begin(), files_b.end());
    EXPECT_EQ(files, files_b);
    for (const std::string& f : files) {
      if (f == "manifest.yaml") continue;
      EXPECT_EQ(read_file(a / f), read_file(b / f)) << f << " differs";
    }
    EXPECT_HAS(read_file(a / "manifest.yaml"), "\ninstrument: six-photodiode\n");
    EXPECT_LACKS(read_file(a / "rig.yaml"), "kind");
    if (cmd == "simulate") {
      ok("calibrate " + shell_quote(a) + " --no-plots -o " + shell_quote(tmp / "ca"));
      ok("calibrate " + shell_quote(b) + " --no-plots -o " + shell_quote(tmp / "cb"));
      for (const auto& e : fs::directory_iterator(tmp / "ca")) {
        const std::string f = e.path().filename().string();
        if (f != "manifest.yaml") {
          EXPECT_EQ(read_file(e.path()), read_file(tmp / "cb" / f)) << f;
        }
      }
    }
  }
}

}  // namespace
