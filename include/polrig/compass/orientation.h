#pragma once
// Orientation from a DoFP camera's sky image (H17 Eqs. 6–14, spec sky-and-compasses.md §2.5):
// each point's E-vector in the camera frame, the sun vector by the eigenvector method, the two
// comparators of H17 §4.2 (single point at the zenith, line detection of the solar meridian) and
// the heading.
//
// Frames and senses (spec §0; docs/physics.md "Orientation from a DoFP camera"):
// - camera frame l: right-handed, Z_l along the optical axis (the zenith for a level camera),
//   X_l = image +x (columns), Y_l = image +y (rows grow). An image angle (a pixel's AoP φ_pix,
//   the view's azimuth α, the sun's azimuth α_S) runs from X_l towards Y_l: for a level camera
//   looking up that is anticlockwise seen from above. (device/dofp_camera.h states the same; compass/
//   takes the camera as plain numbers and never includes device/.)
// - pixel coordinates: pixel (col, row)'s centre is at (col + 0.5, row + 0.5); the principal
//   point (x_c, y_c) is in the same coordinates; a view through (x_p, y_p) is
//   (x_p − x_c, y_p − y_c, f_c) in frame l (Eq. 9: tan γ = r/f_c, α = atan2(y_p − y_c, x_p − x_c)).
// - frame i of a view (Eq. 7): C_i^l = Rz(α)·Ry(γ); Z_i along the view, X_i the direction of
//   increasing zenith angle (in the plane of Z_l and the view), Y_i that of increasing α.
// - heading H (Eq. 14 with spec §0's correction): the geographic azimuth of X_l, clockwise from
//   north seen from above, of a level camera: H = A_s + α_S, with A_s the sun's geographic azimuth
//   (sky/sun.h) and α_S its azimuth in frame l. Turning the camera by +10° anticlockwise seen from
//   above lowers H by 10°.
#include <array>
#include <optional>
#include <string_view>
#include <vector>

#include "polrig/vec3.h"

namespace polrig {

// The camera as orientation needs it. Defaults: H17's camera (spec §2.1): f_c = 3 mm / 7.4 µm,
// the principal point at the centre of 640 × 480 pixels.
struct CameraIntrinsics {
  double f_c_px = 3.0 / 7.4e-3;  // 405.405… px
  double x_c_px = 320.0;
  double y_c_px = 240.0;
};
// Throws std::invalid_argument naming the value: f_c not finite and > 0, a principal point not
// finite.
void check_intrinsics(const CameraIntrinsics& camera);

// A sky image reduced to points: each point's centre (pixel coordinates), its AoP φ_pix in the
// image frame (degrees, axial) and optionally its DoP (empty, or one per point). A NaN AoP (or,
// when DoP weighting is on, a NaN DoP) marks a point to leave out (no sky, saturated, masked).
struct SkyPoints {
  std::vector<double> x_px, y_px;
  std::vector<double> aop_deg;
  std::vector<double> dop;
};
// The points of a regular grid of cols × rows elements, row-major, top row first, each element
// `element_px` pixels wide (2: the 2 × 2 mosaic's unit cells, whose centre is the shared corner
// of their four pixels; 1: pixels). Element (c, r)'s centre is ((c + ½)·element_px,
// (r + ½)·element_px). Throws std::invalid_argument if a size is not positive or an array's
// length is not cols·rows (dop may be empty).
SkyPoints grid_points(int cols, int rows, double element_px, std::vector<double> aop_deg,
                      std::vector<double> dop = {});

// How a pixel's AoP φ_pix (image frame) becomes φ in frame i (spec §2.5 "Missing conversion").
enum class AopConversion {
  Meridional,      // φ = φ_pix − α: a rotationally symmetric lens keeps the meridional frame and the
                   // analyzer sits in the image plane (the spec's reconstruction; default)
  AnalyzerInFront  // [C] an analyzer in front of the lens: e is the normalised projection of
                   // (cos φ_pix, sin φ_pix, 0) onto the plane ⊥ the view
};
std::string_view aop_conversion_name(AopConversion c);  // "meridional", "analyzer-in-front"
std::optional<AopConversion> parse_aop_conversion(std::string_view name);

// A point's view (Eq. 9): zenith angle γ and azimuth α in frame l, radians.
struct PointView {
  double gamma_rad = 0;
  double alpha_rad = 0;
};
PointView point_view(double x_px, double y_px, const CameraIntrinsics& camera);

// The E-vector in frame l of a point whose image AoP is φ_pix (Eqs. 6–8):
// e = Rz(α)·Ry(γ)·[cos φ, sin φ, 0]ᵀ with φ = φ_pix − α (Meridional), or the projection above.
Vec3 point_e_vector(double aop_pix_deg, double x_px, double y_px, const CameraIntrinsics& camera,
                    AopConversion conversion = AopConversion::Meridional);

struct OrientationSettings {
  AopConversion conversion = AopConversion::Meridional;
  // [C] Weight each e·eᵀ in EEᵀ by the point's DoP (off by default, as H17).
  bool dop_weighting = false;
  // Points with a DoP below this are left out (0: none; needs dop). A sky at DoP ≈ 0 carries no
  // AoP (near the sun and the antisun).
  double min_dop = 0.0;
  // [C] Remove the noise bias of EEᵀ (docs/physics.md §15, "The noise bias of the eigenvector
  // method"; needs dop; replaces dop_weighting). A noisy AoP rotates e about the view v, so
  // E[e·eᵀ] = (1 − 2β)·e₀e₀ᵀ + β·(I − v·vᵀ) with β = E[sin² δ] the AoP error's: EEᵀ's null vector
  // is pulled by Σ w·β·(I − v·vᵀ), a bias that does not fall with the number of points. With
  // w = DoP² (∝ 1/var δ when the normalised Stokes noise σ is the same at every point) w·β ≈ σ²/4
  // for every point, so E[EEᵀ] = Σ w(1 − 2β)e₀e₀ᵀ + c·B, B = Σ (I − v·vᵀ), c = σ²/4 unknown: s* is
  // the generalized eigenvector EEᵀ·s = c·B·s for the smallest c (as Taubin's fit), and c gives σ.
  bool correct_noise_bias = false;
  // The solar/antisolar ambiguity (spec §2.5): s and −s fit the same E-vectors. Without a prior
  // the root with s_z > 0 (above the camera's X–Y plane) is taken [C]; with one, the root nearer
  // it (s·prior > 0). Give a prior near the horizon (e.g. the ephemeris' sun in frame l for an
  // approximate heading, or the previous frame's sun): a unit-free direction in frame l.
  std::optional<Vec3> prior_sun;
  // Without a prior, a sun within this of the camera's horizon (|elevation|, degrees) has status
  // NearHorizon: the s_z > 0 rule may have picked the antisun.
  double horizon_margin_deg = 2.0;
  // (λ₂ − λ₁)/(λ₁ + λ₂ + λ₃) of EEᵀ below this: the smallest eigenvalue's eigenvector is not
  // determined (the E-vectors all parallel, or fewer than two independent ones).
  double min_relative_gap = 1e-9;
  // Single point [C]: the points within this distance of the zenith's image (the principal point
  // of a level camera), px. 2 px holds the four unit cells around H17's principal point (a cell
  // corner), or the four pixels there.
  double zenith_radius_px = 2.0;
  // Line detection [C]: points whose φ (frame i) is within this of ±90° (on the solar meridian the
  // E-vector is ⊥ the meridian plane: φ = 90° in the local meridian frame, spec §1.2) ...
  double line_aop_tolerance_deg = 1.0;
  // ... farther than this from the principal point (near it α, hence φ, is ill-conditioned) ...
  double line_min_radius_px = 10.0;
  // ... vote for the line through the principal point at their image angle α (mod 180°), in bins
  // of this width; the peak bin and its two neighbours are refined by the axial mean of α.
  double hough_bin_deg = 0.5;
};
// Throws std::invalid_argument naming the setting and its value (a non-finite or out-of-range
// number, a zero prior).
void check_orientation_settings(const OrientationSettings& settings);

// Failures are data.
enum class SunVectorStatus {
  Ok,
  NearHorizon,    // solved, but the sun is within horizon_margin_deg of the camera's horizon and
                  // no prior chose the root: it may be the antisun
  TooFewVectors,  // fewer than two usable points (all NaN, masked, or none given)
  Degenerate      // the two smallest eigenvalues of EEᵀ coincide (relative gap < min_relative_gap)
};
std::string_view sun_vector_status_name(SunVectorStatus s);  // "ok", "near-horizon",
                                                             // "too-few-vectors", "degenerate"
inline bool has_sun(SunVectorStatus s) {
  return s == SunVectorStatus::Ok || s == SunVectorStatus::NearHorizon;
}

// Which of ±s was taken.
enum class SunRoot { None, AboveHorizon, Prior };
std::string_view sun_root_name(SunRoot r);  // "none", "above-horizon", "prior"

struct SunVectorSolution {
  SunVectorStatus status = SunVectorStatus::TooFewVectors;
  SunRoot root = SunRoot::None;
  Vec3 sun{};                   // s*, unit, frame l (zero without a solution)
  double sun_az_deg = 0;        // α_S* = atan2(s_2, s_1) (Eq. 13), from X_l towards Y_l, [0°, 360°)
  double sun_el_deg = 0;        // asin(s_3): the sun's elevation above the camera's X–Y plane
  std::array<double, 3> eigenvalues{};  // of EEᵀ, rising
  double relative_gap = 0;      // (λ₂ − λ₁)/(λ₁ + λ₂ + λ₃)
  double rms_residual = 0;      // √(λ₁/Σw): RMS of e·s* (unweighted: over the points used)
  int vectors_used = 0;
  // correct_noise_bias: the normalised Stokes noise the fit implies, σ = 2·√c (c the smallest
  // generalized eigenvalue; 0 when the data are noise-free or the correction is off).
  double stokes_noise_sd = 0;
};

// The eigenvector method (Eqs. 10–13): s* is the eigenvector of EEᵀ = Σ w·e·eᵀ for its smallest
// eigenvalue (Eigen's SelfAdjointEigenSolver on the 3 × 3 matrix), w = 1 or the DoP; with
// correct_noise_bias, w = DoP² and s* solves EEᵀ·s = c·B·s (Eigen's
// GeneralizedSelfAdjointEigenSolver). Points whose AoP, position (or, with weighting, the
// correction or min_dop, DoP) is not finite are left out.
// Throws std::invalid_argument for inconsistent array lengths, bad intrinsics or settings.
SunVectorSolution sun_vector_eigen(const SkyPoints& points, const CameraIntrinsics& camera,
                                   const OrientationSettings& settings = {});

// The comparators give the solar meridian (an axis, mod 180°); a prior sun azimuth (frame l)
// picks the half that holds the sun.
enum class SunAzimuthStatus {
  Ok,
  Ambiguous180,  // no prior: sun_az_deg is the meridian's angle in [0°, 180°); the sun may be at
                 // sun_az_deg + 180°
  NoPoints,      // no usable point (single point: none within zenith_radius_px; line: none on the
                 // meridian band)
};
std::string_view sun_azimuth_status_name(SunAzimuthStatus s);  // "ok", "ambiguous-180", "no-points"

struct SunAzimuthSolution {
  SunAzimuthStatus status = SunAzimuthStatus::NoPoints;
  double sun_az_deg = 0;    // α_S in frame l, [0°, 360°) (see Ambiguous180)
  double meridian_deg = 0;  // the solar meridian's image angle, [0°, 180°)
  int points_used = 0;      // single point: the zenith points; line: the points in the peak's bins
  int points_selected = 0;  // line: the points on the ±90° band (all votes); single point: = used
};

// Single point (H17 §4.2, its ref. [34]): the zenith points' E-vectors are ⊥ the solar meridian:
// the meridian is at the axial mean of their image angles atan2(e_y, e_x) plus 90°.
SunAzimuthSolution sun_azimuth_single_point(const SkyPoints& points, const CameraIntrinsics& camera,
                                            const OrientationSettings& settings = {},
                                            std::optional<double> prior_sun_az_deg = std::nullopt);

// Line detection (H17 §4.2, its ref. [20]): the points with φ ≈ ±90° lie on the solar meridian,
// whose image for a level camera is a line through the principal point (the zenith's image): a
// Hough accumulator over that line's angle, then the axial mean of α in the peak's bins.
SunAzimuthSolution sun_azimuth_line(const SkyPoints& points, const CameraIntrinsics& camera,
                                    const OrientationSettings& settings = {},
                                    std::optional<double> prior_sun_az_deg = std::nullopt);

// Eq. 14 in the sense of spec §0: the heading of a level camera (the geographic azimuth of X_l,
// clockwise from north) from the sun's geographic azimuth A_s and its azimuth α_S in frame l
// (anticlockwise seen from above): H = A_s + α_S, wrapped to [0°, 360°).
double camera_heading_deg(double sun_azimuth_geo_deg, double sun_az_camera_deg);

// The sun in frame l of a level camera with heading H (the inverse of camera_heading_deg, with
// the sun's elevation h_s): (cos h_s·cos α_S, cos h_s·sin α_S, sin h_s), α_S = H − A_s. A prior
// for the ambiguity from the ephemeris and an approximate heading.
Vec3 sun_in_level_camera(double sun_azimuth_geo_deg, double sun_elevation_deg, double heading_deg);

// One frame through the three methods.
enum class OrientationMethod { Eigenvector, SinglePoint, LineDetection };
std::string_view orientation_method_name(OrientationMethod m);  // "eigenvector", "single-point",
                                                                // "line-detection"
struct OrientationEstimate {
  OrientationMethod method = OrientationMethod::Eigenvector;
  std::string_view status;  // the method's status name
  bool solved = false;      // a sun azimuth was found and its half of the meridian chosen
  double sun_az_deg = 0;    // frame l
  std::optional<double> sun_el_deg;   // the eigenvector method only
  std::optional<double> heading_deg;  // when solved and the sun's geographic azimuth is known
};
// The eigenvector method, then the comparators with the eigenvector's sun azimuth as their prior
// (when it has a sun; else the settings' prior_sun's azimuth, if any). sun_azimuth_geo_deg: A_s
// from the ephemeris (sky/sun.h) at the frame's time, if known.
std::array<OrientationEstimate, 3> orient_frame(const SkyPoints& points,
                                                const CameraIntrinsics& camera,
                                                std::optional<double> sun_azimuth_geo_deg,
                                                const OrientationSettings& settings = {});

}  // namespace polrig
