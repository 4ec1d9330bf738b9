#pragma once
// Monte-Carlo of positioning from the sun's zenith angle (W16 Eq. 17, spec sky-and-compasses.md
// §3.4–3.6): the position error against the window's length, the zenith-angle noise and the
// levelling error, beside Eq. 15's two-sighting error and the linearized least-squares error.
// `polrig study positioning RIG` and Python's study_positioning.
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "polrig/compass/positioning.h"
#include "polrig/progress.h"
#include "polrig/sky/sun.h"

namespace polrig {

struct PositioningStudySettings {
  // The truth and the window: a sky rig's site, first stop and stop times (times_s since the first
  // stop, rising); the sun's settings of the data and of the fit.
  Site site{28.221, 112.992, 0};                     // W16's roof
  UtcTime first{1450244220.0};                       // 2015-12-16T05:37:00Z (13:37 Beijing)
  std::vector<double> times_s;                       // empty: 0, 1, …, 3600 (W16's hour at 1 Hz)
  SunSettings sun;
  // The three sweeps, each about the baseline (the full window, baseline noise, baseline tilt).
  std::vector<double> windows_s;  // empty: the span × 1/60, 1/30, 1/12, 1/6, 1/3, 1/2, 1
  std::vector<double> noise_sd_deg = {0, 0.02, 0.05, 0.14, 0.3, 0.5};
  std::vector<double> tilt_deg = {0, 0.02, 0.05, 0.1, 0.2};
  double baseline_noise_sd_deg = 0.14;  // W16's zenith-angle scatter (Fig. 5)
  double baseline_tilt_deg = 0;
  // The zenith-angle noise: first-order Gauss–Markov with this correlation time (0: white),
  // stationary with SD σ: e_k = ρ·e_{k−1} + σ·√(1 − ρ²)·n_k, ρ = exp(−Δt/τ).
  double correlation_s = 0;
  // The levelling error: the camera's axis tilted by τ (a sweep value) towards an azimuth drawn
  // uniformly per trial; the measured θ_S is the angle between the sun and that axis (exact).
  double prior_offset_km = 100;  // the prior: the truth moved this far, in a direction drawn per trial
  int trials = 100;
  std::uint64_t seed = 20151216;
  // Also search the mirror root in every trial's fit (twice the work) and keep the root nearer the
  // prior. Off, each fit follows the prior's basin; either way every cell reports M′ (mirror_km,
  // one noise-free fit) and how many trials ended nearer it (wrong_root).
  bool second_root = false;
};

// The ranges (trials in [1, 1e6]; windows in (0, span] and at least two sightings; noise SDs in
// [0, 10]°, tilts in [0, 10]°, correlation in [0, 1e5] s, prior offset in [0, 2000] km; times
// rising and finite). Throws std::invalid_argument "noise_sd_deg: …", the setting named by
// `name` (its field name by default; the CLI passes its option's).
void check_positioning_study_settings(
    const PositioningStudySettings& settings,
    const std::function<std::string(std::string_view field)>& name = [](std::string_view f) {
      return std::string(f);
    });

// One setting of the three sweeps.
struct PositioningCell {
  int index = 0;
  std::string factor;  // "window", "noise", "tilt"
  double window_s = 0, noise_sd_deg = 0, tilt_deg = 0;
  int sightings = 0;
  double delta_beta_deg = 0;  // the sun's azimuth change over the window
  // Eq. 15 with ε_γ = √(σ² + τ²) for the window's first and last sightings (A and B).
  double eq15_km = 0;
  // The linearized least-squares RMS error √trace(P·Σ·Pᵀ) (P = (JᵀJ)⁻¹Jᵀ at the truth, Σ the
  // zenith errors' covariance: Gauss–Markov noise plus the tilt's τ²/2·cos(β_k − β_l) over a
  // uniform tilt azimuth), km.
  double linear_rms_km = 0;
  // W16's M′: Eq. 17's mirror root of the window's noise-free, level zenith angles (the other
  // intersection of the equal-altitude circles, mirrored about the sun's ground track), found by
  // one fit from the truth with the mirror search on; NaN where that search found none. Its
  // distance from the truth is how far off a prior may be before it picks the wrong root.
  double mirror_lat_deg = NAN, mirror_lon_deg = NAN, mirror_km = NAN;
};

struct PositioningTrial {
  int cell = 0, trial = 0;
  double tilt_azimuth_deg = 0;
  double prior_lat_deg = 0, prior_lon_deg = 0;
  double lat_deg = 0, lon_deg = 0;   // the chosen root
  double error_km = 0;               // great-circle distance to the truth
  double north_km = 0, east_km = 0;  // the error's components (local tangent plane)
  PositionTermination termination = PositionTermination::Converged;
  int iterations = 0;
  double residual_rms_deg = 0;
  double sd_major_km = std::numeric_limits<double>::quiet_NaN();  // the fit's own 1σ ellipse
};

// Over a cell's converged trials (NaN where none converged).
struct PositioningStats {
  int cell = 0, trials = 0, converged = 0;
  double rms_km = NAN, mean_km = NAN, p50_km = NAN, p95_km = NAN, max_km = NAN;
  double mean_north_km = NAN, mean_east_km = NAN;
  int wrong_root = 0;  // converged trials whose fix is nearer the cell's M′ than the truth
};

struct PositioningStudy {
  PositioningStudySettings settings;  // as run (times and windows filled in)
  std::vector<PositioningCell> cells;
  std::vector<PositioningTrial> trials;  // cell-major, then trial
  std::vector<PositioningStats> stats;   // one per cell
};

// Trials in parallel (TBB), each a pure function of (settings, cell, trial); its random numbers
// from random.h by (seed, trial, sample): the same noise and tilt azimuth in every cell (common
// random numbers). Identical for any thread count. Throws as check_positioning_study_settings.
PositioningStudy positioning_study(const PositioningStudySettings& settings,
                                   const Progress& progress = {});

}  // namespace polrig
