#pragma once
// The rig's keys: one table that names every setting, its unit, its default (the value in a
// default-constructed Rig), what it accepts and where it lives in the Rig. Parsing, --set,
// sweeps, the resolved-rig dump and docs/formats.md all read this one table.
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "polrig/rig/rig.h"

namespace polrig {

// The default instrument (device.kind).
inline constexpr std::string_view kDefaultDeviceKind = "six-photodiode";

// The most table stops a schedule may give (start/step/stop or an explicit list).
inline constexpr std::size_t kMaxStops = 1000000;

// A closed or open interval of real values; every real rig key has one.
struct RealRange {
  double lo, hi;
  bool lo_open = false, hi_open = false;
  constexpr bool contains(double v) const {
    return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
  }
  std::string text() const;  // "[0, 100]", "(0, 1)"
};

struct RigKey {
  // Bool: a YAML true or false (the camera's on/off settings; yaml-cpp's yes/no/on/off are refused,
  // so that a rig file reads one way).
  enum class Kind { Real, Integer, Seed, Text, RealArray, RealList, Bool };
  std::string_view path;     // "eccentricity.L_IS"
  Kind kind;
  std::string_view unit;     // "mm", "deg", "V", "" …
  std::string expects;       // what a valid value is, for error messages: "a length in [0, 100] mm"
  std::string_view doc;
  std::string_view why = {};  // why the range is what it is (a physical bound, or what the model can represent)

  // Accessors; the one matching `kind` is set.
  double& (*real)(Rig&) = nullptr;
  int& (*integer)(Rig&) = nullptr;
  std::uint64_t& (*seed)(Rig&) = nullptr;
  std::string& (*text)(Rig&) = nullptr;
  std::span<double> (*array)(Rig&) = nullptr;          // fixed length
  std::vector<double>& (*list)(Rig&) = nullptr;        // any length
  bool& (*boolean)(Rig&) = nullptr;
  std::optional<RealRange> range = {};  // real keys (Real, RealArray, RealList)
  std::size_t max_items = 0;             // RealList: the most entries it may hold
  // Value check; returns false when the value is outside what `expects` says.
  bool (*valid_real)(double) = nullptr;
  bool (*valid_integer)(long long) = nullptr;
  bool (*valid_text)(std::string_view) = nullptr;

  // Who reads the key. The studies: simulate (also run, study calibration), the CS study (study
  // cs, sweep), study adc, calibrate (a --rig or a dataset's rig.yaml), and navigate (a unit
  // array's dataset).
  enum Study : unsigned {
    kSimulate = 1u << 0, kCs = 1u << 1, kAdc = 1u << 2, kCalibrate = 1u << 3, kNavigate = 1u << 4
  };
  unsigned studies = 0;
  // The source models that read it (source.model names, space-separated); empty: every model.
  // A rig whose model is not among them refuses the key (rig file, --set, --grid) and leaves it
  // out of its effective rig.yaml.
  std::string_view sources = {};
  bool read_by_source(std::string_view model) const;
  // The instruments that read it (device.kind names, space-separated); empty: every instrument.
  // A rig whose instrument is not among them refuses the key, as for `sources`.
  std::string_view instruments = {};
  bool read_by_instrument(std::string_view kind) const;
  // The skies that read it (sky.model names, space-separated); empty: every sky. A rig whose
  // sky.model is not among them refuses the key, as for `sources`.
  std::string_view sky_models = {};
  bool read_by_sky_model(std::string_view model) const;
  std::string studies_text() const;  // "simulate, cs"
};

const std::vector<RigKey>& rig_keys();
const RigKey* find_rig_key(std::string_view path);

// Whether a rig file of `rig` writes the key (rig_to_yaml, Python's Rig.to_dict): not when the
// rig's source or instrument does not read it, not device.kind when it is the default
// (six-photodiode: a rig.yaml written before the camera stays byte-identical), not device.d when the
// source derives it (traced, sky: the parser derives it again), not an empty optional text or list (unset), and not
// schedule.start/step/stop_deg when an explicit list of stops replaces them. What it writes reads
// back to the same rig.
bool written_for(const RigKey& key, const Rig& rig);

// Checks that involve several keys at once. Returns the offending key's path and what is
// expected, or nothing when the rig is consistent.
struct RigProblem {
  std::string path;
  std::string message;
  std::string related_path = {};  // the other key of the rule, if any
};
// What a rig is loaded for: to run it (simulate, every study: all rules), or to read a recorded
// unit-array dataset with it (navigate, calibrate --method unit-array: a simulated run's own rules,
// its trajectory's whole IMU intervals and motions and the compass rate dividing the IMU's, do not
// apply to a measured log, whose own files are checked as they are read).
enum class RigUse { Run, ReadDataset };
std::optional<RigProblem> check_rig(const Rig& rig, RigUse use = RigUse::Run);

}  // namespace polrig
