#pragma once
// The polarization each 2 × 2 unit cell of a DoFP frame measures (H17 Eqs. 3–5; with a
// calibration, Eqs. 20–22; docs/physics.md §14): per cell, with F̃_j = (f_j − b_j)/K_j and
// Ã_j = [k_j·cos 2(α_j − ε_j), k_j·sin 2(α_j − ε_j), 1],
//   Q̃ = (ÃᵀÃ)⁻¹ÃᵀF̃ = ½·[I·d·cos 2φ, I·d·sin 2φ, I]ᵀ,   φ̃ = ½·atan2(q̃2, q̃1),   d̃ = √(q̃1² + q̃2²)/q̃3.
// With the nominal parameters (K = 1, b = 0, k = 1, ε = 0) it is Eq. 4–5 on the raw DN. The cell
// (cx, cy) holds the pixels TL (2cx, 2cy), TR, BL, BR; angles in the image frame (from X_l towards
// Y_l, device/dofp_camera.h).
#include <array>
#include <span>
#include <vector>

#include "polrig/device/dofp_camera.h"

namespace polrig {

struct DofpCellPolarization {
  int cells_x = 0, cells_y = 0;
  std::vector<double> S0;       // I = 2·q̃3 (DN for the raw parameters, the source's unit once calibrated)
  std::vector<double> aop_deg;  // φ̃, [0°, 180°); NaN where the cell measures no polarization
  std::vector<double> dop;      // d̃; NaN where q̃3 ≤ 0
};

// The nominal parameters of a camera with this mosaic: K = 1, b = 0, k = 1, ε = 0 per pixel.
DofpTruth nominal_dofp_parameters(int width, int height, const std::array<double, 4>& mosaic_deg);

// Every cell of `frame` (DN, row-major, top row first, width × height) with the per-pixel
// parameters (a calibration's maps, dofp_parameter_maps or params.exr, or the nominal ones).
// A cell with a pixel of K = 0 (step 1's mark of an undetermined pixel) gets NaN. Throws
// std::invalid_argument for sizes that do not match, an odd size, a negative or non-finite
// parameter, or a cell whose analyzers do not span the Stokes plane (ÃᵀÃ singular).
DofpCellPolarization dofp_cell_polarization(std::span<const double> frame, const DofpTruth& parameters);

}  // namespace polrig
