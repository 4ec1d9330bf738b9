#pragma once
// Z21's system end to end (Zhang et al. 2021; spec sky-and-compasses.md §4; docs/physics.md §20): a
// unit-array polarization compass on a vehicle with a strapdown INS. simulate_navigation makes a
// dataset from a rig (the true trajectory, the IMU with its errors, every unit's reading at the
// compass rate); navigate runs the three modes of Z21 Figs. 8–13 on a dataset, simulated or
// measured:
//   SINS        the INS alone (ins/mechanization.h), height held when the rig says so;
//   PNS         the position from the sun elevations of the last navigation.pns_window_s
//               (compass/positioning.h's Eq. 17 fit, the vehicle assumed still over the window), each
//               elevation H^n = asin((C_b^n s^b)_z) with the SINS's attitude;
//   integrated  the INS with the 15-state filter (ins/filter.h) updated by H^n at every reading,
//               with its own attitude.
// The sun of a reading: the two highest-DoP units (compass/unit_array.h, Eqs. 3–8) with their nominal
// frames, or a calibration's. Dec and GHA of the filter's model: one SunTrack at the start's site
// (sky/sun.h; the parallax between the site and the vehicle is < 9″).
#include <optional>
#include <span>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "polrig/calib/unit_array.h"
#include "polrig/ins/filter.h"
#include "polrig/ins/imu.h"
#include "polrig/ins/trajectory.h"
#include "polrig/compass/positioning.h"
#include "polrig/compass/unit_array.h"
#include "polrig/progress.h"
#include "polrig/rig/rig.h"
#include "polrig/sky/sun.h"

namespace polrig {

// The rig's settings as ins/ takes them (rig/ins_settings.h's units → SI).
TrajectorySpec trajectory_spec(const Rig& rig);  // the start at the sky's site
ImuErrorSpec imu_error_spec(const ImuSettings& imu);
FilterSettings filter_settings(const Rig& rig);
// The state the INS starts from: the sky's site and first_stop_utc, the trajectory's start attitude
// plus navigation.initial_attitude_error_deg, its speed along the heading and pitch; for a simulated
// run (DrawnFromP0) with navigation.initial_errors drawn, plus an error x ~ N(0, P0) in attitude,
// velocity and position drawn with the rig's seed (the height's and v_U's zero when held), so that
// a Monte-Carlo's NEES tests the filter fairly. A measured log's start is Stated.
enum class StartErrors { Stated, DrawnFromP0 };
InsState initial_state(const Rig& rig, StartErrors errors);
// P0 (diagonal): the navigation.*_sigma keys and the IMU's turn-on and constant biases.
Matrix15 initial_covariance(const Rig& rig);

// A start stated with a measured log (its dataset's start.yaml, docs/formats.md §6.17): P0's
// attitude, velocity and position standard deviations, in place of the navigation.*_sigma keys.
struct StartSigma {
  Eigen::Vector3d attitude_rad = Eigen::Vector3d::Zero();  // φ_E, φ_N, φ_U
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();  // δv_E, δv_N, δv_U
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();    // north, east, up
};

// One reading of every unit.
struct CompassEpoch {
  double t_s = 0;
  std::vector<UnitReading> units;  // aop in the unit's frame (spec sense), dop
  std::vector<UnitSample> samples;  // simulated only: the voltages and the truth (else empty)
};

// What a simulation knows and a measured dataset does not.
struct NavigationTruth {
  std::vector<TruthSample> trajectory;  // at every IMU sample, trajectory[0] at t = 0
  UnitArrayTruth units;
  ImuErrorsDrawn imu;
  std::vector<double> sun_elevation_rad;  // per compass epoch: the true H^n at the true position
};

struct NavigationDataset {
  UtcTime start;                 // t = 0
  InsState initial;              // the vehicle at t = 0 as the user knows it (truth for a simulation)
  // Set when `initial` is the dataset's own statement (start.yaml) rather than the rig's start.
  std::optional<StartSigma> stated_start;
  std::vector<ImuSample> imu;    // IMU samples, t_s the end of each interval
  std::vector<CompassEpoch> compass;
  std::vector<UnitMount> mounts;  // the units' nominal frames C_mi^b (the layout the user knows)
  std::optional<NavigationTruth> truth;
};

// What a run's simulation owes to the rig's trajectory, site and time alone, not to its seed or
// its sensors: the true trajectory (and the ideal IMU along it) and the sun at every compass epoch
// at the true position. A Monte-Carlo study makes it once and draws every trial from it.
struct NavigationScene {
  Trajectory trajectory;
  std::vector<SunPosition> sun;  // per compass epoch k, at t = (k + 1)/units.rate_hz
};
NavigationScene navigation_scene(const Rig& rig, const Progress& progress = {});

// Throws RigError (instrument_problem) unless the rig is a unit array, and std::invalid_argument
// for a trajectory ins/ refuses. Deterministic for any thread count: every deviate is counter-based.
NavigationDataset simulate_navigation(const Rig& rig, const Progress& progress = {});
// The same from a scene of this rig or of one that differs only in seed, sky radiance and
// polarization, sensors and noise (not trajectory, site, time or rates): bit-identical to the
// above. Throws std::invalid_argument when the scene's sample or epoch count is not the rig's.
NavigationDataset simulate_navigation(const Rig& rig, const NavigationScene& scene, const Progress& progress = {});

// Smoothed: the integrated filter's run after the fixed-interval RTS smoother (ins/smoother.h), a
// post-processing of the whole run (each epoch's estimate uses every reading, later ones too).
enum class NavigationMode { Sins, Pns, Integrated, Smoothed };
std::string_view navigation_mode_name(NavigationMode m);  // "sins", "pns", "integrated", "smoothed"
// A comma-separated list of "sins", "pns", "integrated", "smoothed" and "all" (sins, pns,
// integrated: the modes a vehicle has in real time) → the modes in NavigationMode's order, each
// once; throws std::invalid_argument naming the text.
std::vector<NavigationMode> parse_navigation_modes(std::string_view text);

// One mode's solution at a compass epoch.
struct NavigationFix {
  double t_s = 0;
  double lat_rad = 0, lon_rad = 0, h_m = 0;
  Euler attitude;                 // PNS: the SINS's (it has none of its own)
  std::string status = "ok";      // PNS: its fit's termination; "ok" for the INS modes
  // East, north, up (m/s): the INS modes'; NaN for PNS, which has none.
  Eigen::Vector3d v_enu = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
};

// The integrated filter at one compass epoch.
struct FilterEpoch {
  double t_s = 0;
  UnitSun sun;                     // the two units, the angle between their E-vectors, s^b, H^b
  double elevation_rad = 0;        // H^n measured (NaN without a sun)
  double model_elevation_rad = 0;  // H^n of the filter's position before the update
  ScalarUpdate update;             // the elevation's innovation, S, NIS, R (NaN when skipped or not measured)
  ScalarUpdate azimuth_update;     // the azimuth's (measurement azimuth or sun-vector), rad
  double azimuth_rad = 0;          // A^n measured, clockwise from north (NaN without a sun)
  double model_azimuth_rad = 0;    // A^n of the filter's position before the update
  double sigma_north_m = 0, sigma_east_m = 0, sigma_heading_rad = 0;  // after the update
  double corr_north_east = 0;  // the correlation of the north and east errors after the update
  // navigation.zupt: the rest detector's statistic over the reading's interval (NaN when not run)
  // and the zero-velocity update when it passed (NaN components otherwise).
  double rest_statistic = std::numeric_limits<double>::quiet_NaN();
  ZeroVelocityUpdate zero_velocity;
  // navigation.measurement pns-fix: at a window's last reading, the PNS fix taken (NaN elsewhere, or
  // without a usable fit) and its update.
  double pns_fix_lat_rad = std::numeric_limits<double>::quiet_NaN();
  double pns_fix_lon_rad = std::numeric_limits<double>::quiet_NaN();
  PositionUpdate position_update;
};

struct NavigationRun {
  std::vector<NavigationMode> modes;
  std::vector<std::vector<NavigationFix>> fixes;  // per mode in `modes`, one per compass epoch
  std::vector<FilterEpoch> filter;               // integrated only
  FilterSummary filter_summary;
  Matrix15 final_P = Matrix15::Zero();           // integrated: P after the last reading
  std::vector<Matrix15> smoothed_P;              // smoothed: Pˢ per compass epoch (to a divergence)
  int pns_usable = 0;                            // PNS epochs with a converged fix
  std::string vertical_channel;                  // vertical_channel_text
  std::string start;                             // start_text
};

struct NavigationOptions {
  std::vector<NavigationMode> modes{NavigationMode::Sins, NavigationMode::Pns, NavigationMode::Integrated};
  // The units' frames the sun is computed with (a calibration's, calibrate --method unit-array);
  // empty: the dataset's nominal mounts.
  std::vector<UnitMount> mounts;
  // The SINS mode's output rate (Hz): 0, at the compass readings (every IMU sample in a dataset
  // without them); else every 1/rate s, a rate that divides imu.rate_hz. PNS and the integrated
  // mode stay at the compass readings.
  double sins_rate_hz = 0;
};

// P0 for the dataset: initial_covariance(rig) with a stated start's attitude, velocity and position
// blocks (at its latitude) when it has one.
Matrix15 initial_covariance(const Rig& rig, const NavigationDataset& data);
// filter_settings(rig) with the held height a stated start's h (the rig's site height otherwise).
FilterSettings filter_settings(const Rig& rig, const NavigationDataset& data);

// Which vertical channel the INS modes run, for a run's output: "held  # navigation.hold_height:
// h = H m (sky.height_m), v_U = 0" (start.yaml's h_m for a stated start) or "free  #
// navigation.hold_height false: h and v_U integrated".
std::string vertical_channel_text(const Rig& rig, const NavigationDataset& data);
// Where the INS's start came from: "start.yaml" or "rig  # sky.*, trajectory.*, navigation.*_sigma ...".
std::string start_text(const NavigationDataset& data, const Rig& rig);

// Throws std::invalid_argument for a dataset whose times are not increasing, whose compass epochs
// do not fall on IMU samples (within 1 ms) or whose readings are not one per mount; for PNS or the
// integrated mode without compass readings (an IMU log alone runs SINS only); for a sins_rate_hz
// that does not divide imu.rate_hz.
NavigationRun navigate(const NavigationDataset& data, const Rig& rig, const NavigationOptions& options = {},
                       const Progress& progress = {});

// The errors of a mode against the truth (north and east in metres on the ellipsoid, angles in
// degrees), and Z21 §5's statistics of the latitude and longitude errors.
struct PositionError {
  double lat_deg = 0, lon_deg = 0, north_m = 0, east_m = 0;
};
PositionError position_error(const NavigationFix& fix, const TruthSample& truth);
// The truth at a time (within 1 ms; its samples in increasing time), or null; truth_at throws
// std::invalid_argument instead.
const TruthSample* find_truth(const NavigationTruth& truth, double t_s);
const TruthSample& truth_at(const NavigationTruth& truth, double t_s);

struct ErrorStatistics {
  double mae = 0, rmse = 0, std = 0;  // of the errors' values (deg): mean |e|, √mean e², sd about the mean
  int count = 0;                      // finite errors (PNS: usable fixes)
};
ErrorStatistics error_statistics(std::span<const double> errors);

}  // namespace polrig
