#pragma once
// The pixelated (division-of-focal-plane, DoFP) polarization camera of Han et al. 2017 (spec
// sky-and-compasses.md §2.1–2.3): a CCD behind a pinhole lens, a 2 × 2 micro-polarizer mosaic, and
// per pixel a gain K, an offset b, a polarization efficiency k and an angle error ε (Eq. 18):
//   f_j = (K_j/2)·I·[1 + k_j·d·cos(2φ − 2(α_j − ε_j))] + b_j + n_j.
//
// Frames (docs/physics.md): the camera frame l is right-handed, Z_l along the optical axis (out
// of the lens, towards the light; the zenith for a level camera looking up), X_l along the image's
// columns (+x), Y_l = Z_l × X_l along its rows (+y, the row index growing; the image is stored top
// row first). Every angle in the image (the mosaic's α_j, ε_j, a pixel's AoP φ, the view's
// azimuth α of Eq. 9) runs from X_l towards Y_l: a right-hand rotation about Z_l, as H17's
// Eqs. 6–9 take it. For a camera looking up that is anticlockwise seen from above: the sense of
// the six-photodiode sensor's frame (docs/physics.md §1, §13), and the opposite of spec §0's
// "looking into the source".
//
// Units: lengths in mm, except the pixel pitch in µm; angles in degrees at the interface; the
// intensity I is the source's S0 in its own unit, DN per that unit is K.
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "polrig/random.h"
#include "polrig/vec3.h"

namespace polrig {

// The camera's settings (the `device.*` keys of a rig with device.kind dofp-camera). Defaults:
// H17's camera (§2.1) and our choices [C] where H17 says nothing.
struct DofpCameraSpec {
  int width_px = 640;        // columns (even: whole 2 × 2 cells)
  int height_px = 480;       // rows (even)
  double pixel_um = 7.4;     // pixel pitch
  double focal_mm = 3.0;     // pinhole focal length: f_c = 405.4 px
  bool vignetting = false;   // the lens's natural cos⁴ falloff of the image irradiance
  // Analyzer axes α of the cell's four pixels (TL, TR, BL, BR), image frame: H17's (0, 90, 45, 135).
  std::array<double, 4> mosaic_deg = {0, 90, 45, 135};

  // Gain and offset per pixel: a mean and a relative (K) or absolute (b) Gaussian spread.
  double gain_DN = 2000.0;        // K: DN per unit intensity I
  double gain_spread = 0.0;       // relative SD of K over the pixels
  // A gain factor per mosaic position (TL, TR, BL, BR) [C, not in H17]: K of a pixel at position
  // j is gain_DN·mosaic_gain[j]·(1 + gain_spread·z). A systematic difference between the four
  // analyzers' transmittances (each wire grid passes a different share of unpolarized light),
  // which the circular mean of Table 1 does not average out, unlike the random spread.
  std::array<double, 4> mosaic_gain = {1, 1, 1, 1};
  double offset_DN = 0.0;         // b
  double offset_spread_DN = 0.0;  // SD of b over the pixels

  // Polarization efficiency and angle error of the four mosaic positions, with a Gaussian spread
  // per pixel; replaced by the overlap formula (spec §2.3) when a mis-registration is set.
  std::array<double, 4> k = {1, 1, 1, 1};
  std::array<double, 4> eps_deg = {0, 0, 0, 0};
  double k_spread = 0.0;
  double eps_spread_deg = 0.0;
  // Mis-registration of the polarizer mosaic against the pixels (spec §2.3's overlap formula):
  // a shift in pixels along x and y and a rotation about the image centre.
  double misregistration_dx_px = 0.0;
  double misregistration_dy_px = 0.0;
  double misregistration_rotation_deg = 0.0;
  // Extinction ratio τ_M/τ_m of the wire grids [C]: k is multiplied by (ER − 1)/(ER + 1).
  double extinction_ratio = 1e9;

  // Poisson–Gaussian noise and the ADC [C].
  bool noise = true;
  double electrons_per_DN = 10.0;   // shot noise: a signal of s DN holds s·electrons_per_DN electrons
  double read_noise_DN = 1.0;       // Gaussian read noise, SD in DN
  int adc_bits = 12;                // raw values 0 … 2^bits − 1
};

// The per-pixel truth of a camera (what calibration must recover), row-major, top row first.
struct DofpTruth {
  int width = 0, height = 0;
  std::vector<double> K, b, k, eps_deg;  // Eq. 18's K_j, b_j, k_j (extinction included), ε_j
  std::vector<double> alpha_deg;         // the nominal axis α_j of each pixel (the mosaic)
};

// ---- Pinhole geometry (spec §2.1, §2.5 Eq. 9) ----
// f_c = focal_mm / pixel_um · 1000, in pixels (H17: 405.4 px).
double focal_px(const DofpCameraSpec& spec);
// The full fields of view 2·atan(width/2 / f_c) and 2·atan(height/2 / f_c), degrees.
double fov_x_deg(const DofpCameraSpec& spec);
double fov_y_deg(const DofpCameraSpec& spec);
// The unit view direction of pixel (col, row) in frame l: its centre (col + 0.5, row + 0.5)
// against the principal point (width/2, height/2), (x, y, f_c)/|…| (Eq. 9's Rz(α)·Ry(γ)·ẑ).
Vec3 pixel_view(const DofpCameraSpec& spec, int col, int row);
// The mosaic position of a pixel: 0 TL, 1 TR, 2 BL, 3 BR of its 2 × 2 cell (H17's j − 1).
inline int mosaic_position(int col, int row) { return (row & 1) * 2 + (col & 1); }

// ---- The overlap formula (spec §2.3, derived from Eq. 16) ----
// A pixel covered by polarizers of axes α_q (image frame, degrees) with area fractions w_q
// (Σw = 1): c = Σ w_q·exp(i·2α_q), k = |c|, α − ε = ½·arg c.
struct Overlap {
  double k = 1;                // polarization efficiency (before extinction)
  double axis_deg = 0;         // ½·arg c, the effective axis α − ε, (−90°, 90°]
};
Overlap overlap(std::span<const double> weights, std::span<const double> axes_deg);
// ε = α − (α − ε), wrapped to (−90°, 90°].
double overlap_eps_deg(double alpha_deg, const Overlap& o);
// The overlap of pixel (col, row) with a mosaic mis-registered by the spec's dx, dy (pixels) and
// rotation (degrees, X_l towards Y_l, about the image centre): the mosaic's cell of column c, row r
// covers [c, c+1] × [r, r+1] in mosaic coordinates m, at pixel coordinates
// p = centre + Rot(rotation)·(m − centre) + (dx, dy); its axis is mosaic_deg[position] + rotation.
// Exact polygon clipping of the pixel square against the mosaic's cells.
Overlap misregistered_overlap(const DofpCameraSpec& spec, int col, int row);

// The per-pixel truth: K = gain·mosaic_gain[j]·(1 + gain_spread·z) (j the pixel's mosaic position), b = offset + offset_spread·z, k and ε the
// position's means (or the mis-registration's overlap, when any of dx, dy, rotation is non-zero)
// plus their spreads·z, k clamped to [0, 1] and then multiplied by (ER − 1)/(ER + 1); z are
// independent standard normals from (seed, pixel, parameter). Throws std::invalid_argument for a
// spec whose sizes are not positive and even, whose mosaic_gain is not finite and positive, or
// whose K would not be positive.
DofpTruth make_dofp_truth(const DofpCameraSpec& spec, std::uint64_t seed);

// Eq. 18 without noise: (K/2)·I·[1 + k·d·cos(2φ − 2(α − ε))] + b, angles in degrees.
double eq18_DN(double K, double b, double k, double eps_deg, double alpha_deg, double I, double d,
               double phi_deg);

// The standard normal quantile Φ⁻¹(p), p in (0, 1): Wichura's AS 241 (PPND16, relative error
// ~1e-16), the noise's deviate (through noise_deviate's table).
double normal_quantile(double p);

// Poisson–Gaussian noise and the ADC: the photo-signal s = f − b (DN, ≥ 0) holds
// λ = s·electrons_per_DN electrons, Poisson; plus Gaussian read noise; rounded and clamped to
// 0 … 2^adc_bits − 1. Poisson is drawn exactly (inversion) for λ < 32 and as N(λ, λ) above
// (the normal limit: skewness 1/√λ < 0.18). The draws are a pure function of (seed, stop, frame,
// pixel). Without spec.noise: f rounded and clamped.
std::uint16_t expose_DN(const DofpCameraSpec& spec, double f_DN, double b_DN, std::uint64_t seed,
                        std::uint64_t stop, std::uint64_t frame, std::uint64_t pixel);

// expose_DN for one frame's pixels, the hash of (seed, stop, frame) computed once: the same values.
// Inline: the frame simulation's per-pixel step.
class DofpExposure {
 public:
  DofpExposure(const DofpCameraSpec& spec, std::uint64_t seed, std::uint64_t stop, std::uint64_t frame);
  std::uint16_t operator()(double f_DN, double b_DN, std::uint64_t pixel) const {
    double v = f_DN;
    if (noise_) {
      const std::uint64_t h = detail::splitmix64(prefix_ ^ (pixel + 0x8CB92BA72F3D8DD7ull));
      const double s = f_DN > b_DN ? f_DN - b_DN : 0.0;  // the photo-signal, DN
      v = s * electrons_per_DN_ >= 32.0 ? b_DN + s + std::sqrt(s / electrons_per_DN_ + read2_) * deviate(h)
                                        : few_electrons(s, b_DN, h);
    }
    // Rounded to the nearest DN and clamped: v + 0.5 ≥ 0 truncates to its floor.
    if (!(v > -0.5)) return 0;
    if (v >= top_) return static_cast<std::uint16_t>(top_);
    return static_cast<std::uint16_t>(v + 0.5);
  }

 private:
  static constexpr int kIntervals = 4096, kExact = 64;  // noise_deviate's table
  double deviate(std::uint64_t h) const {
    const double u = (static_cast<double>(h >> 12) + 0.5) * 0x1.0p-52;  // (0, 1), never 0 or 1
    const double x = u * kIntervals;
    const int k = static_cast<int>(x);
    if (k < kExact || k >= kIntervals - kExact) return normal_quantile(u);
    const double* T = table_ + k;
    return T[0] + (x - k) * (T[1] - T[0]);
  }
  // λ < 32: exact Poisson by inversion, plus the read noise.
  double few_electrons(double s, double b_DN, std::uint64_t h) const;

  bool noise_;
  double electrons_per_DN_, read2_, read_, top_;
  std::uint64_t prefix_;
  const double* table_;
};

// The normal deviate of the noise from a uniform u in (0, 1): Φ⁻¹(u) interpolated linearly in a
// table of 4096 intervals of u (an error < 2e-5 in the deviate), exact (normal_quantile) for
// u < 1/64 and u > 63/64, so the tails are not cut.
double noise_deviate(double u);


}  // namespace polrig
