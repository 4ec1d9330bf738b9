#pragma once
// What the real sky does to each compass (spec skies.md §5; docs/physics.md §23): the rig's compass
// looks at the exact vector-RT sky (sky/vector_rt_sky.h) and reads it with its own method, which
// assumes single scattering; the sun, heading and position line it reports are set against the
// truth. The same compass under the single-scattering sky it was built for is the reference (its
// error there is the method's own, ~0). `polrig study sky RIG` and Python's study_sky.
//
// The compass of each instrument, with its own method:
// - six-photodiode (W19): the one E-vector along the sensor's axis Z_b, the heading from W19
//   Eq. 25 with the attitude's roll and pitch known (compass/heading.h);
// - dofp-camera (H17) and four-camera (W16): the E-vectors of a grid of points over the image (the
//   DoFP camera's pinhole image; W16's fused image on camera 1's virtual pinhole grid), the sun by
//   the eigenvector method (compass/orientation.h);
// - unit-array (Z21): the units' E-vectors, the sun from the two with the highest DoP crossed
//   (compass/unit_array.h).
// Frames: the body b is the compass's own frame with Z_b its axis (up when level): RFU for W19 and
// Z21, the camera frame l for H17 and W16 (X_l along the image's columns). Its attitude C_b^n =
// Rz(−H)·Rx(0)·Ry(γ) (compass/heading.h) with the roll γ the tilt; the sun at geographic azimuth 180°
// [C], the heading H = 180° + the row's heading (relative to the sun).
//
// Errors, estimate − truth: the heading error H_est − H = A_s − A′, A′ the geographic azimuth that
// the estimated body sun s_b* has under the true attitude (the heading that puts s_b* at the sun's
// azimuth; for W19 the solved heading less the true one); the sun's elevation error asin(s_z^n*) −
// h_s; and the position line's shift 111.195 km per degree of elevation error (a single sighting's
// circle of position moves towards the sub-solar point when the sun is seen too high: W16 Eq. 17,
// Z21's PNS; R = 6371.0 km).
#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "polrig/compass/orientation.h"
#include "polrig/compass/unit_array.h"
#include "polrig/progress.h"
#include "polrig/rig/rig.h"
#include "polrig/sky/rayleigh.h"
#include "polrig/sky/vector_rt.h"
#include "polrig/vec3.h"

namespace polrig {

// How a compass turns E-vectors into a sun or a heading.
enum class SkyCompassKind {
  ZenithEVector,  // W19: one view along Z_b, Eq. 25
  Eigenvector,    // H17, W16: many views, EEᵀ's smallest eigenvector
  UnitPair        // Z21: the two highest-DoP units crossed
};

// The compass of a rig's instrument: its views in the body frame (unit, Z_b up) and, for a unit
// array, each unit's frame. Cameras: a grid of `grid_cols` points across the image (rows in
// proportion), each point a pixel centre of the real image with its pixel coordinates (for
// compass/orientation.h) in `x_px`, `y_px` and the camera in `camera`.
struct SkyCompass {
  SkyCompassKind kind = SkyCompassKind::ZenithEVector;
  std::string device;  // the rig's device.kind
  std::vector<Vec3> views_b;
  std::vector<double> x_px, y_px;  // Eigenvector only
  CameraIntrinsics camera;         // Eigenvector only
  std::vector<UnitMount> units;    // UnitPair only: the nominal frames (mounting errors are not the sky's)
};
// Throws std::invalid_argument for an instrument that reads no sky (none of the four above) or a
// grid outside [4, 2048].
SkyCompass sky_compass(const Rig& rig, int grid_cols);

// The method's variants (physics.md §23.3): what each compass publishes, and options that make
// it robust to the real sky. Not every variant applies to every compass (sky_methods()).
enum class SkyMethod {
  Published,    // the paper's method as it stands
  DopWeighted,  // eigenvector: each e·eᵀ weighted by its DoP
  MinDop,       // eigenvector: points below min_dop left out (the neutral points and the negative band)
  AllUnits      // unit array: the eigenvector method over every unit, DoP-weighted, instead of two
};
std::string_view sky_method_name(SkyMethod m);  // "published", "dop-weighted", "min-dop", "all-units"
std::vector<SkyMethod> sky_methods(SkyCompassKind kind);

struct SkyStudySettings {
  // The vector-RT skies: every τ with every albedo (sky.rt.depolarization and sky.rt.streams from
  // `rt`); the single-scattering sky of P_max beside them.
  std::vector<double> tau = {0.05, 0.1, 0.25, 0.5};
  std::vector<double> albedo = {0.0, 0.25, 0.8};
  VectorRtSettings rt;
  MaxDegree P_max;
  // The sun's elevations (degrees, each ≥ VectorRtSky::kMinSunElevationDeg and ≤ 89) and the
  // attitudes: every tilt (roll, degrees, [0, 30]) at every heading relative to the sun (degrees).
  std::vector<double> sun_el_deg = {5, 10, 15, 20, 25, 30, 35, 40, 45, 50, 55, 60, 65, 70, 75, 80, 85};
  std::vector<double> tilt_deg = {0, 5, 10};
  std::vector<double> heading_deg = {0, 45, 90, 135, 180, 225, 270, 315};
  // Noise [C]: Gaussian noise of this SD on each view's normalised Stokes q = Q/I and u = U/I
  // (the AoP's SD is then σ/(2·DoP) rad), `trials` draws per row beside the noise-free reading.
  double noise_sd = 0.01;
  int trials = 16;
  std::uint64_t seed = 0;
  double min_dop = 0.15;  // SkyMethod::MinDop
  int grid_cols = 48;     // the cameras' points across the image
  // The whole-sky statistics (E-vector error against DoP, the DoP's largest value): equal-area
  // cells, mu_cells in cos θ × 4·mu_cells in azimuth.
  int mu_cells = 45;
};
// Throws std::invalid_argument naming the setting and its value (`name` gives the CLI's option).
void check_sky_study_settings(const SkyStudySettings& s,
                              const std::function<std::string(std::string_view field)>& name =
                                  [](std::string_view f) { return std::string(f); });

// One sky: the single-scattering reference (tau, albedo NaN) or one vector-RT sky.
struct SkyCase {
  SkyKind kind = SkyKind::SingleScattering;
  double tau = NAN, albedo = NAN;
  std::string name() const;  // "single-scattering", "vector-rt"
};

// One row of bias.csv: one sky, sun, attitude and method.
struct SkyBiasRow {
  SkyCase sky;
  double sun_el_deg = 0, tilt_deg = 0, heading_deg = 0;
  SkyMethod method = SkyMethod::Published;
  // The noise-free reading: its status (the compass/ method's status name, or "antisun" where the
  // method's sign rule took the antisun, as Z21's s_z^b > 0 does for a sun near the body's
  // horizon) and errors (NaN where it gave none or took the antisun; sun_el for W19 always NaN:
  // one E-vector fixes no elevation).
  std::string status;
  double heading_error_deg = NAN, sun_el_error_deg = NAN, position_line_km = NAN;
  // Over the noisy trials that solved with the sun (not the antisun): the mean and the SD of each
  // error; `antisun` trials took the antisun.
  int trials = 0, solved = 0, antisun = 0;
  double heading_mean_deg = NAN, heading_sd_deg = NAN, sun_el_mean_deg = NAN, sun_el_sd_deg = NAN;
  // The DoP the compass saw: the mean over its views (W19: its one view).
  double mean_dop = NAN;
};

// One row of sky_dop.csv: what the sky is, whatever reads it.
struct SkyDopRow {
  SkyCase sky;
  double sun_el_deg = 0;
  double zenith_dop = NAN;
  double max_dop_sky = NAN;      // over the upper hemisphere's cells
  double max_dop_compass = NAN;  // over the level compass's views (heading 0)
  double mean_dop_compass = NAN;
};

// One row of evector_by_dop.csv (Z21 Fig. 16's axes): the vector-RT sky's AoP against the
// single-scattering sky's in the same direction, over the upper hemisphere's equal-area cells whose
// vector-RT DoP lies in [dop_lo, dop_hi).
struct EvectorByDopRow {
  SkyCase sky;
  double sun_el_deg = 0, dop_lo = 0, dop_hi = 0;
  int cells = 0;
  double mean_abs_deg = NAN, sd_abs_deg = NAN, rms_deg = NAN, max_abs_deg = NAN;
};

struct SkyStudy {
  SkyStudySettings settings;
  SkyCompass compass;
  std::vector<SkyBiasRow> bias;
  std::vector<SkyDopRow> dop;
  std::vector<EvectorByDopRow> evector_by_dop;
};

// The study: rows in the order sky (single scattering first, then τ-major, albedo), sun, tilt,
// heading, method; each a pure function of (settings, compass, its index), in parallel: identical
// for any thread count. Throws as check_sky_study_settings.
SkyStudy sky_study(const SkyCompass& compass, const SkyStudySettings& settings, const Progress& progress = {});

}  // namespace polrig
