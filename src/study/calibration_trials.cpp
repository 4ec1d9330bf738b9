#include "polrig/study/calibration_trials.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <type_traits>
#include <limits>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "polrig/calib/preprocess.h"
#include "polrig/random.h"
#include "polrig/rig/error.h"
#include "polrig/sim/simulate.h"
#include "polrig/study/rank_failure.h"
#include "polrig/statistics.h"

namespace polrig {

TrialSettings trial_settings_for(const Rig& rig, int trials, std::optional<double> L_IS_max,
                                 std::optional<double> L_S_max, CalibrationOptions calibration) {
  require_instrument(rig, Instrument::kPairVoltages, "study calibration");
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

}  // namespace

std::vector<Trial> calibration_trials(const Rig& rig, const TrialSettings& s, const Progress& progress,
                                      const Ranks* ranks_or_null) {
  const Ranks& ranks = ranks_or_null ? *ranks_or_null : this_process_only();
  require_instrument(rig, Instrument::kPairVoltages, "study calibration");
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
  // This rank's shard: indices [first, last).
  const int n = std::max(0, s.trials);
  const auto shard_start = [&](int k) {
    return static_cast<int>(static_cast<long long>(n) * k / ranks.size());
  };
  const int first = shard_start(ranks.rank()), last = shard_start(ranks.rank() + 1);
  std::vector<Trial> trials(static_cast<std::size_t>(last - first));
  std::optional<std::string> failure;
  try {
    rig.light->prepare(progress);
    progress.begin("study calibration: trials", last - first);
    tbb::parallel_for(first, last, [&](int k) {
      trials[static_cast<std::size_t>(k - first)] = run_trial(rig, s, k);
      progress.advance();
    });
    progress.finish();
  } catch (const std::exception& e) {
    if (ranks.size() == 1) throw;
    failure = rank_failure_text(e);
  }
  if (ranks.size() == 1) return trials;
  if (const auto f = ranks.first_failure(failure)) throw_rank_failure(*f);
  std::vector<std::byte> mine;
  for (const Trial& t : trials) append_trial_bytes(t, mine);
  const std::vector<std::byte> all = ranks.gather(mine);
  if (!ranks.is_root()) return {};
  std::vector<Trial> every;
  every.reserve(static_cast<std::size_t>(n));
  for (std::size_t at = 0; at < all.size();) every.push_back(read_trial_bytes(all, at));
  if (every.size() != static_cast<std::size_t>(n))
    throw std::logic_error(fmt::format("study calibration: gathered {} trials of {}", every.size(), n));
  return every;
}

namespace {
template <class T>
void put(const T& v, std::vector<std::byte>& out) {
  static_assert(std::is_trivially_copyable_v<T>);
  const auto* b = reinterpret_cast<const std::byte*>(&v);
  out.insert(out.end(), b, b + sizeof(T));
}
void put_text(const std::string& text, std::vector<std::byte>& out) {
  put(static_cast<std::uint64_t>(text.size()), out);
  const auto* b = reinterpret_cast<const std::byte*>(text.data());
  out.insert(out.end(), b, b + text.size());
}
void take_bytes(std::span<const std::byte> bytes, std::size_t& at, void* to, std::size_t n) {
  if (n > bytes.size() || at > bytes.size() - n)
    throw std::runtime_error("study calibration: a trial's bytes end early");
  std::memcpy(to, bytes.data() + at, n);
  at += n;
}
template <class T>
T take(std::span<const std::byte> bytes, std::size_t& at) {
  T v;
  take_bytes(bytes, at, &v, sizeof(T));
  return v;
}
std::string take_text(std::span<const std::byte> bytes, std::size_t& at) {
  std::string text(take<std::uint64_t>(bytes, at), '\0');
  take_bytes(bytes, at, text.data(), text.size());
  return text;
}
}  // namespace

// Every field is written below: a new field in FitSummary or Trial changes their size and stops
// the build here until it is written too (x86-64 with libstdc++).
// FitSummary's cost_unit is not sent: every trial's fit is Eq. 15's (V^2, its default).
static_assert(sizeof(FitSummary) == 8 + 2 * sizeof(std::string) + 2 * sizeof(double) + sizeof(const char*) + 16,
              "FitSummary changed: write and read its new field below");
static_assert(sizeof(Trial) == 8 + 8 + sizeof(Eccentricity) + 3 * sizeof(double) + 3 * sizeof(FitSummary),
              "Trial changed: write and read its new field below");

void append_trial_bytes(const Trial& t, std::vector<std::byte>& out) {
  put(t.index, out);
  put(t.seed, out);
  put(t.eccentricity, out);
  put(t.accuracy_deg, out);
  for (const FitSummary& f : t.fit) {
    put(f.termination, out);
    put_text(f.message, out);
    put_text(f.solver_status, out);
    put(f.initial_cost, out);
    put(f.final_cost, out);
    put(f.iterations, out);
    put(f.evaluations, out);
    put(f.observations, out);
  }
}

Trial read_trial_bytes(std::span<const std::byte> bytes, std::size_t& at) {
  Trial t;
  t.index = take<int>(bytes, at);
  t.seed = take<std::uint64_t>(bytes, at);
  t.eccentricity = take<Eccentricity>(bytes, at);
  t.accuracy_deg = take<std::array<double, 3>>(bytes, at);
  for (FitSummary& f : t.fit) {
    f.termination = take<FitTermination>(bytes, at);
    f.message = take_text(bytes, at);
    f.solver_status = take_text(bytes, at);
    f.initial_cost = take<double>(bytes, at);
    f.final_cost = take<double>(bytes, at);
    f.iterations = take<int>(bytes, at);
    f.evaluations = take<int>(bytes, at);
    f.observations = take<int>(bytes, at);
  }
  return t;
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
      s.median_deg = quantile_of_sorted(acc, 0.5);
      s.p05_deg = quantile_of_sorted(acc, 0.05);
      s.p95_deg = quantile_of_sorted(acc, 0.95);
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
