#pragma once
// Monte-Carlo benchmark of central symmetry in calibration terms: many simulated calibration
// runs, each with its own noise and a random eccentricity, calibrated by all three types.
#include <array>
#include <iterator>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "polrig/calib/pipeline.h"
#include "polrig/progress.h"
#include "polrig/ranks.h"
#include "polrig/rig/rig.h"

namespace polrig {

struct TrialSettings {
  int trials = 100;
  // Each trial draws L_IS and L_S uniformly in [0, max] and α_IS, α_S uniformly in [0°, 360°).
  double L_IS_max = 0.1;
  double L_S_max = 0.04;
  CalibrationOptions calibration;  // the method field is ignored: every type runs
};

// The ranges of `polrig study calibration`'s --trials and --L-IS-max/--L-S-max (the keys' own
// range of eccentricity.L_IS and L_S).
inline constexpr int kMaxTrials = 10000000;
inline constexpr double kMaxTrialOffsetMm = 100.0;

// The settings of `polrig study calibration` and Rig.study_calibration: `trials` runs in [1,
// kMaxTrials]; offsets drawn up to L_IS_max and L_S_max mm in [0, 100], by default twice the
// rig's L_IS and L_S (at most 100); `calibration` as calib/rig_options.h's calibration_options.
// Throws RigError naming the setting ("trials=0: …", "L_IS_max=…: …") for a value out of range.
TrialSettings trial_settings_for(const Rig& rig, int trials, std::optional<double> L_IS_max,
                                 std::optional<double> L_S_max, CalibrationOptions calibration);

struct Trial {
  int index = 0;
  std::uint64_t seed = 0;  // the trial's noise seed, derived from the rig's seed and the index
  Eccentricity eccentricity;
  std::array<double, 3> accuracy_deg{};  // θ_sec accuracy per type (kAllMethods order); NaN if it failed
  std::array<FitSummary, 3> fit;         // how each type's fit ended
};

// Every trial is a pure function of (rig, settings, index): the result is the same for any
// thread count and any rank count. Trials run in parallel (TBB). With `ranks`, rank k computes
// the k-th of size() consecutive shards of the indices and rank 0 receives every trial in index
// order (the other ranks an empty vector); a trial that throws on any rank throws on every rank
// (the lowest rank's error). `progress` is reported with this rank's shard.
std::vector<Trial> calibration_trials(const Rig& rig, const TrialSettings& settings,
                                      const Progress& progress = {}, const Ranks* ranks = nullptr);

// A trial as bytes and back, exactly (ranks send trials to rank 0 so).
void append_trial_bytes(const Trial& trial, std::vector<std::byte>& out);
// Reads the trial at `at` and moves `at` past it; std::runtime_error on truncated bytes.
Trial read_trial_bytes(std::span<const std::byte> bytes, std::size_t& at);

struct TrialSummary {
  CalibrationMethod method;
  int succeeded = 0, failed = 0;
  std::array<int, std::size(kAllTerminations)> terminations{};  // count per kAllTerminations entry
  double median_deg = 0, p05_deg = 0, p95_deg = 0, mean_deg = 0;
};
std::vector<TrialSummary> summarize_trials(const std::vector<Trial>& trials);

}  // namespace polrig
