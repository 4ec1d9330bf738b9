#pragma once
// The two-step calibration of the pixelated (DoFP) polarization camera of Han et al. 2017
// (spec sky-and-compasses.md §2.4; docs/physics.md §14):
//   step 1 (Eq. 19): per pixel, gain K and offset b by linear least squares from uniform
//     unpolarized frames, f = K·I/2 + b;
//   step 2 (Eqs. 20–29): per 2 × 2 unit cell (or one global set), the polarization efficiencies
//     k_2..k_4 and angle errors ε_2..ε_4 (gauge k_1 = 1, ε_1 = 0), the reference angle ψ_0 and
//     the source's DoP d_0, by Levenberg–Marquardt with the analytic Jacobian, from frames of a
//     polarized source turned by the table: residuals r_m = wrap90(φ̃_m − ψ_0 − s_R·θ_R,m) and
//     [C] w·(d̃_m − d_0);
//   Table 1 (spec §2.5 "Indoor orientation"): the orientation error of the circular mean AoP
//     before calibration, after step 1 and after step 2.
// Frames are row-major DN, top row first, width × height (the camera's frame convention,
// device/dofp_camera.h); the cell (cx, cy) holds the pixels TL (2cx, 2cy), TR (2cx+1, 2cy),
// BL (2cx, 2cy+1), BR (2cx+1, 2cy+1), whose axes are DofpCameraSpec::mosaic_deg in that order.
#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "polrig/calib/fit.h"
#include "polrig/device/dofp_camera.h"
#include "polrig/progress.h"

namespace polrig {

// s_R: how a table turn θ_R shows in the image. The table turns the camera clockwise seen from
// above (anticlockwise seen from the camera looking up, docs/physics.md §1), and image angles
// run from X_l towards Y_l, anticlockwise seen from above for a camera looking up, so a fixed
// polarizer at ψ is seen at φ = ψ + θ_R: the same sense as the six-photodiode sensor's
// θ = θ_R − ψ_P. docs/physics.md §14.
inline constexpr double kDofpTableSense = +1.0;

// One uniform unpolarized level of step 1: its relative intensity I^i (the source's S0, any
// unit; I_j^i = I^i/2 behind the analyzer) and the mean of its frames.
struct DofpUnpolarizedLevel {
  double intensity = 0;
  std::span<const double> frame;
};

// One stop of step 2: the table angle θ_R (degrees), the source's relative intensity (to pick
// Table 1's stops) and the stop's (mean) frame.
struct DofpPolarizedStop {
  double theta_R_deg = 0;
  double intensity = 0;
  std::span<const double> frame;
};

struct DofpStep1Options {
  // A pixel's value at or above this (DN) is left out of its fit (a saturated level); the
  // default keeps every level.
  double saturation_DN = std::numeric_limits<double>::infinity();
};

// Step 1's result per pixel (row-major). rank is the rank of the pixel's design [I/2, 1]:
// 2 with at least two distinct levels, 1 with one, 0 with none. A pixel with rank < 2 is
// undetermined: it gets K = 0, b = 0 and residual 0 (never a division by zero), and step 2
// reports its cell rank deficient.
struct DofpStep1 {
  int width = 0, height = 0;
  std::vector<double> K;                // DN per unit intensity
  std::vector<double> b;                // DN
  std::vector<double> residual_rms_DN;  // √(Σ(K·I/2 + b − f)²/n) over the levels used
  std::vector<std::uint8_t> rank;       // 0, 1 or 2
  std::vector<std::uint16_t> levels_used;
  long long rank_deficient_pixels = 0;
};

// Step 1 (Eq. 19). Throws std::invalid_argument naming the level for a frame of the wrong size
// or a non-finite value, a non-finite or negative intensity, or an odd or empty frame.
DofpStep1 calibrate_dofp_step1(int width, int height, std::span<const DofpUnpolarizedLevel> levels,
                               const DofpStep1Options& options = {});

enum class DofpStep2Scope { PerCell, Global };
// "per-cell", "global"; parse_dofp_scope throws std::invalid_argument for anything else.
std::string dofp_scope_name(DofpStep2Scope s);
DofpStep2Scope parse_dofp_scope(const std::string& name);

struct DofpStep2Options {
  DofpStep2Scope scope = DofpStep2Scope::PerCell;  // [C] per cell (H17 does not say)
  std::array<double, 4> mosaic_deg = {0, 90, 45, 135};  // α_j of TL, TR, BL, BR (DofpCameraSpec)
  double table_sense = kDofpTableSense;                 // s_R: +1 or −1
  int max_iterations = 50;         // spec §2.4 [C]
  double step_tolerance = 1e-10;   // converged when |Δx| < this (ε, ψ_0 in rad; k unitless)
  int max_halvings = 30;           // step halvings when a Gauss–Newton step raises the cost
  // σ_min/σ_max of the column-scaled Jacobian below this: rank deficient. JᵀJ is what is
  // decomposed, so the ratio is resolved down to about √ε_double ≈ 1e-8.
  double min_singular_ratio = 1e-6;
  // H17's AoP residual alone cannot determine (k, ε) (docs/physics.md §14): only 3 of its 7
  // unknowns at a solution. Two more residuals per observation [C, not in H17] make the fit
  // well posed (8 of 8):
  //  - w·(d̃_m − d_0): the source's DoP is the same at every stop (d_0 an unknown); w in rad per
  //    unit DoP, 0.5 ≈ σ_φ/σ_d = 1/(2d) at d ≈ 1;
  //  - w_e·n̂ᵀF̃_m/q̃3,m: Eq. 21's least-squares residual (n̂ ⊥ Ã's columns), relative to the
  //    intensity: the model must explain the four pixel values, not only their angle.
  // Both 0: H17's cost; its fits end rank_deficient.
  double dop_weight = 0.5;
  double fit_weight = 1.0;
  // Weight each stop's residuals by I_m/I_max [C]: with a constant pixel noise the AoP's and the
  // DoP's noise grow as 1/I, so this is the weighted least squares; it keeps the dim stops'
  // nonlinear (Rician) biases out of (k, ε). false: H17's equal weights.
  bool weight_by_intensity = true;
  // The view's projection [C, not in H17] (docs/physics.md §14). Off: H17's model, every cell
  // sees the port polarizer at β_m = ψ_0 + s_R·θ_R,m, with ψ_0 per cell and the gauge ε_1 = 0.
  // On: each pixel, seen along its own view v (pinhole: focal_px and the principal point; the
  // analyzer in the image plane), sees φ_m = arg(M·(cos β_m, sin β_m)),
  // M = I₂ − (v_x, v_y)(v_x, v_y)ᵀ/(1 + v_z): a plane polarizer's AoP off the axis (tan φ =
  // tan β / cos γ along the azimuth 0). φ is nonlinear in β, so ε_1 is no longer a gauge: one ψ_0
  // for the whole image (one port polarizer; DofpStep2::psi0_fit) and every ε_1..ε_4 per cell.
  // Table 1 then maps each cell's AoP back to the port plane before the mean (all three rows).
  // Needs focal_px > 0; NaN principal point: the image centre (width/2, height/2).
  bool view_projection = false;
  double focal_px = 0;
  double principal_x_px = std::numeric_limits<double>::quiet_NaN();
  double principal_y_px = std::numeric_limits<double>::quiet_NaN();
  // With view_projection: NaN fits ψ_0 (degrees); a finite value holds it there, so that one pass
  // of the ψ_0 fit can run on a band of rows (DofpStep2::psi0_rows, dofp_fit_psi0).
  double psi0_deg = std::numeric_limits<double>::quiet_NaN();
  // With view_projection and per-cell scope, optional: the previous pass's fits of these cells
  // (row-major, every cell), each usable one the start of its cell's fit at the new ψ_0.
  std::span<const struct DofpCellFit> start_cells;
};

// The AoP (degrees, image frame from X_l towards Y_l) that an analyzer in the image plane sees of
// a plane polarizer whose axis lies ⊥ Z_l at psi_deg from X_l, along the unit view v (frame l,
// v_z > 0): arg(M·(cos ψ, sin ψ)), M = I₂ − (v_x, v_y)(v_x, v_y)ᵀ/(1 + v_z) (docs/physics.md §14).
double dofp_projected_aop_deg(const Vec3& view, double psi_deg);
// The view through the centre of pixel (col, row), the one step 2's projected model uses: the unit
// vector (col + ½ − x_c, row + ½ − y_c, f_c) in frame l, with the options' focal length and principal
// point (NaN: the image centre; device/dofp_camera.h's pixel_view). Throws std::invalid_argument
// when focal_px is not positive.
Vec3 dofp_pixel_view(int width, int height, const DofpStep2Options& options, int col, int row);

// One cell's (or the global) fit: the parameters of its four pixels and how the fit ended,
// after calib/fit.h's FitSummary. Only usable() cells have parameters to use; the others hold
// where the fit stopped (k = 1, ε = 0 if it never ran), and dofp_parameter_maps puts the ideal
// k = 1, ε = 0 there.
struct DofpCellFit {
  std::array<double, 4> k = {1, 1, 1, 1};
  std::array<double, 4> eps_deg = {0, 0, 0, 0};  // ε_1 = 0 (the gauge) unless view_projection
  double psi0_deg = 0;  // ψ_0: the AoP at θ_R = 0 (image frame, (−90°, 90°]); the image's one
                        // ψ_0 with view_projection
  double dop = std::numeric_limits<double>::quiet_NaN();  // d_0, the source's DoP (NaN if w = 0)
  FitTermination termination = FitTermination::TooFewObservations;
  std::string message;  // why a fit did not converge ("" when it did)
  int iterations = 0;   // Gauss–Newton steps taken
  int rank = 0;         // rank of J (of 8 unknowns with the DoP residual, else of 7)
  int observations = 0;
  double initial_rms_deg = std::numeric_limits<double>::quiet_NaN();  // at the start
  double final_rms_deg = std::numeric_limits<double>::quiet_NaN();    // √(Σr²/N) at the end
  // (both: of the AoP residuals r_m, m over the N observations)
  bool usable() const { return termination == FitTermination::Converged; }
};

// One pass of the ψ_0 fit (view_projection): every cell fitted with ψ_0 held, and the Gauss–Newton
// normal equation of ψ_0 reduced over each fit's own unknowns (a Schur complement), summed over
// the usable fits. Sums over bands of rows add up to the whole image's.
struct DofpPsi0Pass {
  double gradient = 0;   // Σ (J_ψᵀr − J_ψᵀJ_x·(J_xᵀJ_x)⁻¹·J_xᵀr)
  double curvature = 0;  // Σ (J_ψᵀJ_ψ − J_ψᵀJ_x·(J_xᵀJ_x)⁻¹·J_xᵀJ_ψ)
  double raw_curvature = 0;  // Σ J_ψᵀJ_ψ (how much of ψ_0's signal the fits' own unknowns leave)
  double cost = 0;       // Σ r² of the usable fits
  long long fits = 0;    // usable fits summed
  void add(const DofpPsi0Pass& o) {
    gradient += o.gradient, curvature += o.curvature, raw_curvature += o.raw_curvature;
    cost += o.cost, fits += o.fits;
  }
};

struct DofpStep2 {
  DofpStep2Scope scope = DofpStep2Scope::PerCell;
  int cells_x = 0, cells_y = 0;
  std::vector<DofpCellFit> cells;  // cells_y × cells_x, row-major; one entry when Global
  long long usable_cells = 0;
  // view_projection only: how the fit of the image's one ψ_0 ended (calib/fit.h's convention; its
  // costs are ½·Σr² in rad²), and the last pass's sums (at options.psi0_deg when that was given).
  FitSummary psi0_fit;
  double psi0_deg = std::numeric_limits<double>::quiet_NaN();
  DofpPsi0Pass psi0_pass;                 // = dofp_sum(psi0_rows)
  std::vector<DofpPsi0Pass> psi0_rows;    // per cell row (one entry with the global scope)
};
// The rows' sums added in row order from zero: the same bits for any split into bands.
DofpPsi0Pass dofp_sum(std::span<const DofpPsi0Pass> rows);

// The ψ_0 fit's outer loop (Gauss–Newton on ψ_0, every fit's own unknowns re-fitted at each ψ_0;
// halving a step that raises the cost): `pass(ψ_0 in degrees)` fits every cell there. Ends
// converged when |Δψ_0| < step_tolerance (rad), rank_deficient when the reduced curvature is below
// min_singular_ratio² of the raw one (a narrow field: ψ_0 and ε_1 cannot be told apart). The last
// pass run is at the returned ψ_0 (psi0_deg).
FitSummary dofp_fit_psi0(const std::function<DofpPsi0Pass(double)>& pass, double start_deg,
                         const DofpStep2Options& options, double& psi0_deg);
// The start of that loop: ½·arg Σ exp(2i·ψ̂_c) over the cells' closed-form starts ψ̂_c (H17's gauge,
// where ψ̂_c = ψ_0 + ε_1 near the axis), as the sums (Σ cos 2ψ̂_c, Σ sin 2ψ̂_c) per cell row (add
// them in row order, as dofp_sum).
std::vector<std::array<double, 2>> dofp_psi0_start_rows(const DofpStep1& step1,
                                                        std::span<const DofpPolarizedStop> stops,
                                                        const DofpStep2Options& options);
// ½·arg of those sums added in row order (degrees).
double dofp_psi0_start_deg(std::span<const std::array<double, 2>> rows);

// Step 2 (Eqs. 20–29), in parallel over cells (TBB), bit-identical for any thread count.
// Throws std::invalid_argument for bad input (sizes, non-finite values, a table_sense other
// than ±1, non-positive limits); data that cannot be fitted is a cell's termination instead.
DofpStep2 calibrate_dofp_step2(const DofpStep1& step1, std::span<const DofpPolarizedStop> stops,
                               const DofpStep2Options& options = {},
                               const Progress& progress = {});

// Table 1 (spec §2.5 "Indoor orientation", §2.6): per stop of one intensity, the orientation is
// the circular mean over the cells, o = ½·arg Σ exp(i·2φ̃); its error is
// wrap90((o_m − o_0) − s_R·(θ_R,m − θ_R,0)), m = 1..N, stop 0 the first of those stops.
struct DofpOrientationRow {
  std::string name;                // "raw", "step1", "step2"
  std::vector<double> error_deg;   // per stop m = 1..N
  double max_deg = 0;   // max |error|
  double mean_deg = 0;  // mean error (signed)
  double std_deg = 0;   // sample SD (N − 1)
};
struct DofpTable1 {
  double intensity = 0;              // the stops' intensity (the largest unless chosen)
  std::vector<double> theta_R_deg;   // the stops m = 1..N (table angle)
  long long cells_used = 0;          // cells with every pixel determined and step 2 usable
  std::array<DofpOrientationRow, 3> rows;  // raw, step1, step2
};

// raw: F = f (nominal K = 1, b = 0), ideal k = 1, ε = 0; step1: F = (f − b)/K, ideal k, ε;
// step2: F = (f − b)/K with the cell's fitted k and ε (the global set with Global). The same
// cells in all three rows. intensity ≤ 0 takes the largest intensity among the stops. Throws
// CalibrationError when fewer than two stops have that intensity or no cell is usable.
DofpTable1 dofp_table1(const DofpStep1& step1, const DofpStep2& step2,
                       std::span<const DofpPolarizedStop> stops, const DofpStep2Options& options,
                       double intensity = 0);

struct DofpCalibrationOptions {
  DofpStep1Options step1;
  DofpStep2Options step2;
  double table1_intensity = 0;  // ≤ 0: the largest
};

struct DofpCalibration {
  DofpCalibrationOptions options;
  DofpStep1 step1;
  DofpStep2 step2;
  DofpTable1 table1;
};

// Both steps and Table 1.
DofpCalibration calibrate_dofp(int width, int height,
                               std::span<const DofpUnpolarizedLevel> levels,
                               std::span<const DofpPolarizedStop> stops,
                               const DofpCalibrationOptions& options = {},
                               const Progress& progress = {});

// The calibrated parameters per pixel (K, b from step 1; k, eps_deg from the pixel's cell;
// alpha_deg the mosaic), in DofpTruth's layout so that they compare with a camera's truth.
// `usable` is 1 where the pixel's K, b and its cell's k, ε are determined, else 0.
DofpTruth dofp_parameter_maps(const DofpCalibration& c, std::vector<std::uint8_t>* usable = nullptr);

// ---- One cell's model, exposed for tests (Jacobian against finite differences) ----
// x = [ε2, ε3, ε4 (rad), k2, k3, k4, ψ_0 (rad), d_0]; F̃ holds 4 values per observation (TL, TR,
// BL, BR), theta_R_deg one per observation. Residuals: per observation the AoP residual (rad)
// , the weighted DoP residual and the weighted fit residual (0 when their weight is 0),
// interleaved. With options.view_projection step 2's projected model instead: ψ_0 =
// options.psi0_deg held, x = [ε2 − ε1, ε3 − ε1, ε4 − ε1, k2, k3, k4, ε1, d_0] and `views` the four
// pixels' views (frame l, TL, TR, BL, BR).
Eigen::VectorXd dofp_cell_residuals(const std::vector<double>& F_tilde,
                                    const std::vector<double>& theta_R_deg,
                                    const Eigen::Matrix<double, 8, 1>& x,
                                    const DofpStep2Options& options,
                                    const std::array<Vec3, 4>& views = {});
// The analytic Jacobian (Appendix A's chain ∂φ̃/∂Q̃ · ∂Q̃/∂x in matrix form: ∂(R⁻¹Ãᵀ) =
// R⁻¹(∂Ãᵀ − ∂R·R⁻¹Ãᵀ)), rows as dofp_cell_residuals; columns: x, and with the view's projection
// a ninth, ∂r/∂ψ_0 (rad), the column step 2's fit of ψ_0 reduces.
Eigen::MatrixXd dofp_cell_jacobian(const std::vector<double>& F_tilde,
                                   const std::vector<double>& theta_R_deg,
                                   const Eigen::Matrix<double, 8, 1>& x,
                                   const DofpStep2Options& options,
                                   const std::array<Vec3, 4>& views = {});

// One cell's sums at x by each code path of step 2, for tests: the scalar loop (the one
// dofp_cell_residuals and dofp_cell_jacobian use), and the pass in lanes of 8 that step 2 runs
// (SSE2, or AVX2 where the CPU has it; both must give the same bits). JtJ holds the upper
// triangle; bad is the first observation whose AoP or DoP is undefined (−1 if none; the lanes
// then fall back to the scalar loop). Returns false when the path cannot run on this CPU.
enum class DofpSumsPath { Scalar, LanesSse2, LanesAvx2 };
struct DofpCellSums {
  Eigen::Matrix<double, 8, 8> JtJ = Eigen::Matrix<double, 8, 8>::Zero();
  Eigen::Matrix<double, 8, 1> Jtr = Eigen::Matrix<double, 8, 1>::Zero();
  double cost = 0;    // Σ r² over every residual
  double aop_ss = 0;  // Σ r² of the unweighted AoP residuals
  long long bad = -1;
};
bool dofp_cell_sums(const std::vector<double>& F_tilde, const std::vector<double>& theta_R_deg,
                    const Eigen::Matrix<double, 8, 1>& x, const DofpStep2Options& options,
                    DofpSumsPath path, DofpCellSums& out);

}  // namespace polrig
