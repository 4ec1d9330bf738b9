#pragma once
// Monte-Carlo of Z21's system (Zhang et al. 2021; spec sky-and-compasses.md §4.5–4.6): N trials of
// a unit-array rig, each simulate_navigation + navigate (SINS, PNS, SINS/PNS), with its seed
// derive_seed(rig.seed, trial) for everything the rig draws (the IMU's errors, the units' noise,
// their mounting errors); optional sweeps of the run's length, the sky's P_max, the compass noise and
// the ring's tilt, each value × N trials (the same N seeds: common random numbers); and over the
// rig's own trials Z21's Fig. 17 (a horizontal-attitude error against the sun-elevation error) and
// Fig. 16 (a unit's E-vector error against its DoP). `polrig study navigation RIG`.
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "polrig/progress.h"
#include "polrig/rig/rig.h"
#include "polrig/study/navigation.h"

namespace polrig {

struct NavigationStudySettings {
  int trials = 20;
  // The sweeps (each optional): every value is a cell of `trials` trials, the rig with the one key
  // set (trajectory.duration_s, sky.p_max, electronics.noise_sigma_V, device.units.ring_tilt_deg).
  std::vector<double> durations_s, p_max, noise_sigma_V, ring_tilts_deg;
  // Fig. 17: horizontal-attitude errors (degrees), each towards a direction drawn uniformly per
  // compass reading (the same direction for every tilt: common random numbers).
  std::vector<double> tilts_deg = {0.5, 1, 2};
};

// The sweeps' keys, the order of their cells, and the settings' field names.
struct NavigationSweep {
  std::string_view factor;  // "duration", "p_max", "noise", "ring_tilt" (summary.csv's factor)
  std::string_view key;     // the rig key it sets
  std::string_view field;   // NavigationStudySettings' field
  std::vector<double> NavigationStudySettings::*values;
};
const std::vector<NavigationSweep>& navigation_sweeps();

// The rig with one real key set, and every check a rig file's value of it would meet: the key's
// own range, whether the rig's instrument and source read it, and check_rig's rules across keys
// (study/ sits below io/, so this is the key table's path of io/rig_yaml.h's parse_rig with a
// --set; tests/test_navigation_study.cpp checks that both give the same rig). Also refuses a
// value the rig would ignore (a duration beside trajectory.segment_s, a P_max beside
// sky.p_max_table, a ring tilt beside an explicit device.units.tilt_deg). Throws RigError
// "<key>=<value>: …".
Rig rig_with_value(const Rig& rig, std::string_view key, double value);

// Throws RigError for a rig that is not a unit array (require_instrument) or has no sky, a
// sweep value the rig refuses (rig_with_value) and std::invalid_argument for the settings' ranges
// (trials in [1, 100000]; tilts finite in [0, 10]°, at most 32): "tilts_deg: …", the setting named
// by `name` (its field name by default; the CLI passes its option's).
void check_navigation_study_settings(
    const Rig& rig, const NavigationStudySettings& settings,
    const std::function<std::string(std::string_view field)>& name = [](std::string_view f) {
      return std::string(f);
    });

// A cell: the rig as given ("baseline", cell 0), or one sweep value.
struct NavigationStudyCell {
  int index = 0;
  std::string factor = "baseline";  // or a NavigationSweep's factor
  std::string key;                  // the rig key set ("" for the baseline)
  double value = std::numeric_limits<double>::quiet_NaN();
  double duration_s = 0;            // the run's length in this cell
};

// One trial of one cell, one mode.
struct NavigationTrialResult {
  int cell = 0, trial = 0;
  NavigationMode mode = NavigationMode::Sins;
  std::uint64_t seed = 0;  // the trial's rig seed, derive_seed(rig.seed, trial)
  // At the last compass reading (NaN where the mode has no fix there: PNS without a converged fit).
  double final_t_s = 0, final_north_m = 0, final_east_m = 0, final_error_m = 0;
  // The heading (yaw) error at the last reading, wrapped to ±180° (PNS: the SINS's attitude it takes).
  double final_heading_error_deg = std::numeric_limits<double>::quiet_NaN();
  ErrorStatistics lat_deg, lon_deg;  // over the run's fixes (error_statistics)
  double filter_nis_mean = std::numeric_limits<double>::quiet_NaN();  // integrated only
  int filter_updates = 0;                                              // integrated: scalar sun updates
  // Integrated, at the last reading: the normalized estimation error squared against the filter's P,
  // e^T P^-1 e, of the horizontal position (δL, δλ: 2 degrees of freedom) and of the attitude
  // (φ_E, φ_N, φ_U from C̃_b^n·C_n^b = I − [φ×]: 3); NaN for the other modes or a diverged run.
  double nees_position = std::numeric_limits<double>::quiet_NaN();
  double nees_attitude = std::numeric_limits<double>::quiet_NaN();
};

// The integrated filter's consistency over one cell's trials (Bar-Shalom, Li & Kirubarajan 2001,
// §5.4.2): the mean NEES over N trials times N is χ²(N·d) for a consistent filter, so its two-sided
// 95 % band is [χ²_0.025(N·d), χ²_0.975(N·d)]/N; the mean NIS over every update of every trial
// likewise with N·d the updates' count (Wilson–Hilferty's quantiles, statistics.h).
struct ConsistencyBand {
  double mean = std::numeric_limits<double>::quiet_NaN(), lo = 0, hi = 0;
  long long dof = 0;  // N·d
  bool inside() const { return mean >= lo && mean <= hi; }
};
// Issue 34 §3's goal per cell: the trials whose integrated solution ends no worse than the better of
// SINS and PNS, in horizontal position (PNS without a fix at the end: SINS's) and in heading (PNS has
// none of its own: SINS's), at the last reading. Counted only with all three modes run.
struct NavigationGoal {
  int cell = 0;
  int trials = 0;                            // with a finite integrated and SINS error
  int position_met = 0, heading_met = 0, both_met = 0;
};

struct NavigationConsistency {
  int cell = 0;
  int trials = 0;  // with a finite NEES
  ConsistencyBand nees_position, nees_attitude, nis;
};

// Five percentiles (type 7, as NumPy's default) of the finite values; NaN without any.
struct Percentiles {
  double p05 = NAN, p25 = NAN, p50 = NAN, p75 = NAN, p95 = NAN;
  int count = 0;  // finite values
};
Percentiles percentiles(std::vector<double> values);

struct NavigationStudySummary {
  int cell = 0;
  NavigationMode mode = NavigationMode::Sins;
  int trials = 0;
  Percentiles final_error_m, lat_mae_deg, lon_mae_deg;
};

// The rig's own trials (cell 0): the horizontal position error √(north² + east²) at every compass
// reading, its percentiles over the trials, per mode.
struct NavigationErrorBand {
  NavigationMode mode = NavigationMode::Sins;
  std::vector<double> t_s;
  std::vector<Percentiles> error_m;
};

// Fig. 17 over cell 0's readings: the sun's elevation H^n = asin((C_b^n·s^b)_z) of every reading with
// a sun, with C_b^n the true attitude and with it tilted by τ about a horizontal axis (the up axis
// tipped towards an azimuth drawn uniformly per reading); error = H^n(tilted) − H^n(true).
// Closed form: sin H′ = sin H·cos τ + cos H·sin τ·cos Δ with Δ uniform, so to first order
// H′ − H = τ·cos Δ and mean |H′ − H| = (2/π)·τ.
struct TiltErrorRow {
  double tilt_deg = 0;
  long long draws = 0;
  double mean_abs_deg = NAN, sd_abs_deg = NAN, rms_deg = NAN, max_abs_deg = NAN;
  double first_order_deg = NAN;  // (2/π)·τ
  double exact_deg = NAN;        // E_Δ|asin(sin H cos τ + cos H sin τ cos Δ) − H| at the readings' mean H
  double z21_deg = NAN;          // Z21 Fig. 17 (0.5°, 1°, 2°: 0.113°, 0.221°, 0.887°), NaN otherwise
};

// Fig. 16 over cell 0's readings: every unit reading with an angle, binned by its measured DoP in
// 5 % bins [lo, hi); |aop − true_aop| axial (mod 180°), in degrees.
struct DopBin {
  double lo = 0, hi = 0;
  long long count = 0;
  double mean_abs_deg = NAN, sd_abs_deg = NAN;  // sd: population, about the mean
  double mean_true_dop = NAN;
  double z21_mean_deg = NAN, z21_sd_deg = NAN;  // Z21 Fig. 16: 25–30 %: 2.05° ± 2.38°; 50–55 %: 0.14° ± 0.17°
};
inline constexpr double kDopBinWidth = 0.05;

struct NavigationStudy {
  NavigationStudySettings settings;
  std::vector<NavigationMode> modes;
  std::vector<NavigationStudyCell> cells;
  std::vector<NavigationTrialResult> trials;     // cell-major, then trial, then mode
  std::vector<NavigationStudySummary> summary;   // cell-major, then mode
  std::vector<NavigationConsistency> consistency;  // per cell
  std::vector<NavigationGoal> goal;                // per cell (empty unless sins, pns and integrated ran)
  std::vector<NavigationErrorBand> bands;        // per mode, cell 0
  std::vector<TiltErrorRow> tilt;                // per settings.tilts_deg
  double tilt_mean_elevation_deg = NAN;          // the readings' mean true-attitude H^n (cell 0)
  std::vector<DopBin> dop;                       // the bins from 0 to the largest DoP seen, in order
};

// Trials in parallel (TBB over cells, each cell's scene made once, and over its trials), each a pure
// function of (rig, cell, trial) stored by index: identical for any thread count. Progress: "study navigation: trials" by trial. Throws as
// check_navigation_study_settings.
NavigationStudy navigation_study(const Rig& rig, const NavigationStudySettings& settings,
                                 const Progress& progress = {});

}  // namespace polrig
