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
// azimuth α of Eq. 9) runs from X_l towards Y_l: a right-hand rotation about the view, as H17's
// Eqs. 6–9 take it (the six-photodiode sensor's angles run the other way: docs/physics.md §1).
//
// Units: lengths in mm, except the pixel pitch in µm; angles in degrees at the interface; the
// intensity I is the source's S0 in its own unit, DN per that unit is K.
#include <array>
#include <cstdint>
#include <vector>

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

}  // namespace polrig
