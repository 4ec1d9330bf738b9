#pragma once
// The radiometric and polarizer-angle calibration of W16's four cameras (spec sky-and-compasses.md
// §3.3 items 1–2; docs/physics.md §16.1). The geometry (each camera's CameraGeometry) is an input,
// found first (report/four_camera_calibration_report.h): a file given, else the geometric
// calibration of the dataset's checkerboard views (calib/four_camera_geometry.h), else its truth.
//   Radiometric (item 1): per camera j, f_j = K_j·I + b_j by linear least squares of the mean DN over
//     a window about its principal point against the sphere's level I = level·intensity_per_level
//     (unpolarized stops), leaving out a level whose window holds a clipped pixel.
//   Polarizer angle (item 2): F_j = (f_j − b_j)/K_j co-registered on the virtual camera 1 by
//     device/four_camera.h's FourCameraFusion for the given geometry; at a window of virtual pixels
//     near the principal point the fused AoP φ̂ and DoP d̂ (Eqs. 3–5 with the axes φ_j + ε_j + δ_j)
//     of a polarized source turned by the table; Levenberg–Marquardt (Eigen, as calib/fit.h) with the
//     analytic Jacobian on the residuals wrap90(φ̂ − φ_m) and w·(d̂ − d_0), φ_m the port polarizer's
//     AoP at the table angle, β_m = ψ_0 + s_R·θ_R,m seen along the pixel's view. Gauge: ε_1 = 0.
// Frames (row-major DN, top row first) are width × height, the cameras' size.
#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "polrig/calib/dofp.h"
#include "polrig/calib/fit.h"
#include "polrig/device/four_camera.h"
#include "polrig/progress.h"

namespace polrig {

// Pixels [col0, col1) × [row0, row1), taking every `stride`-th column and row from (col0, row0).
struct PixelWindow {
  int col0 = 0, row0 = 0, col1 = 0, row1 = 0, stride = 1;
  int columns() const { return col1 > col0 ? (col1 - col0 + stride - 1) / stride : 0; }
  int rows() const { return row1 > row0 ? (row1 - row0 + stride - 1) / stride : 0; }
  long long pixels() const { return static_cast<long long>(columns()) * rows(); }
};
// The pixels within `half` px (in columns and rows) of the pixel holding (cx, cy) (centre convention:
// pixel col holds col ≤ cx < col + 1), clipped to the image. Throws std::invalid_argument when
// nothing is left (the point outside the image) or half < 0, stride < 1.
PixelWindow centred_window(int width, int height, double cx, double cy, int half, int stride = 1);

// ---- Radiometric (spec §3.3 item 1) ----
struct RadiometricOptions {
  // [C] 65 × 65 px about each camera's principal point: W16's K_j is one number per camera (Eq. 1
  // has no flat field), which the centre of the field defines; the light of the sphere is uniform
  // there (docs/physics.md §16.1), so the window only sets the noise: σ(mean) = σ_pixel/65.
  int window_half_px = 32;
  // A pixel at or above this (DN; the ADC's top) or at 0 clips: its level is left out of that
  // camera's fit. Infinity: no top.
  double saturation_DN = std::numeric_limits<double>::infinity();
  // The sphere's intensity at level 1 in the source's units (the rig's source.E_0: a calibrated
  // sphere's radiance), so that K_j is in DN per unit of the source's intensity as the truth's.
  double intensity_per_level = 1.0;
};

// One unpolarized level's window in one camera.
struct RadiometricLevel {
  int stop = 0;
  double level = 0;      // the stop's relative level (stops.csv's intensity)
  double intensity = 0;  // level × intensity_per_level
  double mean_DN = 0, sd_DN = 0;  // over the window's pixels (sd: the sample SD)
  long long pixels = 0, clipped = 0;
  bool used = false;     // in the fit (no clipped pixel)
};

struct CameraRadiometry {
  double K = std::numeric_limits<double>::quiet_NaN();  // DN per unit intensity
  double b = std::numeric_limits<double>::quiet_NaN();  // DN
  // Standard errors from each used level's σ(mean) = sd/√pixels, propagated through the fit.
  double K_se = std::numeric_limits<double>::quiet_NaN(), b_se = std::numeric_limits<double>::quiet_NaN();
  int rank = 0;         // of the design [I, 1] over the used levels: 2 with two distinct levels
  int levels_used = 0;
  double residual_rms_DN = std::numeric_limits<double>::quiet_NaN();  // of the window means
  PixelWindow window;
  std::vector<RadiometricLevel> levels;  // every level, used or not
  std::string message;  // why it is not usable ("" when it is)
  bool usable() const { return rank == 2 && K > 0; }
};

struct FourCameraRadiometry {
  RadiometricOptions options;
  std::array<CameraRadiometry, kFourCameras> camera;
  bool usable() const;
};

// One unpolarized stop: its level and the four cameras' frames (DN).
template <class T>
struct FourCameraFrames {
  int stop = 0;
  double theta_R_deg = 0;
  double level = 0;  // the stop's relative intensity
  std::array<std::span<const T>, kFourCameras> f;
};

// The window statistics of one level in camera j (centred_window about the camera's (cx, cy)).
template <class T>
RadiometricLevel radiometric_level(std::span<const T> frame, int width, const PixelWindow& window,
                                   const FourCameraFrames<T>& stop, const RadiometricOptions& options);
// The least-squares line through the used levels (never throws for data: rank and message say).
CameraRadiometry fit_radiometry(std::vector<RadiometricLevel> levels, const PixelWindow& window);
// Every camera from the unpolarized stops. Throws std::invalid_argument for frames of the wrong
// size, a negative or non-finite level, or no stop.
template <class T>
FourCameraRadiometry calibrate_four_camera_radiometry(const std::array<CameraGeometry, kFourCameras>& geometry,
                                                      int width, int height,
                                                      std::span<const FourCameraFrames<T>> levels,
                                                      const RadiometricOptions& options = {});

// ---- Polarizer angle (spec §3.3 item 2) ----
struct PolarizerOptions {
  // [C] virtual pixels within 16 px of the virtual camera's principal point, every second one: 17 × 17
  // samples whose bilinear footprints in each camera do not overlap (so their noise is independent
  // and the standard errors hold), 2.5° of the field, where the view's tilt terms of δ_j are small.
  int window_half_px = 16;
  int stride = 2;
  // w of the DoP residual w·(d̂ − d_0), rad per unit DoP [C]: σ_φ/σ_d = 1/(2d) ≈ 0.5 at d ≈ 1. The
  // AoP alone sees only two combinations of the four axes to first order (docs/physics.md §16.1);
  // the DoP sees the other two. 0: the spec's AoP-only cost (its fits end rank_deficient).
  double dop_weight = 0.5;
  double table_sense = kDofpTableSense;  // s_R: a fixed polarizer at ψ is seen at ψ + s_R·θ_R
  // The port polarizer seen along each pixel's view (a plane polarizer's AoP off the axis,
  // dofp_projected_aop_deg); off: every pixel sees β_m.
  bool view_projection = true;
  FitOptions fit;  // LM's limits and tolerances (its min_singular_ratio is not used: below)
  // σ_min/σ_max of the column-scaled Jacobian below this: rank deficient [C]. The well-posed fit
  // has ≈ 0.15 (12 stops); the AoP alone ≈ 6e-5, a direction the noise then moves 10⁴ times as far.
  double min_singular_ratio = 1e-3;
};

// The co-registered, radiometrically corrected samples of the window: per pixel its view (camera
// 1's frame, unit) and δ_j (degrees, FourCameraFusion::frame_offset_deg), per stop θ_R and per
// stop × pixel F_j = (f_j − b_j)/K_j sampled as the fusion samples.
struct PolarizerSamples {
  PerCamera nominal_deg{};  // φ_j
  PixelWindow window;       // on the virtual grid
  std::vector<Vec3> views;
  std::vector<PerCamera> delta_deg;
  std::vector<int> stops;
  std::vector<double> theta_R_deg;
  std::vector<std::array<double, 4>> F;  // stop-major: F[m·pixels + i]
  std::size_t pixels() const { return views.size(); }
};

// Samples the polarized stops through the fusion of `model` (its geometry; its K, b are the
// radiometric correction; its axes are not used). Throws std::invalid_argument for frames of the
// wrong size, a window pixel some camera does not see, or no stop.
template <class T>
PolarizerSamples polarizer_samples(const FourCameraModel& model, const PerCamera& nominal_deg,
                                   std::span<const FourCameraFrames<T>> stops, const PolarizerOptions& options = {},
                                   const Progress& progress = {});

// One stop's window means for polarizer.csv: the circular mean of the fused AoP (degrees, [0, 180))
// and the mean DoP and AoP residual (degrees) over the window.
struct PolarizerStopRow {
  int stop = 0;
  double theta_R_deg = 0;
  double aop_before_deg = 0, aop_after_deg = 0;
  double residual_before_deg = 0, residual_after_deg = 0;
  double dop_before = 0, dop_after = 0;
};

struct PolarizerFit {
  PerCamera eps_deg{};  // ε_1 = 0 (the gauge), ε_2..ε_4 in each camera's own frame
  PerCamera eps_se_deg{};
  double psi0_deg = 0, psi0_se_deg = 0;  // ψ_0: the polarizer's AoP at θ_R = 0 on the axis, [0°, 180°)
  double dop = 0, dop_se = 0;            // d_0 (NaN when dop_weight = 0)
  int rank = 0, unknowns = 0;
  double singular_ratio = 0;             // σ_min/σ_max of the column-scaled Jacobian
  double residual_rms_deg = std::numeric_limits<double>::quiet_NaN();  // AoP residuals, after
  double residual_rms_before_deg = std::numeric_limits<double>::quiet_NaN();  // nominal axes, ψ_0 refitted
  double dop_residual_rms = std::numeric_limits<double>::quiet_NaN();
  FitSummary summary;
  std::vector<PolarizerStopRow> stops;
  bool usable() const { return summary.usable(); }
};

// The fit. Never throws for data that cannot be fitted (the summary says why); throws
// std::invalid_argument for invalid options or samples.
PolarizerFit fit_polarizer_angles(const PolarizerSamples& samples, const PolarizerOptions& options = {});

// The model, exposed for tests: x = [ε2, ε3, ε4, ψ_0 (rad), d_0]; residuals per stop × pixel
// (stop-major), the AoP residual (rad) then the weighted DoP residual (0 when dop_weight = 0).
Eigen::VectorXd polarizer_residuals(const PolarizerSamples& samples, const Eigen::Matrix<double, 5, 1>& x,
                                    const PolarizerOptions& options);
// The analytic Jacobian: ∂x/∂a_j = G⁻¹(g_j·r_j − D_jᵀ·(g_j·x)), G = DᵀD, r = F − D·x,
// g_j = ∂D_j/∂a_j = (−2 sin 2a_j, 2 cos 2a_j, 0); rows as polarizer_residuals, columns x.
Eigen::MatrixXd polarizer_jacobian(const PolarizerSamples& samples, const Eigen::Matrix<double, 5, 1>& x,
                                   const PolarizerOptions& options);

// ---- Both, and the model they give ----
struct FourCameraCalibrationOptions {
  RadiometricOptions radiometric;
  PolarizerOptions polarizer;
  PerCamera nominal_deg = {0, 45, 90, 135};  // φ_j (W16)
};

struct FourCameraCalibration {
  FourCameraCalibrationOptions options;
  FourCameraRadiometry radiometry;
  PolarizerFit polarizer;
  FourCameraModel model;  // the geometry given, K_j, b_j, axis_deg = φ_j + ε_j
};

// Radiometric, then the polarizer angles on the corrected frames. Throws CalibrationError when the
// radiometric fit of a camera is not usable (the polarizer fit needs every K_j, b_j) or no
// polarized stop; the polarizer fit's own failure is its summary.
template <class T>
FourCameraCalibration calibrate_four_camera(const std::array<CameraGeometry, kFourCameras>& geometry, int width,
                                            int height, std::span<const FourCameraFrames<T>> levels,
                                            std::span<const FourCameraFrames<T>> polarized,
                                            const FourCameraCalibrationOptions& options = {},
                                            const Progress& progress = {});

}  // namespace polrig
