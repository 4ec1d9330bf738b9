#pragma once
// The four-camera polarization-vision sensor of Wang et al. 2016 (W16; spec sky-and-compasses.md
// §3.1–3.2, docs/physics.md §16): four Smartek GC1031CP cameras (Sony ICX204, 1034 × 778 px,
// 4.65 µm pitch) with f = 3.5 mm lenses on the corners of a square, parallel axes, a linear
// polarizer in front of each CCD at φ_j = 0°, 45°, 90°, 135° (W16's order) with a mounting error
// ε_j, a gain K_j and an offset b_j (Eq. 1, with the offset [C]):
//   f_j = K_j·I·[1 + d·cos(2φ − 2(φ_j + ε_j))] + b_j + noise.
//
// Frames: camera j's frame is right-handed, X_j along the image's columns (+x), Y_j along its rows
// (+y), Z_j the optical axis (as DofpCameraSpec's frame l). Camera 1 defines the sensor's frame
// (spec §3.1). Every image angle (φ_j, ε_j, a pixel's AoP φ) runs from X towards Y. Camera j's
// rotation R_j1 maps a direction in camera 1's coordinates to camera j's: v_j = R_j1·v_1 (as
// OpenCV's stereoCalibrate R); it is given as its rotation vector (Rodrigues), degrees.
//
// The lens: OpenCV's fisheye model (Kannala–Brandt) [C]: a ray at angle θ from the optical axis
// and azimuth α lands at radius r_d = θ_d in normalised units, θ_d = θ(1 + k1θ² + k2θ⁴ + k3θ⁶ +
// k4θ⁸), pixel (u, v) = (f_x·θ_d·cos α + c_x, f_y·θ_d·sin α + c_y). With k = 0 it is the
// equidistant projection r = f·θ that fits W16's stated field (77° × 57.7°) with f ≈ 770 px at both
// the width and the height, which no pinhole does (spec §3.1; docs/physics.md §16). Pixel
// (col, row)'s centre is at (col + ½, row + ½), as for the DoFP camera and compass/orientation.h.
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "polrig/device/dofp_camera.h"
#include "polrig/vec3.h"

namespace polrig {

inline constexpr int kFourCameras = 4;
using PerCamera = std::array<double, kFourCameras>;

// The sensor's settings (the `device.*` keys of a rig with device.kind four-camera). Defaults:
// W16's hardware where it says, our choices [C] where it does not (docs/physics.md §16).
struct FourCameraSpec {
  int width_px = 1034;   // W16 §2.1: 1034 × 778
  int height_px = 778;
  double pixel_um = 4.65;  // Sony ICX204's cell (the GC1031CP's CCD); f_mm = f_px·pixel_um/1000
  // Polarizer axes φ_j (W16: 0, 45, 90, 135) and their mounting errors ε_j [C], camera j's frame.
  PerCamera polarizer_deg = {0, 45, 90, 135};
  PerCamera eps_deg = {0.0, 0.4, -0.3, 0.6};
  // Gains K_j (DN per unit of the source's intensity) and offsets b_j (DN) [C].
  PerCamera gain_DN = {1200, 1236, 1176, 1218};
  PerCamera offset_DN = {20, 24, 18, 22};
  // Intrinsics in px [C]: f ≈ 770 px fits the stated field with the equidistant lens (3.58 mm at
  // 4.65 µm; the nominal 3.5 mm gives 752.7 px); the principal point near the centre (517, 389).
  PerCamera fx_px = {770.0, 771.2, 768.9, 770.6};
  PerCamera fy_px = {770.0, 771.2, 768.9, 770.6};
  PerCamera cx_px = {517.0, 518.4, 515.7, 517.9};
  PerCamera cy_px = {389.0, 387.8, 390.3, 388.6};
  // Kannala–Brandt coefficients [C] (0: the equidistant projection).
  PerCamera k1 = {0, 0, 0, 0}, k2 = {0, 0, 0, 0}, k3 = {0, 0, 0, 0}, k4 = {0, 0, 0, 0};
  // R_j1's rotation vector, degrees [C]: small misalignments; camera 1's is zero by definition.
  PerCamera rot_x_deg = {0.0, 0.30, -0.20, 0.15};
  PerCamera rot_y_deg = {0.0, -0.15, 0.25, 0.20};
  PerCamera rot_z_deg = {0.0, 0.50, -0.40, 0.30};
  // The square's side [C]: camera j's centre at (0, 0), (a, 0), (a, a), (0, a) in camera 1's X, Y
  // (mm). The sky is at infinity: recorded as truth, it moves no pixel (spec §3.2).
  double baseline_mm = 60.0;
  // Poisson–Gaussian noise and the ADC [C], as the DoFP camera's (DofpExposure).
  bool noise = true;
  double electrons_per_DN = 10.0;
  double read_noise_DN = 1.0;
  int adc_bits = 12;  // the GC1031CP digitises to 8 or 12 bits
};

// The largest |k_i| of a lens polrig takes: W16's lens has k ≈ 0; a fit beyond is not a lens
// (calibration.yaml's range, and where a geometric fit is called failed).
inline constexpr double kMaxKannalaBrandtK = 10;

// One camera's geometry: intrinsics, distortion and R_j1 (row-major 3 × 3).
struct CameraGeometry {
  double fx = 770, fy = 770, cx = 517, cy = 389;
  std::array<double, 4> k = {0, 0, 0, 0};
  std::array<double, 9> R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
};

// The per-camera model the simulation and the fusion use: the truth of a spec, or later a
// calibration's estimate. axis_deg = φ_j + ε_j, the polarizer's axis in camera j's frame.
struct FourCameraModel {
  int width = 0, height = 0;
  std::array<CameraGeometry, kFourCameras> camera;
  PerCamera K{}, b{}, axis_deg{};
};

// The spec's truth. Throws std::invalid_argument for a spec whose geometry cannot be simulated (a
// non-positive size, focal length or gain, camera 1 rotated, a lens whose θ_d is not increasing
// over the field).
FourCameraModel four_camera_truth(const FourCameraSpec& spec);
// The rotation matrix of a rotation vector r (radians): Rodrigues' formula, row-major.
std::array<double, 9> rotation_from_vector(const Vec3& r);
// Camera j's centre in camera 1's frame, mm (the square, spec §3.1).
Vec3 camera_position_mm(const FourCameraSpec& spec, int j);

// ---- The fisheye lens (Kannala–Brandt, OpenCV's cv::fisheye) ----
// θ_d(θ) and its inverse (Newton from θ = θ_d; throws nothing: returns NaN when no θ in
// [0, π) maps to θ_d).
double kb_theta_d(const std::array<double, 4>& k, double theta);
double kb_theta(const std::array<double, 4>& k, double theta_d);
// The pixel (continuous, centre convention) where direction v (camera j's frame, v_z > 0 needed:
// else NaN) lands.
std::array<double, 2> project(const CameraGeometry& c, const Vec3& v);
// The unit view direction of the continuous pixel position (u, v) (camera j's frame).
Vec3 unproject(const CameraGeometry& c, double u, double v);
// The full fields of view of a camera, degrees: 2·θ at the image's half width and half height
// from its principal point along the axes (W16: 77° × 57.7°).
double four_camera_fov_x_deg(const FourCameraModel& m, int j);
double four_camera_fov_y_deg(const FourCameraModel& m, int j);

// The image-plane AoP φ_pix (radians, image frame of a camera whose view is v, unit, its own
// frame) of an E-vector e (same frame): the meridional conversion φ_pix = φ_i + α (spec §3.4 as
// §2.5; the polarizer sits in front of the CCD, the lens keeps the meridional frame).
double image_plane_aop_rad(const Vec3& v, const Vec3& e);

// ---- Fusion (spec §3.2 Eqs. 3–5) ----
// The least-squares inverse (DᵀD)⁻¹Dᵀ of D_j = [cos 2φ_j, sin 2φ_j, 1] for four axes (degrees):
// x = W·F, row-major 3 × 4. Throws std::invalid_argument when DᵀD is singular (fewer than three
// distinct axes mod 180°).
std::array<double, 12> fusion_matrix(const PerCamera& axis_deg);
// x = (I·d·cos 2φ, I·d·sin 2φ, I) from F_j = (f_j − b_j)/K_j.
struct FusedStokes {
  double S1 = 0, S2 = 0, S0 = 0;
};
inline FusedStokes fuse_pixel(const std::array<double, 12>& W, const std::array<double, 4>& F) {
  return {W[0] * F[0] + W[1] * F[1] + W[2] * F[2] + W[3] * F[3],
          W[4] * F[0] + W[5] * F[1] + W[6] * F[2] + W[7] * F[3],
          W[8] * F[0] + W[9] * F[1] + W[10] * F[2] + W[11] * F[3]};
}

// The virtual camera 1: camera 1's undistorted pinhole grid (same size, f_c = f_x of camera 1,
// principal point (c_x, c_y) of camera 1), the image the fused layers and the eigenvector method
// (compass/orientation.h, W16 Eqs. 6–8) use.
struct VirtualCamera {
  int width = 0, height = 0;
  double f_c = 0, cx = 0, cy = 0;
};
VirtualCamera virtual_camera(const FourCameraModel& m);

// The fused image on the virtual grid (float, row-major, top row first): S0, S1, S2 (reference
// X of camera 1), AoP = ½·atan2(S2, S1) in [0°, 180°), DoP = √(S1² + S2²)/S0 (Eq. 5), and
// `valid` (1 where all four cameras see the pixel and S0 > 0; elsewhere every layer 0).
struct FusedImage {
  VirtualCamera grid;
  std::vector<float> S0, S1, S2, AoP, DoP;
  std::vector<std::uint8_t> valid;
};

// Co-registration and fusion: each virtual pixel's ray (camera 1's frame) into camera j by R_j1,
// through camera j's lens (the infinite homography p_j ∝ K_j·R_j1·K_1⁻¹·p with the distortion,
// spec §3.2), camera j's F_j = (f_j − b_j)/K_j sampled bilinearly at that point (pixel centres;
// outside the outermost centres: not seen), then Eqs. 3–5 per pixel with the model's axes taken
// into camera 1's image frame at that ray: axis_deg[j] + δ_j(p), δ_j(p) the angle between camera
// j's and camera 1's image-plane frames about the common ray (a pure offset for a given ray, since
// both are frames of the plane ⊥ the ray; zero for aligned cameras, about the roll for a small
// misalignment plus tilt terms that grow off axis: up to 0.05° in AoP for W16-sized default
// misalignments if ignored, so it is not).
// `frames[j]` holds camera j's signal (DN; raw or noise-free), width × height each. TBB over chunks of pixels.
// fuse() runs in float and in SIMD lanes with the per-pixel (DᵀD)⁻¹Dᵀ precomputed (docs/physics.md
// §16 "Fusion" gives its error against fuse_at's double precision); the same bits for any thread
// count and on every x86-64 CPU (src/device/four_camera_lanes.cpp).
namespace detail {
// FourCameraFusion's per-pixel constants of kFusionChunk consecutive virtual pixels (row-major
// i = chunk·kFusionChunk + k), stored by quantity so that fuse() streams one array and loads whole
// SIMD vectors (a multiple of every target's lane count).
inline constexpr std::size_t kFusionChunk = 64;
struct alignas(64) FusionChunk {
  // Camera j's top-left tap (−1: not seen; also beyond the last pixel) and its bilinear weights
  // (float: an error ≤ 2⁻²⁴ of a pixel-to-pixel difference).
  std::int32_t index[kFourCameras][kFusionChunk];
  float wx[kFourCameras][kFusionChunk], wy[kFourCameras][kFusionChunk];
  // Eq. 4's W = (DᵀD)⁻¹Dᵀ at the pixel (with its δ_j), rows S1, S2, S0, columns 1–3 (float): since
  // W's rows sum to 0, 0, 1, x_r = Σ_{j<4} W_rj·(F_j − F_4) + [r = S0]·F_4.
  float W[9][kFusionChunk];
};
}  // namespace detail

class FourCameraFusion {
 public:
  explicit FourCameraFusion(const FourCameraModel& model);
  const VirtualCamera& grid() const { return grid_; }
  // δ_j at virtual pixel i (row-major), degrees.
  double frame_offset_deg(int j, std::size_t i) const;
  template <class T>
  FusedImage fuse(const std::array<std::span<const T>, kFourCameras>& frames) const;
  // One virtual pixel (row-major index i) in double precision: false where a camera does not see it.
  template <class T>
  bool fuse_at(const std::array<std::span<const T>, kFourCameras>& frames, std::size_t i, FusedStokes& x) const;

 private:
  FourCameraModel model_;
  VirtualCamera grid_;
  PerCamera cos2a_{}, sin2a_{};
  // The taps, weights and W of every virtual pixel, by chunks.
  std::vector<detail::FusionChunk> chunks_;
  // cos 2δ_j, sin 2δ_j of cameras 2–4 per virtual pixel (float; camera 1's δ is 0), for fuse_at.
  std::vector<std::array<float, 6>> offsets_;
};

extern template bool FourCameraFusion::fuse_at<std::uint16_t>(
    const std::array<std::span<const std::uint16_t>, kFourCameras>&, std::size_t, FusedStokes&) const;
extern template bool FourCameraFusion::fuse_at<double>(const std::array<std::span<const double>, kFourCameras>&,
                                                       std::size_t, FusedStokes&) const;
extern template FusedImage FourCameraFusion::fuse<std::uint16_t>(
    const std::array<std::span<const std::uint16_t>, kFourCameras>&) const;
extern template FusedImage FourCameraFusion::fuse<double>(
    const std::array<std::span<const double>, kFourCameras>&) const;

// The noise and ADC settings as the DoFP camera's exposure reads them (DofpExposure: reused, not
// copied).
DofpCameraSpec exposure_spec(const FourCameraSpec& spec);

}  // namespace polrig
