#include "polrig/study/calibration_trials.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "polrig/calib/preprocess.h"
#include "polrig/random.h"
#include "polrig/rig/error.h"
#include "polrig/sim/simulate.h"

namespace polrig {

TrialSettings trial_settings_for(const Rig& rig, int trials, std::optional<double> L_IS_max,
                                 std::optional<double> L_S_max, CalibrationOptions calibration) {
  if (trials < 1 || trials > kMaxTrials)
    throw RigError(fmt::format("trials={}: expected a whole number in [1, {}]", trials, kMaxTrials));
  const auto offset = [](std::optional<double> given, double rig_mm, const char* name) {
    if (!given) return std::min(2.0 * rig_mm, kMaxTrialOffsetMm);  // twice the rig's, in range
    if (!(*given >= 0.0 && *given <= kMaxTrialOffsetMm))
      throw RigError(fmt::format("{}={}: expected a number in [0, {}] mm", name, *given, kMaxTrialOffsetMm));
    return *given;
  };
  TrialSettings s;
  s.trials = trials;
  s.L_IS_max = offset(L_IS_max, rig.eccentricity.L_IS, "L_IS_max");
  s.L_S_max = offset(L_S_max, rig.eccentricity.L_S, "L_S_max");
  s.calibration = std::move(calibration);
  return s;
}

namespace {

Trial run_trial(const Rig& base, const TrialSettings& s, int index) {
  Trial t;
  t.index = index;
  t.seed = derive_seed(base.seed, static_cast<std::uint64_t>(index));
  // Stream 0 of the trial's seed draws its geometry; the noise uses the seed itself.
  const auto u = [&](std::uint64_t k) { return uniform_unit(t.seed, 0, 0xEC, k); };
  t.eccentricity = {s.L_IS_max * u(0), 360.0 * u(1), s.L_S_max * u(2), 360.0 * u(3)};

  Rig rig = base;
  rig.seed = t.seed;
  rig.eccentricity = t.eccentricity;
  const Simulation sim = simulate(rig);
  std::vector<StopVoltages> stops;
  for (std::size_t k = 0; k < sim.stops.size(); ++k)
    stops.push_back({sim.stops[k].theta_R_deg, sim.stops[k].V_mean, "stop " + std::to_string(k)});

  for (std::size_t m = 0; m < kAllMethods.size(); ++m) {
    CalibrationOptions o = s.calibration;
    o.method = kAllMethods[m];
    const CalibrationResult r = calibrate(stops, o);
    t.fit[m] = r.fit.summary;
    t.accuracy_deg[m] = r.usable() ? r.accuracy[kThetaSec].accuracy_deg()
                                   : std::numeric_limits<double>::quiet_NaN();
  }
  return t;
}

double quantile(std::vector<double> sorted, double q) {
  // Linear interpolation between order statistics (type 7, as R's and NumPy's default).
  const double pos = q * static_cast<double>(sorted.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (pos - static_cast<double>(lo)) * (sorted[hi] - sorted[lo]);
}

}  // namespace

std::vector<Trial> calibration_trials(const Rig& rig, const TrialSettings& s, const Progress& progress) {
  std::vector<Trial> trials(static_cast<std::size_t>(std::max(0, s.trials)));
  // The CS types need every stop paired; that depends on the schedule alone, so it is the rig's
  // error, said once before any work, not a failure of every trial.
  std::vector<StopVoltages> schedule;
  for (double theta : rig.schedule.table_angles_deg())
    schedule.push_back({theta, {0, 0, 0}, fmt::format("stop {}", schedule.size())});
  try {
    central_symmetry_points(schedule);
  } catch (const CalibrationError& e) {
    throw CalibrationError(fmt::format("the rig's schedule: {}; study calibration runs the CS "
                                       "types too", e.what()));
  }
  rig.light->prepare(progress);
  progress.begin("study calibration: trials", s.trials);
  tbb::parallel_for(0, s.trials, [&](int k) {
    trials[static_cast<std::size_t>(k)] = run_trial(rig, s, k);
    progress.advance();
  });
  progress.finish();
  return trials;
}

std::vector<TrialSummary> summarize_trials(const std::vector<Trial>& trials) {
  std::vector<TrialSummary> out;
  for (std::size_t m = 0; m < kAllMethods.size(); ++m) {
    TrialSummary s;
    s.method = kAllMethods[m];
    std::vector<double> acc;
    for (const Trial& t : trials) {
      if (t.fit[m].usable()) acc.push_back(t.accuracy_deg[m]);
      else ++s.failed;
      for (std::size_t k = 0; k < std::size(kAllTerminations); ++k)
        if (t.fit[m].termination == kAllTerminations[k]) ++s.terminations[k];
    }
    s.succeeded = static_cast<int>(acc.size());
    if (!acc.empty()) {
      std::sort(acc.begin(), acc.end());
      s.median_deg = quantile(acc, 0.5);
      s.p05_deg = quantile(acc, 0.05);
      s.p95_deg = quantile(acc, 0.95);
      double sum = 0;
      for (double a : acc) sum += a;
      s.mean_deg = sum / static_cast<double>(acc.size());
    } else {
      s.median_deg = s.p05_deg = s.p95_deg = s.mean_deg = std::numeric_limits<double>::quiet_NaN();
    }
    out.push_back(s);
  }
  return out;
}

}  // namespace polrig
