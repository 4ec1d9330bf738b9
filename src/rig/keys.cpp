#include "polrig/rig/keys.h"

#include "polrig/ins/mechanization.h"
#include "polrig/quoted.h"

#include <charconv>
#include <algorithm>
#include <cmath>
#include <utility>

#include <fmt/format.h>

#include "polrig/sky/rayleigh.h"
#include "polrig/source/sky_settings.h"

#include "polrig/rig/error.h"
#include "polrig/sky/sun.h"

namespace polrig {

double parse_finite_number(std::string_view text, std::string_view what) {
  double v = 0.0;
  const char* b = text.data();
  const char* e = text.data() + text.size();
  if (b != e && *b == '+') ++b;
  auto [end, ec] = std::from_chars(b, e, v);
  if (b == e || ec != std::errc() || end != e || !std::isfinite(v))
    throw RigError(fmt::format("{}: expected a finite number, got '{}'", what, quoted_value(text)));
  return v;
}

std::string RealRange::text() const {
  return fmt::format("{}{}, {}{}", lo_open ? "(" : "[", lo, hi, hi_open ? ")" : "]");
}

namespace {

using K = RigKey::Kind;

template <RealRange R>
bool within(double v) { return R.contains(v); }

std::string expects_text(std::string_view noun, const RealRange& r, std::string_view unit) {
  return fmt::format("{} in {}{}{}", noun, r.text(), unit.empty() ? "" : " ", unit);
}

// A real key: `noun` names what it is ("a length"), R is its range in `unit`, `why` says why.
template <RealRange R>
RigKey real(std::string_view path, std::string_view unit, std::string_view noun,
            std::string_view doc, std::string_view why, double& (*ref)(Rig&)) {
  RigKey k{path, K::Real, unit, expects_text(noun, R, unit), doc, why};
  k.real = ref;
  k.range = R;
  k.valid_real = &within<R>;
  return k;
}
template <RealRange R>
RigKey array(std::string_view path, std::string_view unit, std::string_view noun,
             std::string_view doc, std::string_view why, std::span<double> (*ref)(Rig&)) {
  RigKey k{path, K::RealArray, unit, expects_text(noun, R, unit), doc, why};
  k.array = ref;
  k.range = R;
  k.valid_real = &within<R>;
  return k;
}

// Ranges shared by several keys.
constexpr RealRange kTurn{-360.0, 360.0};          // an orientation: one turn either way
constexpr RealRange kTableAngle{-3600.0, 3600.0};  // a table stop: ten turns either way
constexpr RealRange kOffset{0.0, 100.0};           // an eccentricity, mm
constexpr std::string_view kTurnWhy = "an orientation: one turn either way gives every orientation";
constexpr std::string_view kOffsetWhy =
    "the paper's offsets are 0.01–2 mm; beyond 100 mm (the JF-500's port diameter) the sensor "
    "no longer sits under the port";
constexpr std::string_view kTableWhy = "ten turns of the table either way";

// "\"cos4\" or \"traced\"": the models make_source knows.
std::string kinds_text() {
  std::string out;
  const auto kinds = source_kinds();
  for (std::size_t i = 0; i < kinds.size(); ++i)
    out += fmt::format("{}\"{}\"", i == 0 ? "" : i + 1 == kinds.size() ? " or " : ", ", kinds[i]);
  return out;
}

// Who reads a key: the studies (RigKey::Study bits) and the source models (space-separated
// source.model names; empty for every model).
RigKey reads(RigKey k, unsigned studies, std::string_view sources) {
  k.studies = studies;
  k.sources = sources;
  return k;
}

// A key only some instruments read (space-separated device.kind names).
RigKey only(RigKey k, std::string_view instruments) {
  k.instruments = instruments;
  return k;
}
constexpr std::string_view kSix = "six-photodiode", kCamera = "dofp-camera";
constexpr std::string_view kFour = "four-camera", kCameras = "dofp-camera four-camera";
// Z21's unit array; its units are six-photodiode sensors, which read the sensor's own keys.
constexpr std::string_view kUnits = "unit-array", kSixAndUnits = "six-photodiode unit-array";

// An integer key in [lo, hi]; `even`: whole 2 × 2 mosaic cells.
template <long long lo, long long hi, bool even = false>
bool integer_within(long long v) { return v >= lo && v <= hi && (!even || v % 2 == 0); }

RigKey boolean(std::string_view path, std::string_view doc, bool& (*ref)(Rig&)) {
  RigKey k{path, RigKey::Kind::Bool, "", "true or false", doc};
  k.boolean = ref;
  return k;
}

RigKey integer(std::string_view path, std::string_view expects, std::string_view doc,
               std::string_view why, int& (*ref)(Rig&), bool (*valid)(long long)) {
  RigKey k{path, RigKey::Kind::Integer, "", std::string(expects), doc, why};
  k.integer = ref;
  k.valid_integer = valid;
  return k;
}

// "\"six-photodiode\" or \"dofp-camera\"": the kinds make_instrument knows.
std::string instrument_kinds_text() {
  std::string out;
  const auto kinds = instrument_kinds();
  for (std::size_t i = 0; i < kinds.size(); ++i)
    out += fmt::format("{}\"{}\"", i == 0 ? "" : i + 1 == kinds.size() ? " or " : ", ", kinds[i]);
  return out;
}

constexpr unsigned kSimulate = RigKey::kSimulate, kCs = RigKey::kCs, kAdc = RigKey::kAdc,
                   kCalibrate = RigKey::kCalibrate;

// --- trajectory.*, imu.*, navigation.* (rig/ins_settings.h; spec sky-and-compasses.md §4): a unit
// array's vehicle, its IMU and the SINS/PNS filter. Read by a unit-array rig under the sky, whose
// site and first_stop_utc are the run's start.
void add_ins_keys(std::vector<RigKey>& keys) {
  const auto push = [&](RigKey k, unsigned studies) { keys.push_back(reads(only(std::move(k), kUnits), studies, "sky")); };
  const auto list = [&](std::string_view path, std::string_view unit, std::string_view noun, RealRange r,
                        std::string_view doc, std::string_view why, std::vector<double>& (*ref)(Rig&),
                        bool (*valid)(double)) {
    RigKey k{path, K::RealList, unit, expects_text(noun, r, unit), doc, why};
    k.list = ref;
    k.range = r;
    k.max_items = 1000;
    k.valid_real = valid;
    push(k, kSimulate);
  };
  push(real<RealRange{0.01, 100.0}>(
           "device.units.rate_hz", "Hz", "a rate", "the compass's output rate: every unit read once per 1/rate "
           "(Z21 Table 1: 1 Hz) [C: 1]; the IMU's rate must be a whole multiple of it",
           "a reading per 100 s to 100 per second; the six-photodiode chain averages its samples within one",
           [](Rig& r) -> double& { return r.units.rate_hz; }), kSimulate);
  // The vehicle.
  constexpr RealRange kHeading{-360.0, 360.0}, kPitch{-80.0, 80.0}, kRoll{-180.0, 180.0};
  push(real<kHeading>("trajectory.heading_deg", "deg", "an angle", "the start's heading (yaw), clockwise from north",
                      kTurnWhy, [](Rig& r) -> double& { return r.trajectory.heading_deg; }), kSimulate | RigKey::kNavigate);
  push(real<kPitch>("trajectory.pitch_deg", "deg", "an angle", "the start's pitch, nose up positive",
                    "the Euler angles are singular at ±90°; a land vehicle climbs far less than 80°",
                    [](Rig& r) -> double& { return r.trajectory.pitch_deg; }), kSimulate | RigKey::kNavigate);
  push(real<kRoll>("trajectory.roll_deg", "deg", "an angle", "the start's roll, right side down positive; it stays",
                   "half a turn either way", [](Rig& r) -> double& { return r.trajectory.roll_deg; }), kSimulate | RigKey::kNavigate);
  push(real<RealRange{0.0, 300.0}>("trajectory.speed_mps", "m/s", "a speed", "the start's speed along the body's "
                                   "forward axis (0: at rest)",
                                   "at rest to an airliner's cruise", [](Rig& r) -> double& { return r.trajectory.speed_mps; }),
       kSimulate | RigKey::kNavigate);
  push(real<RealRange{0.0, 86400.0, true, false}>(
           "trajectory.duration_s", "s", "a duration",
           "the run's length when no segments are given: one static segment (a cruise when moving) [C: 1200, Z21's 20 min]",
           "positive, at most a day", [](Rig& r) -> double& { return r.trajectory.duration_s; }), kSimulate);
  list("trajectory.segment_s", "s", "a list of up to 1000 durations", RealRange{0.0, 86400.0, true, false},
       "the segments' durations (replace trajectory.duration_s); each a whole number of IMU intervals",
       "positive, at most a day each", [](Rig& r) -> std::vector<double>& { return r.trajectory.segment_s; },
       &within<RealRange{0.0, 86400.0, true, false}>);
  list("trajectory.segment_accel_mps2", "m/s^2", "a list of up to 1000 accelerations", RealRange{-20.0, 20.0},
       "each segment's acceleration along the body's forward axis (one per segment, or none: 0)",
       "a car brakes at ~10 m/s²; 2 g is beyond any land vehicle",
       [](Rig& r) -> std::vector<double>& { return r.trajectory.segment_accel_mps2; }, &within<RealRange{-20.0, 20.0}>);
  list("trajectory.segment_turn_deg_s", "deg/s", "a list of up to 1000 turn rates", RealRange{-90.0, 90.0},
       "each segment's turn rate, clockwise seen from above positive (one per segment, or none: 0)",
       "a quarter turn per second is beyond a vehicle's turns",
       [](Rig& r) -> std::vector<double>& { return r.trajectory.segment_turn_deg_s; }, &within<RealRange{-90.0, 90.0}>);
  list("trajectory.segment_climb_deg_s", "deg/s", "a list of up to 1000 pitch rates", RealRange{-10.0, 10.0},
       "each segment's pitch rate, nose up positive (one per segment, or none: 0); the pitch stays within ±80°",
       "a vehicle's pitch changes by degrees per second at most",
       [](Rig& r) -> std::vector<double>& { return r.trajectory.segment_climb_deg_s; }, &within<RealRange{-10.0, 10.0}>);
  push(real<RealRange{0.0, 10.0}>(
           "trajectory.vibration_mps2", "m/s^2", "an rms acceleration",
           "the vehicle's vibration while it moves: a body-fixed oscillation in the IMU's Δv, rms per axis from 1 m/s "
           "on and in proportion to the speed below, none at rest (ins/trajectory.h); without it steady motion "
           "looks like rest to navigation.zupt's detector [C: 0]",
           "0 (a smooth ride) to 1 g; a car body on a paved road ~0.1–0.5 m/s²",
           [](Rig& r) -> double& { return r.trajectory.vibration_mps2; }), kSimulate);
  // The IMU (ins/imu.h), per axis x, y, z of the body.
  push(real<RealRange{1.0, 2000.0}>("imu.rate_hz", "Hz", "a rate", "the IMU's output rate [C: 100]",
                                    "strapdown IMUs output 1 Hz to 2 kHz",
                                    [](Rig& r) -> double& { return r.imu.rate_hz; }), kSimulate | RigKey::kNavigate);
  // The accessors must be plain function pointers: one per key, so one lambda per triad and field.
#define POLRIG_TRIAD_ARRAY(TRIAD, FIELD) \
  +[](Rig& r) { return std::span<double>(r.imu.TRIAD.FIELD); }
  constexpr RealRange kGyroBias{-1e4, 1e4}, kGyroSigma{0.0, 1e4}, kGyroArw{0.0, 100.0}, kAccelBias{-1e5, 1e5},
      kAccelSigma{0.0, 1e5}, kVrw{0.0, 1e4}, kTau{1.0, 1e7}, kPpm{0.0, 1e5};
  constexpr std::string_view gyro_why = "from navigation grade (0.001°/h) to consumer MEMS (1e4°/h = 2.8°/s)";
  constexpr std::string_view accel_why = "from navigation grade (10 µg) to consumer MEMS (0.1 g)";
  keys.push_back(reads(only(array<kGyroBias>("imu.gyro.bias_deg_h", "deg/h", "3 rates", "constant gyro bias per axis "
      "(the same in every run)", gyro_why, POLRIG_TRIAD_ARRAY(gyro, bias)), kUnits), kSimulate | RigKey::kNavigate, "sky"));
  keys.push_back(reads(only(array<kGyroSigma>("imu.gyro.turn_on_deg_h", "deg/h", "3 standard deviations",
      "σ of the gyro's turn-on bias, drawn per seed (Z21 Table 1's 5°/h) [C: 5]", gyro_why,
      POLRIG_TRIAD_ARRAY(gyro, turn_on_sigma)), kUnits), kSimulate | RigKey::kNavigate, "sky"));
  keys.push_back(reads(only(array<kGyroSigma>("imu.gyro.instability_deg_h", "deg/h", "3 standard deviations",
      "σ of the gyro's bias instability, a first-order Gauss–Markov process [C: 0]", gyro_why,
      POLRIG_TRIAD_ARRAY(gyro, bias_instability)), kUnits), kSimulate | RigKey::kNavigate, "sky"));
  keys.push_back(reads(only(array<kTau>("imu.gyro.correlation_time_s", "s", "3 times",
      "the Gauss–Markov bias's correlation time [C: 3600]", "a second to four months",
      POLRIG_TRIAD_ARRAY(gyro, correlation_time_s)), kUnits), kSimulate | RigKey::kNavigate, "sky"));
  keys.push_back(reads(only(array<kGyroArw>("imu.gyro.arw_deg_rt_h", "deg/sqrt(h)", "3 noise densities",
      "angle random walk (white rate noise) [C: 0.5, Z21 Table 1]", "navigation grade 0.001°/√h to MEMS 100°/√h",
      POLRIG_TRIAD_ARRAY(gyro, white_noise)), kUnits), kSimulate | RigKey::kNavigate, "sky"));
  keys.push_back(reads(only(array<kGyroArw>("imu.gyro.rrw_deg_h_rt_h", "deg/h/sqrt(h)", "3 noise densities",
      "rate random walk of the gyro bias [C: 0]", "as the angle random walk",
      POLRIG_TRIAD_ARRAY(gyro, random_walk)), kUnits), kSimulate, "sky"));
  keys.push_back(reads(only(array<kPpm>("imu.gyro.scale_factor_ppm", "ppm", "3 standard deviations",
      "σ of the gyro scale-factor errors, drawn per seed [C: 0]", "10 % at most",
      POLRIG_TRIAD_ARRAY(gyro, scale_factor_ppm)), kUnits), kSimulate, "sky"));
  keys.push_back(reads(only(array<kAccelBias>("imu.accel.bias_ug", "ug", "3 accelerations",
      "constant accelerometer bias per axis (the same in every run)", accel_why,
      POLRIG_TRIAD_ARRAY(accel, bias)), kUnits), kSimulate | RigKey::kNavigate, "sky"));
  keys.push_back(reads(only(array<kAccelSigma>("imu.accel.turn_on_ug", "ug", "3 standard deviations",
      "σ of the accelerometer's turn-on bias, drawn per seed (Z21 Table 1's 50 µg) [C: 50]", accel_why,
      POLRIG_TRIAD_ARRAY(accel, turn_on_sigma)), kUnits), kSimulate | RigKey::kNavigate, "sky"));
  keys.push_back(reads(only(array<kAccelSigma>("imu.accel.instability_ug", "ug", "3 standard deviations",
      "σ of the accelerometer's bias instability (Gauss–Markov) [C: 0]", accel_why,
      POLRIG_TRIAD_ARRAY(accel, bias_instability)), kUnits), kSimulate | RigKey::kNavigate, "sky"));
  keys.push_back(reads(only(array<kTau>("imu.accel.correlation_time_s", "s", "3 times",
      "the Gauss–Markov bias's correlation time [C: 3600]", "a second to four months",
      POLRIG_TRIAD_ARRAY(accel, correlation_time_s)), kUnits), kSimulate | RigKey::kNavigate, "sky"));
  keys.push_back(reads(only(array<kVrw>("imu.accel.vrw_ug_rt_hz", "ug/sqrt(Hz)", "3 noise densities",
      "velocity random walk (white specific-force noise) [C: 25, Z21 Table 1]",
      "navigation grade 5 µg/√Hz to MEMS 1e4 µg/√Hz", POLRIG_TRIAD_ARRAY(accel, white_noise)), kUnits),
      kSimulate | RigKey::kNavigate, "sky"));
  keys.push_back(reads(only(array<kVrw>("imu.accel.rrw_ug_rt_s", "ug/sqrt(s)", "3 noise densities",
      "random walk of the accelerometer bias [C: 0]", "as the velocity random walk",
      POLRIG_TRIAD_ARRAY(accel, random_walk)), kUnits), kSimulate, "sky"));
  keys.push_back(reads(only(array<kPpm>("imu.accel.scale_factor_ppm", "ppm", "3 standard deviations",
      "σ of the accelerometer scale-factor errors, drawn per seed [C: 0]", "10 % at most",
      POLRIG_TRIAD_ARRAY(accel, scale_factor_ppm)), kUnits), kSimulate, "sky"));
#undef POLRIG_TRIAD_ARRAY
  constexpr RealRange kMis{0.0, 5.0};
  push(real<kMis>("imu.gyro.misalignment_deg", "deg", "a standard deviation",
                  "σ of each off-diagonal element of the gyro triad's misalignment, drawn per seed [C: 0]",
                  "a triad's axes are orthogonal to a few mrad", [](Rig& r) -> double& { return r.imu.gyro.misalignment_deg; }),
       kSimulate);
  push(real<kMis>("imu.accel.misalignment_deg", "deg", "a standard deviation",
                  "σ of each off-diagonal element of the accelerometer triad's misalignment, drawn per seed [C: 0]",
                  "a triad's axes are orthogonal to a few mrad", [](Rig& r) -> double& { return r.imu.accel.misalignment_deg; }),
       kSimulate);
  // The filter (ins/filter.h) and the INS's start.
  constexpr unsigned kNav = RigKey::kNavigate;
  push(real<RealRange{0.0, 10.0, true, false}>(
           "navigation.sigma_H_deg", "deg", "a standard deviation",
           "the compass' sun-elevation σ the filter assumes: R = (cos H·σ_H)² [C: 0.1, Z21 Table 1]",
           "positive; beyond 10° the elevation tells nothing of the position",
           [](Rig& r) -> double& { return r.navigation.sigma_H_deg; }), kNav);
  push(real<RealRange{0.0, 10.0, true, false}>(
           "navigation.sigma_A_deg", "deg", "a standard deviation",
           "the compass' sun-azimuth σ in n the filter assumes (navigation.measurement azimuth or sun-vector): R = σ_A² "
           "[C: 0.0405, what the shipped Z21 rigs' chain delivers beside its 0.1° in elevation; docs/validation.md]",
           "positive; beyond 10° the azimuth tells nothing of the heading",
           [](Rig& r) -> double& { return r.navigation.sigma_A_deg; }), kNav);
  push(boolean("navigation.adaptive", "Sage–Husa's adaptive R (spec §4.7) [C: true]",
               [](Rig& r) -> bool& { return r.navigation.adaptive; }), kNav);
  push(real<RealRange{0.5, 1.0, false, true}>(
           "navigation.forgetting_factor", "", "a factor", "Sage–Husa's b: β → 1 − b (Z21: 0.98) [C: 0.98]",
           "below 0.5 R follows the last few innovations; towards 1 it forgets ever more slowly (1 itself: never)",
           [](Rig& r) -> double& { return r.navigation.forgetting_factor; }), kNav);
  push(boolean("navigation.hold_height", "hold the height at the start's, as Z21's barometer does [C: true]",
               [](Rig& r) -> bool& { return r.navigation.hold_height; }), kNav);
  push(boolean("navigation.zupt", "zero-velocity updates of the integrated filter at every compass reading whose "
               "IMU interval passes the rest detector (ins/zupt.h; needs the IMU's white noise, imu.gyro.arw_deg_rt_h "
               "and imu.accel.vrw_ug_rt_hz) [C: false, Z21 has none]",
               [](Rig& r) -> bool& { return r.navigation.zupt; }), kNav);
  push(real<RealRange{0.0, 1.0, true, false}>(
           "navigation.zupt_sigma_mps", "m/s", "a standard deviation",
           "the velocity a zero-velocity update allows per axis: R = σ² [C: 0.001, a vehicle standing on its wheels]",
           "positive; 1 m/s is no rest at all", [](Rig& r) -> double& { return r.navigation.zupt_sigma_mps; }), kNav);
  keys.push_back(reads(only(array<RealRange{-10.0, 10.0}>(
      "navigation.initial_attitude_error_deg", "deg", "3 angles",
      "roll, pitch and heading errors of the INS's start: added to the start attitude of trajectory.* the INS starts from [C: 0, 0, 0]",
      "an alignment is good to degrees at worst", [](Rig& r) { return std::span<double>(r.navigation.initial_attitude_error_deg); }),
      kUnits), kNav, "sky"));
  keys.push_back(reads(only(array<RealRange{0.0, 30.0, true, false}>(
      "navigation.attitude_sigma_deg", "deg", "3 standard deviations",
      "P0's attitude errors φ_E, φ_N, φ_U [C: 0.05, 0.05, 0.5]", "positive; 30° is no alignment at all",
      [](Rig& r) { return std::span<double>(r.navigation.attitude_sigma_deg); }), kUnits), kNav, "sky"));
  push(real<RealRange{0.0, 100.0, true, false}>(
           "navigation.velocity_sigma_mps", "m/s", "a standard deviation", "P0's velocity error per axis [C: 0.02]",
           "positive; 100 m/s is no velocity at all", [](Rig& r) -> double& { return r.navigation.velocity_sigma_mps; }),
       kNav);
  push(real<RealRange{0.0, 1e6, true, false}>(
           "navigation.position_sigma_m", "m", "a standard deviation", "P0's north and east position error, and the height's when navigation.hold_height is false [C: 200]",
           "positive; 1000 km is a continent", [](Rig& r) -> double& { return r.navigation.position_sigma_m; }), kNav);
  push(real<RealRange{2.0, 86400.0}>(
           "navigation.pns_window_s", "s", "a duration",
           "PNS: each fix from the sun elevations of the last window (W16's positioning fit, the vehicle assumed "
           "still over it) [C: 300]",
           "two readings at least; a day at most", [](Rig& r) -> double& { return r.navigation.pns_window_s; }), kNav);
  {
    RigKey k{"navigation.pns_level", K::Text, "", "accelerometer or sins",
             "PNS's roll and pitch: accelerometer, the mean specific force over each reading's interval (readings "
             "while the vehicle accelerates or turns are left out), or sins, the free INS's attitude (drifting with "
             "the gyro biases) [C: accelerometer]"};
    k.text = [](Rig& r) -> std::string& { return r.navigation.pns_level; };
    k.valid_text = [](std::string_view v) { return v == "accelerometer" || v == "sins"; };
    push(k, kNav);
  }
  {
    RigKey k{"navigation.integrated_level", K::Text, "", "ins or accelerometer",
             "the SINS/PNS filter's roll and pitch for the measured elevation: ins, its own attitude (Z21), or "
             "accelerometer, the mean specific force over each reading's interval as PNS's (unsteady readings give no "
             "update) [C: ins]"};
    k.text = [](Rig& r) -> std::string& { return r.navigation.integrated_level; };
    k.valid_text = [](std::string_view v) { return v == "ins" || v == "accelerometer"; };
    push(k, kNav);
  }
  {
    RigKey k{"navigation.measurement", K::Text, "", "elevation, elevation-z21, azimuth, sun-vector or pns-fix",
             "what the SINS/PNS filter takes from the compass (ins/filter.h): elevation, the sun's elevation with the "
             "tilt columns (the INS's tilt the measured elevation carries is estimated); elevation-z21, Z21's "
             "position-only H; azimuth, the sun's azimuth in n (the heading, the tilt and the position); sun-vector, "
             "both as two updates; pns-fix, no sun update but the PNS's fix of each navigation.pns_window_s window "
             "that does not overlap the last, with the fit's covariance (loosely coupled) [C: elevation]"};
    k.text = [](Rig& r) -> std::string& { return r.navigation.measurement; };
    k.valid_text = [](std::string_view v) {
      return v == "elevation" || v == "elevation-z21" || v == "azimuth" || v == "sun-vector" || v == "pns-fix";
    };
    push(k, kNav);
  }
  {
    RigKey k{"navigation.initial_errors", K::Text, "", "drawn or none",
             "a simulated run's INS start: the truth plus errors drawn from P0 (navigation.attitude_sigma_deg, "
             "velocity_sigma_mps, position_sigma_m) with the rig's seed, so that the filter's P0 is true, or the "
             "truth itself; navigation.initial_attitude_error_deg is added to either. A measured log's INS starts "
             "where its rig says [C: drawn]"};
    k.text = [](Rig& r) -> std::string& { return r.navigation.initial_errors; };
    k.valid_text = [](std::string_view v) { return v == "drawn" || v == "none"; };
    push(k, kNav);
  }
}

// --- sky.model and sky.rt.* (source/sky_settings.h; docs/physics.md §21): which sky, and the
// vector-RT sky's atmosphere. Read under source.model sky; sky.rt.* only by sky.model vector-rt.
// The sky models that read a key: P_max and the radiance model serve single scattering and Berry's
// sky; the atmosphere (sky.rt.*) the vector-RT sky and Berry's fit to it.
constexpr std::string_view kSingleScattering = "single-scattering berry", kVectorRt = "vector-rt berry",
                           kBerry = "berry";

void add_vector_rt_keys(std::vector<RigKey>& keys) {
  {
    RigKey k{"sky.model", K::Text, "", "single-scattering, vector-rt or berry",
             "what the sky is: single scattering with one P_max and a radiance model (sky.p_max, "
             "sky.radiance); the exact polarized Rayleigh sky of a plane-parallel atmosphere over a "
             "Lambertian ground (sky.rt.*), whose radiance, DoP and AoP all come from the solution; or "
             "Berry et al. 2004's four-neutral-point sky (sky.berry.*, with sky.p_max and sky.radiance)"};
    k.text = [](Rig& r) -> std::string& { return r.source.sky.model; };
    k.valid_text = [](std::string_view v) { return parse_sky_kind(v).has_value(); };
    keys.push_back(reads(k, kSimulate, "sky"));
  }
  const auto rt = [&](RigKey k) {
    k.sky_models = kVectorRt;
    keys.push_back(reads(std::move(k), kSimulate, "sky"));
  };
  {
    RigKey k{"sky.rt.tau_rayleigh", K::Text, "", "an optical depth in [0, 100], or bodhaine",
             "the Rayleigh optical depth of the whole atmosphere, or bodhaine: Bodhaine et al. 1999's at "
             "sky.rt.wavelength_nm and sky.rt.pressure_hPa (0.22 at 450 nm, 0.097 at 550 nm at sea level)",
             "from a nearly clear atmosphere to one the sun barely crosses; 0 only under an aerosol (an "
             "aerosol-only layer, IPRT's cases)"};
    k.text = [](Rig& r) -> std::string& { return r.source.sky.tau_rayleigh; };
    k.valid_text = [](std::string_view v) {
      try {
        (void)parse_tau_rayleigh(v);
        return true;
      } catch (const std::invalid_argument&) {
        return false;
      }
    };
    rt(k);
  }
  rt(real<RealRange{250.0, 4000.0}>(
      "sky.rt.wavelength_nm", "nm", "a wavelength", "the wavelength of sky.rt.tau_rayleigh: bodhaine",
      "Bodhaine et al.'s refractive index of air holds from the near UV to the thermal infrared",
      [](Rig& r) -> double& { return r.source.sky.wavelength_nm; }));
  rt(real<RealRange{1.0, 1100.0}>(
      "sky.rt.pressure_hPa", "hPa", "a pressure", "the surface pressure of sky.rt.tau_rayleigh: bodhaine",
      "from the stratosphere to the deepest mine; sea level is 1013.25 hPa",
      [](Rig& r) -> double& { return r.source.sky.pressure_hPa; }));
  rt(real<RealRange{0.0, 0.5, false, true}>(
      "sky.rt.depolarization", "", "a depolarization factor",
      "ρ of the Rayleigh scatterers (Hansen & Travis 1974 Eq. 2.15): air's is 0.0279",
      "0 is isotropic molecules; 1/2 makes the phase matrix's Δ' change sign",
      [](Rig& r) -> double& { return r.source.sky.rt.depolarization; }));
  rt(real<RealRange{0.0, 1.0}>(
      "sky.rt.ground_albedo", "", "an albedo", "the Lambertian ground's albedo under the atmosphere",
      "a ground reflects between none and all of the light it receives",
      [](Rig& r) -> double& { return r.source.sky.rt.ground_albedo; }));
  rt(integer("sky.rt.streams", "an even integer in [4, 128]",
             "discrete ordinates over both hemispheres; 32 meets the exact tables to 6e-6 in I; with an aerosol its "
             "phase matrix is truncated at l = streams/2 - 1 (physics §24), and streams that leave the truncated phase "
             "function negative are refused (IPRT A4's is negative at 16, 20 and 24 streams; 32, the default, and 64 hold)",
             "fewer than 4 cannot hold Rayleigh's m = 2 term; beyond 128 the solve takes seconds",
             [](Rig& r) -> int& { return r.source.sky.rt.streams; }, &integer_within<4, 128, true>));
  {
    RigKey k{"sky.rt.direct_beam", K::Text, "", "plane-parallel or pseudo-spherical",
             "the sun's direct beam through the atmosphere: plane-parallel (air mass 1/mu0, the exact tables' "
             "geometry; the sun at 2 degrees or higher) or pseudo-spherical (the Chapman air mass of an 8 km "
             "scale height over the Earth's sphere; the sun at 1 degree or higher; physics §24)"};
    k.text = [](Rig& r) -> std::string& { return r.source.sky.direct_beam; };
    k.valid_text = [](std::string_view v) { return v == "plane-parallel" || v == "pseudo-spherical"; };
    rt(k);
  }
  rt(real<RealRange{0.0, 100.0}>(
      "sky.rt.aerosol.tau", "", "an optical depth",
      "the aerosol's optical depth, mixed evenly with the air through the layer (physics §24); 0: no aerosol",
      "0.05-0.3 in clear continental air at 500 nm; past 100 no light reaches the ground",
      [](Rig& r) -> double& { return r.source.sky.rt.aerosol.tau; }));
  rt(real<RealRange{0.0, 1.0, true, false}>(
      "sky.rt.aerosol.ssa", "", "a single-scattering albedo",
      "the aerosol's single-scattering albedo: the part of its extinction that is scattering",
      "0.8-1 for most aerosols; 0 would be a pure absorber, which scatters no light to polarize",
      [](Rig& r) -> double& { return r.source.sky.rt.aerosol.ssa; }));
  {
    RigKey k{"sky.rt.aerosol.phase_matrix", K::Text, "", "a path to a phase-matrix file",
             "the aerosol's phase matrix over the scattering angle (docs/formats.md §6.22; "
             "../shared/data/aerosol-phase-matrix/ holds IPRT case A4's), relative to the rig file; needed "
             "with sky.rt.aerosol.tau > 0"};
    k.text = [](Rig& r) -> std::string& { return r.source.sky.aerosol_phase_matrix; };
    k.valid_text = [](std::string_view v) { return !v.empty(); };
    rt(k);
  }
  for (const bool babinet : {true, false}) {
    RigKey k{babinet ? "sky.berry.babinet_deg" : "sky.berry.brewster_deg", K::Text, "deg",
             "a distance in [0, 90) degrees, or fit",
             babinet ? "Berry's sky: Babinet's point's distance above the sun along the solar meridian, or fit: "
                       "fitted to the vector-RT sky of sky.rt.* at the sun's elevation (physics §22)"
                     : "Berry's sky: Brewster's point's distance below the sun along the solar meridian, or fit "
                       "(as sky.berry.babinet_deg)",
             "0 puts the point on the sun (single scattering's pattern when both are 0); clear skies have "
             "10-25 degrees; at 90 the point's antipode meets the sun"};
    if (babinet) k.text = [](Rig& r) -> std::string& { return r.source.sky.berry_babinet_deg; };
    else k.text = [](Rig& r) -> std::string& { return r.source.sky.berry_brewster_deg; };
    k.valid_text = [](std::string_view v) {
      try {
        (void)parse_berry_distance("", v);
        return true;
      } catch (const std::invalid_argument&) {
        return false;
      }
    };
    k.sky_models = kBerry;
    keys.push_back(reads(std::move(k), kSimulate, "sky"));
  }
}

std::vector<RigKey> make_keys() {
  std::vector<RigKey> keys;
  // --- device -------------------------------------------------------------------------
  {
    RigKey k{"device.kind", K::Text, "", instrument_kinds_text(),
             "the instrument: six-photodiode is W19's sensor (pair voltages), dofp-camera H17's "
             "pixelated polarization camera (frames), four-camera W16's four cameras with one "
             "polarizer each (frames, a fused Stokes image), unit-array Z21's compass of six-photodiode "
             "units each along its own view (an AoP and a DoP per unit); it decides which device.* keys the rig reads"};
    k.text = [](Rig& r) -> std::string& { return r.device_kind; };
    k.valid_text = [](std::string_view v) {
      for (std::string_view kind : instrument_kinds())
        if (v == kind) return true;
      return false;
    };
    keys.push_back(reads(k, kSimulate | kCs | kAdc | kCalibrate, ""));
  }
  keys.push_back(reads(real<RealRange{0.1, 500.0}>(
      "device.L_photo", "mm", "a length",
      "radius of the photodiode ring around the sensor centre O_S",
      "the seed sensor's ring is 14 mm; a ring of more than 0.5 m is no sensor under a port",
      [](Rig& r) -> double& { return r.device.ring.L_photo; }), kSimulate | kCs, ""));
  keys.push_back(reads(array<kTurn>("device.beta_deg", "deg", "6 angles",
                              "angle β_m of photodiode m on the ring, rig frame at θ_R = 0 "
                              "(x-axis from O_S through photodiode 1)",
                              kTurnWhy,
                              [](Rig& r) { return std::span<double>(r.device.ring.beta_deg); }), kSimulate | kCs, ""));
  keys.push_back(reads(array<kTurn>("device.film_axes_deg", "deg", "6 angles",
                              "nominal film axes in the sensor frame; they define the theory "
                              "parameters α_j = −2f_j, α_h = 180° − 2f_h",
                              kTurnWhy,
                              [](Rig& r) { return std::span<double>(r.device.film_axis_deg); }), kAdc | kCalibrate, ""));
  keys.push_back(reads(real<RealRange{0.0, 1.0, true, true}>(
      "device.d", "", "a degree of polarization",
      "degree of linear polarization of the light reaching the sensor",
      "0 is unpolarized light (no angle to measure), 1 the limit of a perfect polarizer",
      [](Rig& r) -> double& { return r.device.d; }), kSimulate | kAdc | kCalibrate, ""));
  keys.push_back(reads(array<RealRange{-720.0, 720.0}>(
      "device.truth.alpha_deg", "deg", "6 angles",
      "true installation angles α_m, doubled-angle domain (Eq. 15)",
      "doubled angles (α = −2f): one turn of the film either way",
      [](Rig& r) { return std::span<double>(r.device.truth.alpha_deg); }), kSimulate | kCs, ""));
  keys.push_back(reads(array<RealRange{-1000.0, 1000.0}>(
      "device.truth.k_mV", "mV", "3 offsets",
      "true additive offsets k_i of the pair voltages (Eq. 15)",
      "the paper's offsets are ±10 mV; beyond ±1 V an offset exceeds a log amplifier's output",
      [](Rig& r) { return std::span<double>(r.device.truth.k_mV); }), kSimulate, ""));
  keys.push_back(reads(array<RealRange{0.5, 2.0}>(
      "device.truth.kv", "", "3 gains",
      "true log-amplifier reference deviations kv_i (Eq. 15)",
      "the amplifier's scale against nominal: Table 2's are 1.008–1.022; a factor of 2 either "
      "way is another amplifier",
      [](Rig& r) { return std::span<double>(r.device.truth.kv); }), kSimulate | kCs, ""));
  keys.push_back(reads(array<RealRange{-1.0, 0.0, true, false}>(
      "device.truth.kd", "", "6 values",
      "true polarizer coefficients kd_m = (τM−τm)/(τM+τm) − 1 (Eq. 15)",
      "kd = −1 is a film that does not polarize, 0 a perfect one",
      [](Rig& r) { return std::span<double>(r.device.truth.kd); }), kSimulate | kCs, ""));
  {
    RigKey k{"device.truth_from", K::Text, "", "a path to a params.yaml",
             "load device.truth from a calibration's params.yaml (path relative to the rig "
             "file); excludes device.truth.*"};
    k.text = [](Rig& r) -> std::string& { return r.device.truth_from; };
    k.valid_text = [](std::string_view v) { return !v.empty(); };
    keys.push_back(reads(k, kSimulate | kCs, ""));
  }
  // Every device.* key above but device.kind and device.d (the light's degree, at any
  // instrument) is the six-photodiode sensor's.
  for (RigKey& k : keys)
    if (k.path != "device.kind" && k.path != "device.d") k.instruments = kSix;
  // Each unit of a unit array is that sensor: its true parameters and film axes (the theory model).
  for (RigKey& k : keys)
    if (k.path.starts_with("device.truth.") || k.path == "device.film_axes_deg") k.instruments = kSixAndUnits;
  // --- device.kind dofp-camera (device/dofp_camera.h; spec sky-and-compasses.md §2.1–2.3) --
  keys.push_back(reads(only(integer(
      "device.width_px", "an even integer in [2, 16384]", "image columns (H17's CCD: 640)",
      "whole 2 × 2 mosaic cells; 16384 columns is beyond any polarization camera made",
      [](Rig& r) -> int& { return r.camera.width_px; }, &integer_within<2, 16384, true>), kCamera),
      kSimulate | kCalibrate, ""));
  keys.push_back(reads(only(integer(
      "device.height_px", "an even integer in [2, 16384]", "image rows (H17's CCD: 480)",
      "whole 2 × 2 mosaic cells; 16384 rows is beyond any polarization camera made",
      [](Rig& r) -> int& { return r.camera.height_px; }, &integer_within<2, 16384, true>), kCamera),
      kSimulate | kCalibrate, ""));
  keys.push_back(reads(only(real<RealRange{0.5, 100.0}>(
      "device.pixel_um", "um", "a pixel pitch", "pixel pitch (H17: 7.4 µm)",
      "image sensors' pixels span about 1 µm (phones) to tens of µm (scientific CCDs)",
      [](Rig& r) -> double& { return r.camera.pixel_um; }), kCamera), kSimulate | kCalibrate, ""));
  keys.push_back(reads(only(real<RealRange{0.5, 1000.0}>(
      "device.focal_mm", "mm", "a focal length",
      "pinhole focal length (H17: 3 mm, f_c = focal_mm/pixel_um·1000 = 405.4 px)",
      "from a fisheye's 0.5 mm to a 1 m telephoto",
      [](Rig& r) -> double& { return r.camera.focal_mm; }), kCamera), kSimulate | kCalibrate, ""));
  keys.push_back(reads(only(boolean(
      "device.vignetting", "the lens's natural cos⁴ falloff of the image irradiance (off: H17's "
      "pinhole model)",
      [](Rig& r) -> bool& { return r.camera.vignetting; }), kCamera), kSimulate, ""));
  keys.push_back(reads(only(array<kTurn>(
      "device.mosaic_deg", "deg", "4 angles",
      "analyzer axes α of a 2 × 2 cell's pixels (top-left, top-right, bottom-left, bottom-right), "
      "image frame from X_l towards Y_l (H17: 0, 90, 45, 135)",
      kTurnWhy, [](Rig& r) { return std::span<double>(r.camera.mosaic_deg); }), kCamera),
      kSimulate | kCalibrate, ""));
  keys.push_back(reads(only(real<RealRange{0.0, 1e9, true, false}>(
      "device.gain_DN", "DN", "a gain", "mean gain K: DN per unit of the source's intensity",
      "positive; 1e9 DN per unit saturates any ADC at any useful light",
      [](Rig& r) -> double& { return r.camera.gain_DN; }), kCamera), kSimulate, ""));
  keys.push_back(reads(only(real<RealRange{0.0, 0.3}>(
      "device.gain_spread", "", "a relative spread", "relative SD of the gain K over the pixels",
      "beyond 30 % a Gaussian draw gives non-positive gains (3.3 σ) in a VGA frame",
      [](Rig& r) -> double& { return r.camera.gain_spread; }), kCamera), kSimulate, ""));
  keys.push_back(reads(only(array<RealRange{0.5, 2.0}>(
      "device.mosaic_gain", "", "4 gain factors",
      "gain factor of each mosaic position (top-left, top-right, bottom-left, bottom-right): "
      "K = gain_DN·mosaic_gain·(1 + gain_spread·z); a systematic difference between the four "
      "analyzers, which step 1 removes (H17 Table 1)",
      "a relative gain: the four analyzers of one sensor differ by percents; a factor of 2 either "
      "way is no longer one camera's mosaic",
      [](Rig& r) { return std::span<double>(r.camera.mosaic_gain); }), kCamera), kSimulate, ""));
  keys.push_back(reads(only(real<RealRange{-16777216.0, 16777216.0}>(
      "device.offset_DN", "DN", "an offset", "mean offset b",
      "an offset beyond the largest ADC's range (24 bits) clips every pixel",
      [](Rig& r) -> double& { return r.camera.offset_DN; }), kCamera), kSimulate, ""));
  keys.push_back(reads(only(real<RealRange{0.0, 16777216.0}>(
      "device.offset_spread_DN", "DN", "a standard deviation", "SD of the offset b over the pixels",
      "as device.offset_DN: the largest ADC's range",
      [](Rig& r) -> double& { return r.camera.offset_spread_DN; }), kCamera), kSimulate, ""));
  keys.push_back(reads(only(array<RealRange{0.0, 1.0}>(
      "device.k", "", "4 efficiencies",
      "polarization efficiency k of the cell's four positions (Eq. 17), before the extinction",
      "0 is a pixel that does not analyze, 1 a perfect analyzer (spec §2.3: k is the modulus of a mean of unit phasors)",
      [](Rig& r) { return std::span<double>(r.camera.k); }), kCamera), kSimulate, ""));
  keys.push_back(reads(only(array<RealRange{-90.0, 90.0}>(
      "device.eps_deg", "deg", "4 angles", "angle error ε of the cell's four positions (Eq. 17)",
      "an axial angle: ±90° is every orientation of an analyzer",
      [](Rig& r) { return std::span<double>(r.camera.eps_deg); }), kCamera), kSimulate, ""));
  keys.push_back(reads(only(real<RealRange{0.0, 0.5}>(
      "device.k_spread", "", "a standard deviation", "SD of k over the pixels",
      "k lies in [0, 1]: a spread of half that range is no longer a spread about a mean",
      [](Rig& r) -> double& { return r.camera.k_spread; }), kCamera), kSimulate, ""));
  keys.push_back(reads(only(real<RealRange{0.0, 45.0}>(
      "device.eps_spread_deg", "deg", "a standard deviation", "SD of ε over the pixels",
      "an axial angle's spread beyond 45° is no longer a spread about a mean",
      [](Rig& r) -> double& { return r.camera.eps_spread_deg; }), kCamera), kSimulate, ""));
  keys.push_back(reads(only(real<RealRange{-1.0, 1.0}>(
      "device.misregistration_dx_px", "px", "a shift",
      "shift of the polarizer mosaic against the pixels along x (spec §2.3's overlap formula)",
      "a whole pixel turns each analyzer into its neighbour's",
      [](Rig& r) -> double& { return r.camera.misregistration_dx_px; }), kCamera), kSimulate, ""));
  keys.push_back(reads(only(real<RealRange{-1.0, 1.0}>(
      "device.misregistration_dy_px", "px", "a shift",
      "shift of the polarizer mosaic against the pixels along y (spec §2.3's overlap formula)",
      "a whole pixel turns each analyzer into its neighbour's",
      [](Rig& r) -> double& { return r.camera.misregistration_dy_px; }), kCamera), kSimulate, ""));
  keys.push_back(reads(only(real<RealRange{-45.0, 45.0}>(
      "device.misregistration_rotation_deg", "deg", "an angle",
      "rotation of the polarizer mosaic about the image centre, from X_l towards Y_l",
      "a quarter turn maps the mosaic onto itself with its axes exchanged: ±45° covers it",
      [](Rig& r) -> double& { return r.camera.misregistration_rotation_deg; }), kCamera), kSimulate, ""));
  keys.push_back(reads(only(real<RealRange{1.0, 1e12, true, false}>(
      "device.extinction_ratio", "", "a ratio",
      "extinction ratio τ_M/τ_m of the wire grids: k is multiplied by (ER − 1)/(ER + 1)",
      "1 is no polarizer; wire grids reach 10²–10⁴; 1e12 is an ideal one in double precision",
      [](Rig& r) -> double& { return r.camera.extinction_ratio; }), kCamera), kSimulate, ""));
  keys.push_back(reads(only(boolean(
      "device.noise", "Poisson–Gaussian noise (shot and read noise) on every frame",
      [](Rig& r) -> bool& { return r.camera.noise; }), kCamera), kSimulate, ""));
  keys.push_back(reads(only(real<RealRange{0.0, 1e6, true, false}>(
      "device.electrons_per_DN", "e/DN", "a conversion gain",
      "shot noise: a signal of s DN holds s·electrons_per_DN electrons",
      "image sensors' conversion gains lie around 0.1–100 e⁻/DN; 1e6 is noise-free in practice",
      [](Rig& r) -> double& { return r.camera.electrons_per_DN; }), kCamera), kSimulate, ""));
  keys.push_back(reads(only(real<RealRange{0.0, 1e4}>(
      "device.read_noise_DN", "DN", "a standard deviation", "Gaussian read noise per pixel and frame",
      "more than 1e4 DN buries a 12-bit camera's whole range",
      [](Rig& r) -> double& { return r.camera.read_noise_DN; }), kCamera), kSimulate, ""));
  keys.push_back(reads(only(integer(
      "device.adc_bits", "an integer in [1, 16]", "the camera's ADC depth: raw values 0 … 2^bits − 1",
      "cameras digitise to 8–16 bits; a raw frame holds 16-bit values",
      [](Rig& r) -> int& { return r.camera.adc_bits; }, &integer_within<1, 16>), kCamera),
      kSimulate, ""));
  // --- device.kind four-camera (device/four_camera.h; spec sky-and-compasses.md §3.1–3.2): the
  // cameras' settings under device.cameras (the DoFP camera's device.width_px etc. are its own).
  keys.push_back(reads(only(integer(
      "device.cameras.width_px", "an integer in [2, 16384]", "image columns of each camera (W16: 1034)",
      "16384 columns is beyond any machine-vision camera of the kind",
      [](Rig& r) -> int& { return r.four_camera.width_px; }, &integer_within<2, 16384>), kFour), kSimulate, ""));
  keys.push_back(reads(only(integer(
      "device.cameras.height_px", "an integer in [2, 16384]", "image rows of each camera (W16: 778)",
      "16384 rows is beyond any machine-vision camera of the kind",
      [](Rig& r) -> int& { return r.four_camera.height_px; }, &integer_within<2, 16384>), kFour), kSimulate, ""));
  keys.push_back(reads(only(real<RealRange{0.5, 100.0}>(
      "device.cameras.pixel_um", "um", "a pixel pitch",
      "pixel pitch (the GC1031CP's Sony ICX204: 4.65 µm); converts f_x to mm in the truth",
      "image sensors' pixels span about 1 µm (phones) to tens of µm (scientific CCDs)",
      [](Rig& r) -> double& { return r.four_camera.pixel_um; }), kFour), kSimulate, ""));
  keys.push_back(reads(only(array<kTurn>(
      "device.cameras.polarizer_deg", "deg", "4 angles",
      "polarizer axes φ_j of cameras 1–4, each camera's frame from X towards Y (W16: 0, 45, 90, 135)",
      kTurnWhy, [](Rig& r) { return std::span<double>(r.four_camera.polarizer_deg); }), kFour), kSimulate, ""));
  keys.push_back(reads(only(array<RealRange{-90.0, 90.0}>(
      "device.cameras.eps_deg", "deg", "4 angles",
      "mounting errors ε_j of the four polarizers: the true axis is φ_j + ε_j [C: 0, 0.4, −0.3, 0.6]",
      "an axial angle: ±90° is every orientation of a polarizer",
      [](Rig& r) { return std::span<double>(r.four_camera.eps_deg); }), kFour), kSimulate, ""));
  keys.push_back(reads(only(array<RealRange{0.0, 1e9, true, false}>(
      "device.cameras.gain_DN", "DN", "4 gains",
      "gains K_j of cameras 1–4: DN per unit of the source's intensity, Malus's ½ absorbed (spec §3.2) "
      "[C: 1200 ± 3 %]",
      "positive; 1e9 DN per unit saturates any ADC at any useful light",
      [](Rig& r) { return std::span<double>(r.four_camera.gain_DN); }), kFour), kSimulate, ""));
  keys.push_back(reads(only(array<RealRange{-65536.0, 65536.0}>(
      "device.cameras.offset_DN", "DN", "4 offsets", "offsets b_j of cameras 1–4, the dark level [C: about 20 DN]",
      "beyond a 16-bit ADC's range every pixel clips",
      [](Rig& r) { return std::span<double>(r.four_camera.offset_DN); }), kFour), kSimulate, ""));
  {
    constexpr RealRange kFocal{10.0, 100000.0};
    constexpr std::string_view why = "from a 10 px toy image to a long telephoto on a large sensor";
    keys.push_back(reads(only(array<kFocal>(
        "device.cameras.fx_px", "px", "4 focal lengths",
        "focal lengths f_x of cameras 1–4 in px [C: about 770 px, the equidistant lens's fit to W16's 77° × "
        "57.7° field; 3.5 mm / 4.65 µm = 752.7 px]",
        why, [](Rig& r) { return std::span<double>(r.four_camera.fx_px); }), kFour), kSimulate, ""));
    keys.push_back(reads(only(array<kFocal>(
        "device.cameras.fy_px", "px", "4 focal lengths", "focal lengths f_y of cameras 1–4 in px [C: as f_x, square pixels]",
        why, [](Rig& r) { return std::span<double>(r.four_camera.fy_px); }), kFour), kSimulate, ""));
  }
  {
    constexpr RealRange kCentre{-16384.0, 32768.0};
    constexpr std::string_view why = "a principal point lies near the image; beyond twice its largest size it is no lens";
    keys.push_back(reads(only(array<kCentre>(
        "device.cameras.cx_px", "px", "4 positions",
        "principal points c_x of cameras 1–4, pixel (col, row)'s centre at (col + ½, row + ½) [C: 517 ± 1.5]",
        why, [](Rig& r) { return std::span<double>(r.four_camera.cx_px); }), kFour), kSimulate, ""));
    keys.push_back(reads(only(array<kCentre>(
        "device.cameras.cy_px", "px", "4 positions", "principal points c_y of cameras 1–4 [C: 389 ± 1.5]",
        why, [](Rig& r) { return std::span<double>(r.four_camera.cy_px); }), kFour), kSimulate, ""));
  }
  {
    constexpr RealRange kKb{-1.0, 1.0};
    constexpr std::string_view why =
        "fisheye lenses' Kannala–Brandt coefficients are of order 0.01–0.1; a lens that folds its image is refused";
    keys.push_back(reads(only(array<kKb>(
        "device.cameras.k1", "", "4 coefficients",
        "Kannala–Brandt k1 of cameras 1–4: θ_d = θ(1 + k1θ² + k2θ⁴ + k3θ⁶ + k4θ⁸), OpenCV's fisheye [C: 0, equidistant]",
        why, [](Rig& r) { return std::span<double>(r.four_camera.k1); }), kFour), kSimulate, ""));
    keys.push_back(reads(only(array<kKb>(
        "device.cameras.k2", "", "4 coefficients", "Kannala–Brandt k2 of cameras 1–4 [C: 0]",
        why, [](Rig& r) { return std::span<double>(r.four_camera.k2); }), kFour), kSimulate, ""));
    keys.push_back(reads(only(array<kKb>(
        "device.cameras.k3", "", "4 coefficients", "Kannala–Brandt k3 of cameras 1–4 [C: 0]",
        why, [](Rig& r) { return std::span<double>(r.four_camera.k3); }), kFour), kSimulate, ""));
    keys.push_back(reads(only(array<kKb>(
        "device.cameras.k4", "", "4 coefficients", "Kannala–Brandt k4 of cameras 1–4 [C: 0]",
        why, [](Rig& r) { return std::span<double>(r.four_camera.k4); }), kFour), kSimulate, ""));
  }
  {
    constexpr RealRange kMisalign{-10.0, 10.0};
    constexpr std::string_view why =
        "cameras mounted with parallel axes (W16): misalignments of a few degrees at most; camera 1's must be 0";
    keys.push_back(reads(only(array<kMisalign>(
        "device.cameras.rot_x_deg", "deg", "4 angles",
        "x components of the rotation vectors of R_j1 (v_j = R_j1·v_1: camera 1's coordinates to camera j's, as "
        "OpenCV's stereo R) [C: 0, 0.3, −0.2, 0.15]",
        why, [](Rig& r) { return std::span<double>(r.four_camera.rot_x_deg); }), kFour), kSimulate, ""));
    keys.push_back(reads(only(array<kMisalign>(
        "device.cameras.rot_y_deg", "deg", "4 angles", "y components of R_j1's rotation vectors [C: 0, −0.15, 0.25, 0.2]",
        why, [](Rig& r) { return std::span<double>(r.four_camera.rot_y_deg); }), kFour), kSimulate, ""));
    keys.push_back(reads(only(array<kMisalign>(
        "device.cameras.rot_z_deg", "deg", "4 angles",
        "z components of R_j1's rotation vectors, a roll about the optical axis [C: 0, 0.5, −0.4, 0.3]",
        why, [](Rig& r) { return std::span<double>(r.four_camera.rot_z_deg); }), kFour), kSimulate, ""));
  }
  keys.push_back(reads(only(real<RealRange{0.0, 10000.0}>(
      "device.cameras.baseline_mm", "mm", "a length",
      "side of the square the cameras sit on (cameras 1–4 at (0,0), (a,0), (a,a), (0,a) in camera 1's X, Y); "
      "truth only: the sky is at infinity (spec §3.2) [C: 60 mm]",
      "0 (coincident) to 10 m", [](Rig& r) -> double& { return r.four_camera.baseline_mm; }), kFour), kSimulate, ""));
  keys.push_back(reads(only(boolean(
      "device.cameras.noise", "Poisson–Gaussian noise (shot and read noise) on every frame of every camera",
      [](Rig& r) -> bool& { return r.four_camera.noise; }), kFour), kSimulate, ""));
  keys.push_back(reads(only(real<RealRange{0.0, 1e6, true, false}>(
      "device.cameras.electrons_per_DN", "e/DN", "a conversion gain",
      "shot noise: a signal of s DN holds s·electrons_per_DN electrons [C: 10]",
      "image sensors' conversion gains lie around 0.1–100 e⁻/DN; 1e6 is noise-free in practice",
      [](Rig& r) -> double& { return r.four_camera.electrons_per_DN; }), kFour), kSimulate, ""));
  keys.push_back(reads(only(real<RealRange{0.0, 1e4}>(
      "device.cameras.read_noise_DN", "DN", "a standard deviation", "Gaussian read noise per pixel and frame [C: 1]",
      "more than 1e4 DN buries a 12-bit camera's whole range",
      [](Rig& r) -> double& { return r.four_camera.read_noise_DN; }), kFour), kSimulate, ""));
  keys.push_back(reads(only(integer(
      "device.cameras.adc_bits", "an integer in [1, 16]", "the cameras' ADC depth: raw values 0 … 2^bits − 1 (GC1031CP: 8 or 12)",
      "cameras digitise to 8–16 bits; a raw frame holds 16-bit values",
      [](Rig& r) -> int& { return r.four_camera.adc_bits; }, &integer_within<1, 16>), kFour), kSimulate | kCalibrate, ""));
  // --- checkerboard (geometry/checkerboard.h, sim/checkerboard.h): the target of the four cameras'
  // geometric calibration (spec §3.3 item 3), rendered by `polrig simulate` into DIR/checkerboard/.
  keys.push_back(reads(only(integer(
      "checkerboard.views", "an integer in [0, 10000]",
      "checkerboard poses rendered for the geometric calibration (DIR/checkerboard/view_NNNN.exr; 0: none)",
      "OpenCV's calibration wants some 10–50 views; 10000 bounds the dataset (one view is four frames)",
      [](Rig& r) -> int& { return r.checkerboard.views; }, &integer_within<0, 10000>), kFour), kSimulate, ""));
  keys.push_back(reads(only(integer(
      "checkerboard.inner_cols", "an integer in [3, 100]",
      "inner corners along a row of the board (OpenCV's pattern width) [C: 9]",
      "cv::findChessboardCorners needs at least 3; 100 is beyond any printed target's use",
      [](Rig& r) -> int& { return r.checkerboard.inner_corners[0]; }, &integer_within<3, 100>), kFour), kSimulate, ""));
  keys.push_back(reads(only(integer(
      "checkerboard.inner_rows", "an integer in [3, 100]",
      "inner corners along a column of the board; must differ from inner_cols (a square grid's corner order "
      "is ambiguous) [C: 6]",
      "cv::findChessboardCorners needs at least 3; 100 is beyond any printed target's use",
      [](Rig& r) -> int& { return r.checkerboard.inner_corners[1]; }, &integer_within<3, 100>), kFour), kSimulate, ""));
  keys.push_back(reads(only(real<RealRange{0.1, 1000.0}>(
      "checkerboard.square_mm", "mm", "a length", "side of one square [C: 30]",
      "from a millimetre-sized printed target to a metre-sized board",
      [](Rig& r) -> double& { return r.checkerboard.square_mm; }), kFour), kSimulate, ""));
  keys.push_back(reads(only(real<RealRange{0.0, 1000.0, true, false}>(
      "checkerboard.margin_mm", "mm", "a length",
      "the white border around the squares (cv::findChessboardCorners needs one) [C: 30]",
      "positive: without a border the outer squares merge into the wall; beyond 1 m it is no border",
      [](Rig& r) -> double& { return r.checkerboard.margin_mm; }), kFour), kSimulate, ""));
  keys.push_back(reads(only(array<RealRange{1.0, 100000.0}>(
      "checkerboard.distance_mm", "mm", "2 depths",
      "[near, far]: the board centre's depth along camera 1's axis, uniform between them [C: 450, 800]",
      "in front of the cameras (1 mm) to 100 m, where no board of the kind resolves",
      [](Rig& r) { return std::span<double>(r.checkerboard.distance_mm); }), kFour), kSimulate, ""));
  keys.push_back(reads(only(real<RealRange{0.0, 80.0}>(
      "checkerboard.tilt_max_deg", "deg", "an angle",
      "the largest angle of the board's normal from camera 1's axis, uniform in [0, max]: tilts make the focal "
      "length and distortion observable [C: 35]",
      "beyond 80° the board is seen nearly edge-on and its corners cannot be found",
      [](Rig& r) -> double& { return r.checkerboard.tilt_max_deg; }), kFour), kSimulate, ""));
  keys.push_back(reads(only(real<RealRange{0.0, 45.0}>(
      "checkerboard.roll_max_deg", "deg", "an angle", "the largest turn of the board about its normal, uniform in "
      "[−max, max] [C: 15]",
      "beyond 45° a row of corners may run closer to the image's columns than to its rows, and the corner order "
      "(first corner left of the last) becomes ambiguous",
      [](Rig& r) -> double& { return r.checkerboard.roll_max_deg; }), kFour), kSimulate, ""));
  keys.push_back(reads(only(array<RealRange{0.0, 1000.0}>(
      "checkerboard.intensity", "", "3 intensities",
      "[white, black, wall]: I of the white squares and margin, of the black squares and of the wall behind, in "
      "the source's intensity units (unpolarized: f_j = K_j·I + b_j) [C: 2.5, 0.15, 0.6]",
      "non-negative; 1000 units saturate any ADC at the cameras' gains",
      [](Rig& r) { return std::span<double>(r.checkerboard.intensity); }), kFour), kSimulate, ""));
  // --- device.kind unit-array (device/unit_array.h; spec sky-and-compasses.md §4.1–4.2): Z21's
  // units, each a six-photodiode sensor (device.truth.*, electronics.*, schedule.samples_per_stop).
  {
    const auto list = [&](std::string_view path, std::string_view unit, std::string_view noun, RealRange r,
                          std::string_view doc, std::string_view why, std::vector<double>& (*ref)(Rig&),
                          bool (*valid)(double)) {
      RigKey k{path, K::RealList, unit, expects_text(noun, r, unit), doc, why};
      k.list = ref;
      k.range = r;
      k.max_items = 64;
      k.valid_real = valid;
      keys.push_back(reads(only(k, kUnits), kSimulate, ""));
    };
    constexpr RealRange kTilt{0.0, 90.0}, kError{-10.0, 10.0};
    keys.push_back(reads(only(boolean(
        "device.units.zenith", "a unit looking along Z_b (up), unit 0, the layout's middle unit [C: true]",
        [](Rig& r) -> bool& { return r.units.zenith_unit; }), kUnits), kSimulate, ""));
    keys.push_back(reads(only(real<kTilt>(
        "device.units.ring_tilt_deg", "deg", "an angle", "tilt β of the ring units' views from Z_b [C: 30]",
        "0 is the zenith; beyond 90° a unit looks below the body's horizon",
        [](Rig& r) -> double& { return r.units.ring_tilt_deg; }), kUnits), kSimulate, ""));
    list("device.units.ring_azimuths_deg", "deg", "a list of up to 64 angles", kTurn,
         "azimuths of the ring units' views, from X_b (right) towards Y_b (forward), after the zenith unit "
         "[C: 0, 45, …, 315]",
         "an orientation: one turn either way; 64 units is beyond any compass of the kind",
         [](Rig& r) -> std::vector<double>& { return r.units.ring_azimuths_deg; }, &within<kTurn>);
    list("device.units.tilt_deg", "deg", "a list of up to 64 angles", kTilt,
         "an explicit layout (replaces device.units.zenith and the ring): each unit's tilt β from Z_b",
         "0 is the zenith; beyond 90° a unit looks below the body's horizon",
         [](Rig& r) -> std::vector<double>& { return r.units.tilt_deg; }, &within<kTilt>);
    list("device.units.azimuth_deg", "deg", "a list of up to 64 angles", kTurn,
         "an explicit layout: each unit's azimuth a, from X_b towards Y_b (one per tilt)",
         "an orientation: one turn either way",
         [](Rig& r) -> std::vector<double>& { return r.units.azimuth_deg; }, &within<kTurn>);
    list("device.units.roll_deg", "deg", "a list of up to 64 angles", kTurn,
         "an explicit layout: each unit's roll ρ about its own view, C_m^b = Rz(a)·Ry(β)·Rz(ρ) (one per tilt; "
         "none: 0)",
         "an orientation: one turn either way",
         [](Rig& r) -> std::vector<double>& { return r.units.roll_deg; }, &within<kTurn>);
    keys.push_back(reads(only(real<RealRange{0.0, 10.0}>(
        "device.units.mount_error_sd_deg", "deg", "a standard deviation",
        "σ of each unit's three mounting errors δ (about its own X, Y, Z), drawn with the rig's seed; truth only "
        "(Z21: E-vector errors of 1.2–4.6° before installation calibration) [C: 0]",
        "mounting errors are small angles: beyond 10° the unit is mounted elsewhere",
        [](Rig& r) -> double& { return r.units.mount_error_sd_deg; }), kUnits), kSimulate, ""));
    for (std::size_t a = 0; a < 3; ++a) {
      static constexpr std::array<std::string_view, 3> paths{"device.units.mount_error_x_deg",
                                                             "device.units.mount_error_y_deg",
                                                             "device.units.mount_error_z_deg"};
      static constexpr std::array<std::string_view, 3> docs{
          "explicit mounting errors δ_x (about each unit's X_m), one per unit; replace the draw of this axis",
          "explicit mounting errors δ_y (about each unit's Y_m), one per unit; replace the draw of this axis",
          "explicit mounting errors δ_z (about each unit's view Z_m: a turn of its zero direction), one per "
          "unit; replace the draw of this axis"};
      list(paths[a], "deg", "a list of up to 64 angles", kError, docs[a],
           "mounting errors are small angles: beyond 10° the unit is mounted elsewhere",
           a == 0   ? +[](Rig& r) -> std::vector<double>& { return r.units.mount_error_x_deg; }
           : a == 1 ? +[](Rig& r) -> std::vector<double>& { return r.units.mount_error_y_deg; }
                    : +[](Rig& r) -> std::vector<double>& { return r.units.mount_error_z_deg; },
           &within<kError>);
    }
    keys.push_back(reads(only(array<kError>(
        "device.units.misalignment_deg", "deg", "3 angles",
        "the compass's misalignment μ to the body, about X_b, Y_b, Z_b: C_m^b,true = Rx·Ry·Rz(μ)·C_m^b·…; truth only "
        "[C: 0, 0, 0]",
        "a misalignment is a small angle: beyond 10° the compass is mounted otherwise",
        [](Rig& r) { return std::span<double>(r.units.misalignment_deg); }), kUnits), kSimulate, ""));
    RigKey k{"device.units.apply", K::Text, "", "truth or theory",
             "the calibration model each unit's voltages are read with (polrig apply): truth, its own "
             "device.truth (a perfectly calibrated unit), or theory, the nominal parameters of device.film_axes_deg"};
    k.text = [](Rig& r) -> std::string& { return r.units.apply; };
    k.valid_text = [](std::string_view v) { return v == "truth" || v == "theory"; };
    keys.push_back(reads(only(k, kUnits), kSimulate, ""));
  }
  add_ins_keys(keys);
  {
    RigKey k{"source.model", K::Text, "", kinds_text(),
             "source model: cos4 is the analytic E_0·cos⁴φ port; traced is the Embree-traced "
             "sphere of source.scene; sky is the Rayleigh sky of the sky.* keys (outdoors)"};
    k.text = [](Rig& r) -> std::string& { return r.source.model; };
    k.valid_text = [](std::string_view v) {
      for (std::string_view kind : source_kinds())
        if (v == kind) return true;
      return false;
    };
    keys.push_back(reads(k, kSimulate | kCs, ""));
  }
  {
    RigKey k{"source.scene", K::Text, "", "a path to a scene file",
             "traced: the scene (scenes/*.yaml), relative to the rig file; its port film gives "
             "the light's d and angle"};
    k.text = [](Rig& r) -> std::string& { return r.source.scene; };
    k.valid_text = [](std::string_view v) { return !v.empty(); };
    keys.push_back(reads(k, kSimulate | kCs, "traced"));
  }
  keys.push_back(reads(real<RealRange{0.1, 1000.0}>(
      "source.L_o", "mm", "a length",
      "distance from the port plane down to the photosensitive plane",
      "the paper's is 20 mm; at 0 the cos⁴ law gives no light off-axis, beyond 1 m the port is "
      "a point",
      [](Rig& r) -> double& { return r.source.cos4.L_o; }), kSimulate | kCs, ""));
  keys.back().instruments = kSix;  // the camera's port fills its view: no eccentricity, no L_o
  keys.push_back(reads(real<RealRange{1e-3, 1e5}>(
      "source.E_0", "W/m^2", "an irradiance",
      "irradiance on the port axis at the photosensitive plane",
      "from dim laboratory light to a hundred suns",
      [](Rig& r) -> double& { return r.source.cos4.E_0; }), kSimulate | kCalibrate, "cos4"));
  keys.push_back(reads(real<kTurn>("source.polarizer_deg", "deg", "an angle",
                             "axis ψ_P of the port polarizer in the rig frame; θ = θ_R − ψ_P",
                             kTurnWhy, [](Rig& r) -> double& { return r.source.polarizer_deg; }), kSimulate, "cos4"));
  // --- sky (source.model: sky; docs/physics.md §10) ------------------------------------
  const auto sky_text = [&](std::string_view path, std::string_view expects, std::string_view doc,
                            std::string& (*ref)(Rig&), bool (*valid)(std::string_view),
                            unsigned studies) {
    RigKey k{path, K::Text, "", std::string(expects), doc};
    k.text = ref;
    k.valid_text = valid;
    keys.push_back(reads(k, studies, "sky"));
  };
  keys.push_back(reads(real<RealRange{-90.0, 90.0}>(
      "sky.lat_deg", "deg", "a latitude", "the site's geodetic latitude, north positive",
      "the poles bound latitude (W19's roof in Dalian: 38.879167°)",
      [](Rig& r) -> double& { return r.source.sky.sky.site.lat_deg; }), kSimulate | kCalibrate, "sky"));
  keys.push_back(reads(real<RealRange{-180.0, 180.0}>(
      "sky.lon_deg", "deg", "a longitude", "the site's longitude, east positive",
      "one turn of longitude (W19's roof: 121.543889°)",
      [](Rig& r) -> double& { return r.source.sky.sky.site.lon_deg; }), kSimulate | kCalibrate, "sky"));
  keys.push_back(reads(real<RealRange{-500.0, 9000.0}>(
      "sky.height_m", "m", "a height", "the site's height above the WGS-84 ellipsoid",
      "from the Dead Sea shore to above Everest",
      [](Rig& r) -> double& { return r.source.sky.sky.site.height_m; }), kSimulate, "sky"));
  sky_text("sky.first_stop_utc", "an ISO 8601 UTC time with Z",
           "time of the first table stop (UTC; W19 gives Beijing time, UTC+8); stop k is "
           "schedule-timed after it",
           [](Rig& r) -> std::string& { return r.source.sky.first_stop_utc; },
           [](std::string_view v) {
             try {
               parse_utc(v);
               return true;
             } catch (const std::invalid_argument&) {
               return false;
             }
           },
           kSimulate | kCalibrate);
  keys.push_back(reads(real<RealRange{-0.9, 0.9}>(
      "sky.ut1_minus_utc_s", "s", "a time difference", "UT1 − UTC (IERS Bulletin A)",
      "UTC is kept within 0.9 s of UT1 by leap seconds",
      [](Rig& r) -> double& { return r.source.sky.sky.sun.ut1_minus_utc_s; }), kSimulate, "sky"));
  sky_text("sky.refraction", "off or on", "atmospheric refraction of the sun's elevation (spec §1.1)",
           [](Rig& r) -> std::string& { return r.source.sky.refraction; },
           [](std::string_view v) { return v == "off" || v == "on"; }, kSimulate);
  keys.push_back(reads(real<RealRange{0.0, 1.0, true, false}>(
      "sky.p_max", "", "a degree of polarization",
      "P_max of the single-scattering sky, P = P_max·sin²γ/(1 + cos²γ)",
      "near 0 a nearly unpolarized sky, 1 the single-scattering limit (clear skies: 0.65–0.75)",
      [](Rig& r) -> double& { return r.source.sky.sky.model.P_max.constant; }), kSimulate, "sky"));
  keys.back().sky_models = kSingleScattering;
  for (const bool values : {false, true}) {
    constexpr RealRange kElevation{-90.0, 90.0}, kPmax{0.0, 1.0, true, false};
    RigKey k{values ? "sky.p_max_table" : "sky.p_max_table_elevation_deg", K::RealList,
             values ? "" : "deg",
             values ? expects_text("a list of degrees of polarization", kPmax, "")
                    : expects_text("a rising list of elevations", kElevation, "deg"),
             values ? "P_max at each elevation of sky.p_max_table_elevation_deg (replaces "
                      "sky.p_max; linear between, constant beyond)"
                    : "sun elevations h_s of a P_max(h_s) table (spec §1.2: one P_max cannot fit "
                      "every elevation)",
             values ? "as sky.p_max" : "the sun's elevation"};
    if (values) k.list = [](Rig& r) -> std::vector<double>& { return r.source.sky.p_max_table; };
    else k.list = [](Rig& r) -> std::vector<double>& { return r.source.sky.p_max_table_elevation_deg; };
    k.range = values ? kPmax : kElevation;
    k.max_items = 1000;
    k.valid_real = values ? &within<kPmax> : &within<kElevation>;
    k.sky_models = kSingleScattering;
    keys.push_back(reads(k, kSimulate, "sky"));
  }
  sky_text("sky.radiance", "uniform, rayleigh or cie-clear", "the sky's radiance model (spec §1.2)",
           [](Rig& r) -> std::string& { return r.source.sky.radiance; },
           [](std::string_view v) { return v == "uniform" || v == "rayleigh" || v == "cie-clear"; },
           kSimulate);
  keys.back().sky_models = kSingleScattering;
  add_vector_rt_keys(keys);
  keys.push_back(reads(real<kTurn>(
      "sky.mount_deg", "deg", "an angle",
      "geographic azimuth (clockwise from north) of the sensor's 0° axis at table angle 0",
      kTurnWhy, [](Rig& r) -> double& { return r.source.sky.mount.mount_deg; }), kSimulate, "sky"));
  keys.push_back(reads(real<RealRange{-90.0, 90.0}>(
      "sky.roll_deg", "deg", "an angle",
      "the table's tilt about the sensor's 90° axis at θ_R = 0 (its 0° axis down for > 0)",
      "a quarter turn either way: beyond it the sensor looks below the horizon",
      [](Rig& r) -> double& { return r.source.sky.mount.roll_deg; }), kSimulate, "sky"));
  keys.push_back(reads(real<RealRange{-90.0, 90.0}>(
      "sky.pitch_deg", "deg", "an angle",
      "the table's tilt about the sensor's 0° axis at θ_R = 0 (its 90° axis up for > 0)",
      "a quarter turn either way: beyond it the sensor looks below the horizon",
      [](Rig& r) -> double& { return r.source.sky.mount.pitch_deg; }), kSimulate, "sky"));
  keys.push_back(reads(real<RealRange{-86400.0, 86400.0}>(
      "sky.time_offset_s", "s", "a time difference",
      "true time of each stop minus its nominal time (a clock error): the sky is seen then",
      "a clock off by up to a day",
      [](Rig& r) -> double& { return r.source.sky.mount.time_offset_s; }), kSimulate, "sky"));
  sky_text("sky.field", "point or cone",
           "a point sample along the sensor's axis, or the lens's cone (spec §1.3)",
           [](Rig& r) -> std::string& { return r.source.sky.field; },
           [](std::string_view v) { return v == "point" || v == "cone"; }, kSimulate);
  keys.back().instruments = kSix;  // a photodiode's view; a camera's pixels each have their own ray
  keys.push_back(reads(real<RealRange{0.0, 10.0, true, false}>(
      "sky.field_half_angle_deg", "deg", "an angle",
      "half-angle of the lens's cone, atan(0.65 mm/50 mm) = 0.74475° (spec §1.3)",
      "a photodiode at the focus of a lens sees a few degrees at most",
      [](Rig& r) -> double& { return r.source.sky.mount.field_half_angle_deg; }), kSimulate, "sky"));
  keys.back().instruments = kSix;
  keys.push_back(reads(real<RealRange{1e-7, 1e5}>(
      "sky.E_0", "W/m^2", "an irradiance",
      "each channel's irradiance (a camera: each pixel's intensity S0) for the sky's radiance 1 "
      "(the zenith of a uniform sky)",
      "W19's log amplifier covers 1.46e-5 to 14.64 W/m²; from deep twilight to a hundred suns",
      [](Rig& r) -> double& { return r.source.sky.mount.E0_Wm2; }), kSimulate, "sky"));
  // --- eccentricity -------------------------------------------------------------------
  keys.push_back(reads(real<kOffset>("eccentricity.L_IS", "mm", "a length",
                               "offset of the port centre O_IS from the table centre O_R",
                               kOffsetWhy, [](Rig& r) -> double& { return r.eccentricity.L_IS; }), kSimulate | kCs, ""));
  keys.back().instruments = kSix;  // the camera's port fills its view: no eccentricity, no L_o
  keys.push_back(reads(real<kTurn>("eccentricity.alpha_IS", "deg", "an angle",
                             "direction of the port centre's offset", kTurnWhy,
                             [](Rig& r) -> double& { return r.eccentricity.alpha_IS; }), kSimulate | kCs, ""));
  keys.back().instruments = kSix;  // the camera's port fills its view: no eccentricity, no L_o
  keys.push_back(reads(real<kOffset>("eccentricity.L_S", "mm", "a length",
                               "offset of the sensor centre O_S from O_R at θ_R = 0", kOffsetWhy,
                               [](Rig& r) -> double& { return r.eccentricity.L_S; }), kSimulate | kCs, ""));
  keys.back().instruments = kSix;  // the camera's port fills its view: no eccentricity, no L_o
  keys.push_back(reads(real<kTurn>("eccentricity.alpha_S", "deg", "an angle",
                             "direction of the sensor centre's offset at θ_R = 0", kTurnWhy,
                             [](Rig& r) -> double& { return r.eccentricity.alpha_S; }), kSimulate | kCs, ""));
  keys.back().instruments = kSix;  // the camera's port fills its view: no eccentricity, no L_o
  // --- schedule -----------------------------------------------------------------------
  keys.push_back(reads(real<kTableAngle>("schedule.start_deg", "deg", "an angle", "first table stop",
                                   kTableWhy,
                                   [](Rig& r) -> double& { return r.schedule.start_deg; }), kSimulate, ""));
  keys.push_back(reads(real<RealRange{0.0, 360.0}>(
      "schedule.step_deg", "deg", "a step", "table step between stops (0 only with schedule.count)",
      "at most one turn; the stops between start and stop may number at most 1e6",
      [](Rig& r) -> double& { return r.schedule.step_deg; }), kSimulate, ""));
  keys.push_back(reads(real<kTableAngle>("schedule.stop_deg", "deg", "an angle ≥ schedule.start_deg",
                                   "last table stop (included when reached by whole steps)",
                                   kTableWhy, [](Rig& r) -> double& { return r.schedule.stop_deg; }), kSimulate, ""));
  keys.push_back(reads(integer(
      "schedule.count", "an integer in [0, 1000000]",
      "number of stops start + k·step, k < count (replaces schedule.stop_deg; step may be 0: a static time "
      "series at one table angle, W16's 1 Hz hour); 0: unset, the stops run up to schedule.stop_deg",
      "at most 1e6 stops, as for start/step/stop",
      [](Rig& r) -> int& { return r.schedule.count; }, &integer_within<0, 1000000>), kSimulate, ""));
  {
    RigKey k{"schedule.angles_deg", K::RealList, "deg",
             expects_text("a list of 1 to 1e6 angles", kTableAngle, "deg"),
             "explicit table stops; replaces start/step/stop (give one or the other)",
             "ten turns of the table either way; at most 1e6 stops, as for start/step/stop"};
    k.list = [](Rig& r) -> std::vector<double>& { return r.schedule.angles_deg; };
    k.range = kTableAngle;
    k.max_items = kMaxStops;
    k.valid_real = &within<kTableAngle>;
    keys.push_back(reads(k, kSimulate, ""));
  }
  {
    RigKey k{"schedule.samples_per_stop", K::Integer, "", "an integer in [1, 100000]",
             "samples the sensor records at each stop (the paper averages 40)"};
    k.integer = [](Rig& r) -> int& { return r.schedule.samples_per_stop; };
    k.valid_integer = [](long long v) { return v >= 1 && v <= 100000; };
    keys.push_back(reads(only(k, kSixAndUnits), kSimulate, ""));
  }
  keys.push_back(reads(real<RealRange{0.01, 1000.0}>(
      "schedule.speed_deg_s", "deg/s", "a speed",
      "the table's turning speed between stops (times the stops of a time-dependent source)",
      "from a slow hand-turned table (0.01°/s) to a fast motorised one (1000°/s); the paper's 10° "
      "steps at 3 s per stop suggest 5°/s with 1 s of dwell",
      [](Rig& r) -> double& { return r.schedule.speed_deg_s; }), kSimulate, ""));
  keys.push_back(reads(real<RealRange{0.0, 3600.0}>(
      "schedule.dwell_s", "s", "a duration",
      "time the table rests at each stop while the sensor records",
      "0 (no rest) to an hour per stop",
      [](Rig& r) -> double& { return r.schedule.dwell_s; }), kSimulate, ""));
  // A camera's stops (geometry/schedule.h; H17 §4.1, spec §2.4): step 1's unpolarized levels,
  // then every table angle at each polarized intensity.
  for (const bool levels : {true, false}) {
    constexpr RealRange kLevel{0.0, 100.0}, kIntensity{0.0, 100.0, true, false};
    RigKey k{levels ? "schedule.unpolarized_levels" : "schedule.intensities", K::RealList, "",
             levels ? expects_text("a list of 1 to 10000 relative intensities", kLevel, "")
                    : expects_text("a list of 1 to 10000 relative intensities", kIntensity, ""),
             levels ? "step 1: one unpolarized stop (polarizer out, table at its first stop) per "
                      "level, relative to the source's level (H17: 0 to 1720 cd/m² in about 60 "
                      "cd/m² steps)"
                    : "step 2: the polarized intensities, relative to the source's level; every "
                      "table stop at each (H17: 1, 0.5, 0.25, 0.1, 0.05, 0.025)",
             levels ? "0 is dark; a hundredfold the source's level saturates any exposure set for it"
                    : "a polarized frame needs light; a hundredfold the source's level saturates "
                      "any exposure set for it"};
    if (levels) k.list = [](Rig& r) -> std::vector<double>& { return r.schedule.unpolarized_levels; };
    else k.list = [](Rig& r) -> std::vector<double>& { return r.schedule.intensities; };
    k.range = levels ? kLevel : kIntensity;
    k.max_items = 10000;
    k.valid_real = levels ? &within<kLevel> : &within<kIntensity>;
    keys.push_back(reads(only(k, kCameras), kSimulate, ""));
  }
  keys.push_back(reads(only(integer(
      "schedule.frames_per_stop", "an integer in [1, 999]",
      "frames the camera exposes at each stop (H17: 5 per step-1 level, 1 per position)",
      "H17 averages 5; 999 frames is 12 s of video at 80 fps (and the dataset's channels raw.000 … "
      "raw.998 keep their order)",
      [](Rig& r) -> int& { return r.schedule.frames_per_stop; }, &integer_within<1, 999>), kCamera),
      kSimulate, ""));
  // --- electronics --------------------------------------------------------------------
  keys.push_back(reads(real<RealRange{0.01, 10.0}>(
      "electronics.volts_per_decade", "V", "a gain", "log-amplifier scale (the 0.5 of Eq. 1)",
      "log amplifiers give tens to thousands of mV per decade (the paper's: 500 mV)",
      [](Rig& r) -> double& { return r.electronics.volts_per_decade; }), kSimulate | kCs | kAdc | kCalibrate, ""));
  {
    RigKey k{"electronics.adc_bits", K::Integer, "", "an integer in [2, 31]",
             "resolution of the signed ADC (Eq. 3 uses 2^(bits−1))"};
    k.integer = [](Rig& r) -> int& { return r.electronics.adc_bits; };
    k.valid_integer = [](long long v) { return v >= 2 && v <= 31; };
    keys.push_back(reads(k, kSimulate | kAdc, ""));
  }
  keys.push_back(reads(real<RealRange{0.01, 100.0}>(
      "electronics.vref_V", "V", "a voltage", "ADC reference voltage",
      "ADC references span tens of mV to tens of volts (the paper's: 0.6 V)",
      [](Rig& r) -> double& { return r.electronics.vref_V; }), kSimulate | kAdc, ""));
  keys.push_back(reads(real<RealRange{0.0, 1.0}>(
      "electronics.noise_sigma_V", "V", "a standard deviation",
      "Gaussian noise on each pair voltage, per sample, before the ADC",
      "noise of more than 1 V buries any log amplifier's signal (our rigs: 0.1 mV)",
      [](Rig& r) -> double& { return r.electronics.noise_sigma_V; }), kSimulate, ""));
  // The log amplifiers and the signed ADC are the six-photodiode sensor's (the camera's own ADC
  // and noise are device.* keys).
  for (RigKey& k : keys)
    if (k.path.starts_with("electronics.")) k.instruments = kSixAndUnits;
  // --- seed ---------------------------------------------------------------------------
  {
    RigKey k{"seed", K::Seed, "", "an unsigned 64-bit integer",
             "seed of every random stream; streams derive from (seed, stop, channel, sample)"};
    k.seed = [](Rig& r) -> std::uint64_t& { return r.seed; };
    keys.push_back(reads(k, kSimulate, ""));
  }
  return keys;
}

}  // namespace

const std::vector<RigKey>& rig_keys() {
  static const std::vector<RigKey> keys = make_keys();
  return keys;
}

namespace {
// Whether `name` is one of the space-separated names of `list` (every name when it is empty).
bool listed(std::string_view list, std::string_view name) {
  if (list.empty()) return true;
  for (std::size_t b = 0; b < list.size();) {
    const std::size_t e = std::min(list.find(' ', b), list.size());
    if (list.substr(b, e - b) == name) return true;
    b = e + 1;
  }
  return false;
}
}  // namespace

bool RigKey::read_by_source(std::string_view model) const { return listed(sources, model); }
bool RigKey::read_by_instrument(std::string_view kind) const { return listed(instruments, kind); }
bool RigKey::read_by_sky_model(std::string_view model) const { return listed(sky_models, model); }

std::string RigKey::studies_text() const {
  std::string out;
  for (const auto& [bit, name] : {std::pair{kSimulate, "simulate"}, {kCs, "cs"}, {kAdc, "adc"}, {kCalibrate, "calibrate"},
                                                {kNavigate, "navigate"}})
    if (studies & bit) out += (out.empty() ? "" : ", ") + std::string(name);
  return out;
}

const RigKey* find_rig_key(std::string_view path) {
  for (const RigKey& k : rig_keys())
    if (k.path == path) return &k;
  return nullptr;
}

namespace {
// Whether n is within 1e-9 (relative) of a positive whole number.
bool whole(double n) { return n >= 0.5 && std::abs(n - std::round(n)) <= 1e-9 * std::max(1.0, n); }

// A unit array's run (rig/ins_settings.h): under the sky, a whole number of IMU intervals per
// compass reading and per segment, one motion per segment, the speed never negative and the pitch
// within ±80° along the way, and at most 2e6 IMU samples (a run's truth and IMU are held in memory).
std::optional<RigProblem> unit_array_run_problem(const Rig& rig, RigUse use) {
  if (rig.source.model != "sky")
    return RigProblem{"source.model", fmt::format("expected sky for device.kind unit-array (its units read the "
                                                  "sky), got '{}'", rig.source.model), "device.kind"};
  if (std::abs(rig.source.sky.sky.site.lat_deg) > kInsMaxLatitudeDeg)
    return RigProblem{"sky.lat_deg", fmt::format("expected a latitude within ±{}° for device.kind unit-array (its "
                                                 "INS's local-level frame is singular at the poles), got {}",
                                                 kInsMaxLatitudeDeg, rig.source.sky.sky.site.lat_deg), "device.kind"};
  if (rig.navigation.measurement == "pns-fix" && rig.navigation.pns_level != "accelerometer")
    return RigProblem{"navigation.pns_level",
                      fmt::format("expected accelerometer with navigation.measurement pns-fix (the filter's fixes are "
                                  "levelled by the accelerometers, independent of its own attitude), got '{}'",
                                  rig.navigation.pns_level),
                      "navigation.measurement"};
  if (rig.navigation.measurement != "elevation-z21" && rig.navigation.measurement != "pns-fix" &&
      rig.navigation.integrated_level == "accelerometer")
    return RigProblem{"navigation.measurement",
                      "expected elevation-z21 with navigation.integrated_level accelerometer (the tilt columns and "
                      "the azimuth model the filter's attitude in the measured sun, which the accelerometers' level "
                      "leaves out)",
                      "navigation.integrated_level"};
  if (rig.navigation.zupt)
    for (const auto& [path, noise] : {std::pair{"imu.gyro.arw_deg_rt_h", &rig.imu.gyro.white_noise},
                                      {"imu.accel.vrw_ug_rt_hz", &rig.imu.accel.white_noise}})
      if (!(std::min({(*noise)[0], (*noise)[1], (*noise)[2]}) > 0))
        return RigProblem{path, fmt::format("expected a positive density on every axis with navigation.zupt true (the "
                                            "rest detector weighs each axis by its white noise), got [{}, {}, {}]",
                                            (*noise)[0], (*noise)[1], (*noise)[2]), "navigation.zupt"};
  const TrajectorySettings& t = rig.trajectory;
  const std::size_t n = t.segment_s.size();
  for (const auto& [path, list] : {std::pair{"trajectory.segment_accel_mps2", &t.segment_accel_mps2},
                                   {"trajectory.segment_turn_deg_s", &t.segment_turn_deg_s},
                                   {"trajectory.segment_climb_deg_s", &t.segment_climb_deg_s}})
    if (!list->empty() && list->size() != n)
      return RigProblem{path, fmt::format("expected one value per segment of trajectory.segment_s ({}), got {}", n,
                                          list->size()), "trajectory.segment_s"};
  if (use == RigUse::ReadDataset) return std::nullopt;  // the rest: a simulated run's own rules
  const double imu_hz = rig.imu.rate_hz;
  if (!whole(imu_hz / rig.units.rate_hz))
    return RigProblem{"device.units.rate_hz", fmt::format("expected a rate that divides imu.rate_hz ({} Hz) into a "
                                                          "whole number of IMU samples, got {} Hz", imu_hz, rig.units.rate_hz),
                      "imu.rate_hz"};
  const auto at = [](const std::vector<double>& v, std::size_t i) { return v.empty() ? 0.0 : v[i]; };
  double u = t.speed_mps, pitch = t.pitch_deg, total = 0;
  for (std::size_t i = 0; i < std::max<std::size_t>(n, 1); ++i) {
    const double d = n == 0 ? t.duration_s : t.segment_s[i];
    const std::string path = n == 0 ? "trajectory.duration_s" : "trajectory.segment_s";
    if (!whole(d * imu_hz))
      return RigProblem{path, fmt::format("expected a whole number of IMU intervals (1/{} s) per segment, got {} s "
                                          "(segment {})", imu_hz, d, i + 1), "imu.rate_hz"};
    const double a = at(t.segment_accel_mps2, i), w = at(t.segment_turn_deg_s, i), c = at(t.segment_climb_deg_s, i);
    if (int(a != 0) + int(w != 0) + int(c != 0) > 1)
      return RigProblem{"trajectory.segment_accel_mps2", fmt::format("expected one motion per segment (an acceleration, "
                                                                     "a turn or a climb), segment {} has {} m/s², {}°/s "
                                                                     "and {}°/s", i + 1, a, w, c)};
    u += a * d;
    pitch += c * d;
    total += d;
    if (u < -1e-9)
      return RigProblem{"trajectory.segment_accel_mps2", fmt::format("expected a speed ≥ 0 throughout, segment {} ends "
                                                                     "at {} m/s", i + 1, u)};
    if (std::abs(pitch) > 80)
      return RigProblem{"trajectory.segment_climb_deg_s", fmt::format("expected the pitch within ±80°, segment {} ends "
                                                                      "at {}°", i + 1, pitch)};
  }
  if (total * imu_hz > 2e6)
    return RigProblem{"imu.rate_hz", fmt::format("expected at most 2e6 IMU samples in a run, got {:.0f} ({} s at {} Hz)",
                                                 total * imu_hz, total, imu_hz)};
  return std::nullopt;
}
}  // namespace

std::optional<RigProblem> check_rig(const Rig& rig, RigUse use) {
  const Schedule& s = rig.schedule;
  if (s.angles_deg.size() > kMaxStops)
    return RigProblem{"schedule.angles_deg",
                      fmt::format("expected at most 1e6 stops, got {}", s.angles_deg.size())};
  if (s.angles_deg.empty() && s.count == 0 && !(s.step_deg > 0))
    return RigProblem{"schedule.step_deg",
                      fmt::format("expected a step > 0 without schedule.count, got {}", s.step_deg), "schedule.count"};
  if (s.angles_deg.empty() && s.count == 0) {
    if (s.stop_deg < s.start_deg)
      return RigProblem{"schedule.stop_deg",
                        fmt::format("expected an angle ≥ schedule.start_deg ({}), got {}",
                                    s.start_deg, s.stop_deg),
                        "schedule.start_deg"};
    if ((s.stop_deg - s.start_deg) / s.step_deg > kMaxStops)
      return RigProblem{"schedule.step_deg",
                        fmt::format("expected at most 1e6 stops, got {:.0f}",
                                    std::floor((s.stop_deg - s.start_deg) / s.step_deg) + 1)};
  }
  if (rig.instrument().has(Instrument::kFrames)) {
    // A camera's stops: every unpolarized level, then every table angle at each intensity.
    const double angles = !s.angles_deg.empty() ? static_cast<double>(s.angles_deg.size())
                          : s.count > 0       ? static_cast<double>(s.count)
                                              : std::floor((s.stop_deg - s.start_deg) / s.step_deg + 1e-9) + 1;
    const double stops = static_cast<double>(s.unpolarized_levels.size()) +
                         angles * static_cast<double>(s.intensities.size());
    if (stops > static_cast<double>(kMaxStops))
      return RigProblem{"schedule.intensities",
                        fmt::format("expected at most 1e6 camera stops (levels + angles × intensities), got {:.0f}",
                                    stops), "schedule.step_deg"};
  }
  if (rig.instrument().has(Instrument::kCameraArray)) {
    const FourCameraSpec& c = rig.four_camera;
    for (const auto& [path, v] : {std::pair{"device.cameras.rot_x_deg", c.rot_x_deg[0]},
                                  {"device.cameras.rot_y_deg", c.rot_y_deg[0]}, {"device.cameras.rot_z_deg", c.rot_z_deg[0]}})
      if (v != 0.0)
        return RigProblem{path, fmt::format("expected 0 for camera 1 (R_11 is the identity: camera 1 defines the "
                                            "frame), got {}", v)};
    const CheckerboardSpec& b = rig.checkerboard;
    if (b.inner_corners[0] == b.inner_corners[1])
      return RigProblem{"checkerboard.inner_rows",
                        fmt::format("expected a number of rows other than checkerboard.inner_cols ({}): a square "
                                    "grid's corner order is ambiguous", b.inner_corners[0]), "checkerboard.inner_cols"};
    if (b.distance_mm[0] > b.distance_mm[1])
      return RigProblem{"checkerboard.distance_mm",
                        fmt::format("expected [near, far] with near ≤ far, got [{}, {}]", b.distance_mm[0], b.distance_mm[1])};
    if (!(b.intensity[0] > b.intensity[1]))
      return RigProblem{"checkerboard.intensity",
                        fmt::format("expected the white squares brighter than the black ones, got white {} and black {}",
                                    b.intensity[0], b.intensity[1])};
  }
  if (rig.instrument().has(Instrument::kUnitArray)) {
    if (auto p = unit_array_problem(rig.units)) return RigProblem{p->path, p->message};
    if (auto p = unit_array_run_problem(rig, use)) return p;
  }
  for (int m = 0; m < 6 && rig.instrument().has(Instrument::kPairVoltages); ++m) {
    // Eq. 15's brackets must stay positive for every θ: (1+kd_m)·d < 1.
    if ((1.0 + rig.device.truth.kd[m]) * rig.device.d >= 1.0)
      return RigProblem{"device.d", fmt::format("expected (1+kd_{})·d < 1, got {}", m + 1,
                                                (1.0 + rig.device.truth.kd[m]) * rig.device.d)};
  }
  return std::nullopt;
}

bool written_for(const RigKey& key, const Rig& rig_in) {
  if (!key.read_by_source(rig_in.source.model)) return false;
  if (!key.read_by_instrument(rig_in.device_kind)) return false;
  if (rig_in.source.model == "sky" && !key.read_by_sky_model(rig_in.source.sky.model)) return false;
  if (key.path == "sky.rt.wavelength_nm" || key.path == "sky.rt.pressure_hPa")
    if (rig_in.source.sky.tau_rayleigh != "bodhaine") return false;
  if (key.path == "device.kind" && rig_in.device_kind == kDefaultDeviceKind) return false;
  // A source that sets the light's d itself (the traced port film, the sky at its first stop): the
  // file leaves device.d out and the parser derives it again, so that a --set of the source's keys
  // on a written rig.yaml (navigate --set sky.p_max=…) derives the new d instead of clashing.
  if (key.path == "device.d" && rig_in.light && rig_in.light->rig_degree_of_polarization(rig_in.source_view()))
    return false;
  // A rig without checkerboard views writes none of the board's keys.
  if (key.path.starts_with("checkerboard.") && rig_in.checkerboard.views == 0) return false;
  Rig rig = rig_in;  // accessors hand out references into a mutable Rig
  using K = RigKey::Kind;
  if (key.kind == K::Text && key.text(rig).empty()) return false;
  if (key.kind == K::RealList && key.list(rig).empty()) return false;
  const bool explicit_stops = !rig.schedule.angles_deg.empty();
  if (key.path == "schedule.count" && (explicit_stops || rig.schedule.count == 0)) return false;
  if (key.path == "schedule.stop_deg" && rig.schedule.count > 0) return false;
  return !(explicit_stops && (key.path == "schedule.start_deg" || key.path == "schedule.step_deg" ||
                              key.path == "schedule.stop_deg"));
}

}  // namespace polrig
