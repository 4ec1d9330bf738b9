#pragma once
// Monte-Carlo of the heading error of the W19 compass on a moving platform (spec
// sky-and-compasses.md §1.5, W19 §5.2): per trial a random attitude, a time-sync error during a
// turn, a mount misalignment, the sky's P_max and sensor noise through the device model
// (device/sensor pair voltages, ADC, calib/angles), then the heading from compass/heading.
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "polrig/compass/heading.h"
#include "polrig/progress.h"
#include "polrig/rig/rig.h"
#include "polrig/sky/sun.h"

namespace polrig {

struct HeadingStudySettings {
  int trials = 1000;
  // Where and when. Defaults: W19's dynamic run (Dalian, 2019-07-01 19:01 Beijing time, the static
  // site's coordinates; spec §1.1: h_s = 2.9°, A_s = 297.6°). `polrig study heading` takes them
  // from a sky rig's `sky:` block when the rig has one, and from --site/--utc over either.
  Site site;
  UtcTime utc{1561978860.0};  // 2019-07-01T11:01:00Z
  SunSettings sun;
  // Attitude: roll and pitch normal with these SDs (degrees), the heading uniform in [0°, 360°).
  double roll_sd_deg = 5, pitch_sd_deg = 5;
  // Time sync: the sensor's sample is taken Δt after the INS's, Δt uniform in [−Δt_max, Δt_max];
  // the platform turns at ω uniform in [−ω_max, ω_max] (W19 §5.2: ≈ 30°/s and a suspected 0.1 s).
  double sync_max_s = 0.1, turn_rate_max_dps = 30;
  // INS attitude error: normal, this SD (degrees) on roll and on pitch (SPAN-CPT: 0.015°).
  double ins_tilt_sd_deg = 0.015;
  // Mount: the sensor frame is the body's turned by Rx(m_x)·Ry(m_y)·Rz(m_z); m_x, m_y normal with
  // mount_tilt_sd_deg, m_z (the azimuthal offset left after mounting calibration) with
  // mount_azimuth_sd_deg.
  double mount_tilt_sd_deg = 0.2, mount_azimuth_sd_deg = 0.05;
  // The sky's P_max, uniform in [min, max] (W19's dynamic run: zenith DoP ≈ 0.61).
  double p_max_min = 0.5, p_max_max = 0.7;
  // Samples averaged per heading (W19's dynamic run: one sample at 70 Hz).
  int samples = 1;
};

struct HeadingTrial {
  int index = 0;
  std::uint64_t seed = 0;
  // Drawn inputs.
  double heading_deg = 0, roll_deg = 0, pitch_deg = 0;  // truth at the INS's time
  double sync_s = 0, turn_rate_dps = 0;
  double ins_roll_error_deg = 0, ins_pitch_error_deg = 0;
  double mount_x_deg = 0, mount_y_deg = 0, mount_z_deg = 0;
  double p_max = 0;
  // What the sensor saw and gave.
  double dop = 0;            // d at the sensor's axis
  double aop_true_deg = 0;   // θ_b the solver would get from a perfect sensor on a perfect mount
  double aop_meas_deg = 0;   // θ_b from the noisy voltages (θ_mount + θ_sec, θ_mount = 0; both anticlockwise from above)
  HeadingStatus status = HeadingStatus::Ok;
  double heading_est_deg = 0;  // NaN without a solution
  // Heading error (estimate − truth at the INS's time, [−180°, 180°)), all factors together, then
  // each factor alone (the others off): sync (ω·Δt), INS tilt, mount, sensor noise.
  double error_deg = 0;
  double error_sync_deg = 0, error_ins_tilt_deg = 0, error_mount_deg = 0, error_noise_deg = 0;

  // The heading the platform turns during the sync error, ω·Δt (degrees), and the sensor axis'
  // mount tilt √(m_x² + m_y²) (degrees): trials.csv's sync_heading_deg and mount_tilt_deg.
  double sync_heading_deg() const { return turn_rate_dps * sync_s; }
  double mount_tilt_deg() const { return std::hypot(mount_x_deg, mount_y_deg); }
};

// A sky rig's run (a rig whose source is time-dependent): its `sky:` block's site, first stop,
// UT1 − UTC and refraction replace those of `settings`; returns false, `settings` unchanged, for
// any other rig. `polrig study heading` then applies the options given on its command line.
bool use_rig_sky(const Rig& rig, HeadingStudySettings& settings);

// The ranges of `polrig study heading`'s settings (trials in [1, 1e7], samples in [1, 1e5], the
// SDs and limits as the CLI's options, p_max_min ≤ p_max_max in [0.05, 1]); throws
// std::invalid_argument "roll_sd_deg: expected a finite number in [0, 30] °, got 31", the setting
// named by `name` (its field name by default; the CLI passes its option's).
void check_heading_study_settings(
    const HeadingStudySettings& settings,
    const std::function<std::string(std::string_view field)>& name = [](std::string_view f) {
      return std::string(f);
    });

// summary.csv's rows: the heading error's statistics over the trials with a heading (NaN where
// none has one), overall for the full error and each factor alone (factor "all", bin NaN), then
// the full error in 8 equal bins of each factor's range (sync_heading_deg, tilt_deg = √(roll² +
// pitch²), mount_tilt_deg, mount_z_deg, p_max, dop; a factor without spread has no bins).
struct HeadingErrorStats {
  std::string factor, error;
  double bin_lo = NAN, bin_hi = NAN;  // the factor's bin [lo, hi) (the last closed)
  int trials = 0, solved = 0;
  double mean_deg = NAN, rms_deg = NAN, p50_abs_deg = NAN, p95_abs_deg = NAN, max_abs_deg = NAN;
};
std::vector<HeadingErrorStats> summarize_heading_trials(const std::vector<HeadingTrial>& trials);

// cdf.csv: at fraction (k + ½)/n, the k-th smallest |error| of the full error and of each factor
// alone (sync, INS tilt, mount, noise), each sorted on its own; NaN past a column's solved trials.
struct HeadingErrorCdf {
  std::vector<double> fraction;
  std::array<std::vector<double>, 5> abs_error_deg;  // all, sync, ins_tilt, mount, noise
};
HeadingErrorCdf heading_error_cdf(const std::vector<HeadingTrial>& trials);

// Sun at settings.utc and site; trials in parallel (TBB), each a pure function of
// (rig, settings, index): identical for any thread count.
// Throws as check_heading_study_settings for settings out of range.
std::vector<HeadingTrial> heading_trials(const Rig& rig, const HeadingStudySettings& settings,
                                         const Progress& progress = {});

}  // namespace polrig
