#pragma once
// Monte-Carlo benchmark of central symmetry in calibration terms: many simulated calibration
// runs, each with its own noise and a random eccentricity, calibrated by all three types.
#include <array>
#include <iterator>
#include <string>
#include <vector>

#include "polrig/calib/pipeline.h"
#include "polrig/progress.h"
#include "polrig/rig/rig.h"

namespace polrig {

struct TrialSettings {
  int trials = 100;
  // Each trial draws L_IS and L_S uniformly in [0, max] and α_IS, α_S uniformly in [0°, 360°).
  double L_IS_max = 0.1;
  double L_S_max = 0.04;
  CalibrationOptions calibration;  // the method field is ignored: every type runs
};

struct Trial {
  int index = 0;
  std::uint64_t seed = 0;  // the trial's noise seed, derived from the rig's seed and the index
  Eccentricity eccentricity;
  std::array<double, 3> accuracy_deg{};  // θ_sec accuracy per type (kAllMethods order); NaN if it failed
  std::array<FitSummary, 3> fit;         // how each type's fit ended
};

// Every trial is a pure function of (rig, settings, index): the result is the same for any
// thread count. Trials run in parallel (TBB).
std::vector<Trial> calibration_trials(const Rig& rig, const TrialSettings& settings,
                                      const Progress& progress = {});

struct TrialSummary {
  CalibrationMethod method;
  int succeeded = 0, failed = 0;
  std::array<int, std::size(kAllTerminations)> terminations{};  // count per kAllTerminations entry
  double median_deg = 0, p05_deg = 0, p95_deg = 0, mean_deg = 0;
};
std::vector<TrialSummary> summarize_trials(const std::vector<Trial>& trials);

}  // namespace polrig
