// The two-step DoFP calibration (calib/dofp.h) against frames made here, in the test, straight
// from Eq. 18 with a known per-pixel truth (spec sky-and-compasses.md §2.3–2.4).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>

#include <cmath>
#include <complex>
#include <iostream>
#include <cstring>
#include <numbers>
#include <random>
#include <span>

#include <Eigen/Dense>
#include <tbb/global_control.h>

#include <fmt/format.h>

#include "polrig/calib/dofp.h"
#include "polrig/calib/dofp_polarization.h"
#include "polrig/rig/rig.h"
#include "polrig/sim/dofp_frames.h"
#include "polrig/units.h"

namespace {
using namespace polrig;
double rad(double deg) { return deg * kPi / 180.0; }

// A per-pixel truth of Eq. 18. j = (row % 2)·2 + col % 2 indexes TL, TR, BL, BR.
struct Truth {
  int W = 0, H = 0;
  std::array<double, 4> alpha_deg = {0, 90, 45, 135};
  std::vector<double> K, b, k, eps_deg;
  int j(std::size_t p) const {
    const int col = static_cast<int>(p % W), row = static_cast<int>(p / W);
    return (row % 2) * 2 + col % 2;
  }
};

// Systematic per-position parameters plus a spread per pixel (gauge: TL has k = 1, ε = 0).
Truth make_truth(int W, int H, unsigned seed, double spread) {
  Truth t;
  t.W = W;
  t.H = H;
  const std::array<double, 4> gain = {1.00, 1.06, 0.95, 1.03}, offset = {40, 55, 35, 60};
  const std::array<double, 4> k = {1.0, 0.93, 0.96, 0.90}, eps = {0.0, 1.2, -0.8, 0.6};
  std::mt19937_64 gen(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  const std::size_t N = static_cast<std::size_t>(W) * H;
  for (std::size_t p = 0; p < N; ++p) {
    const int j = t.j(p);
    t.K.push_back(2000.0 * gain[j] * (1.0 + 0.04 * n01(gen)));
    t.b.push_back(offset[j] + 8.0 * n01(gen));
    t.k.push_back(j == 0 ? 1.0 : k[j] + spread * 0.02 * n01(gen));
    t.eps_deg.push_back(j == 0 ? 0.0 : eps[j] + spread * 0.5 * n01(gen));
  }
  return t;
}

// Eq. 18: f = (K/2)·I·[1 + k·d·cos(2φ − 2(α − ε))] + b, plus Gaussian noise of SD sigma_DN.
std::vector<double> frame(const Truth& t, double I, double d, double phi_deg, double sigma_DN,
                          std::mt19937_64* gen) {
  std::normal_distribution<double> n01(0.0, 1.0);
  std::vector<double> f(t.K.size());
  for (std::size_t p = 0; p < f.size(); ++p) {
    const double a = rad(t.alpha_deg[t.j(p)] - t.eps_deg[p]);
    f[p] = 0.5 * t.K[p] * I * (1.0 + t.k[p] * d * std::cos(2.0 * rad(phi_deg) - 2.0 * a)) + t.b[p];
    if (gen) f[p] += sigma_DN * n01(*gen);
  }
  return f;
}

struct Dataset {
  std::vector<std::vector<double>> level_frames, stop_frames;
  std::vector<DofpUnpolarizedLevel> levels;
  std::vector<DofpPolarizedStop> stops;
};

// 30 unpolarized levels 0..1; 79 positions at 4.6036° × six intensities (spec §2.4); the AoP at
// table angle θ_R is ψ + θ_R (kDofpTableSense = +1: docs/physics.md §14).
Dataset make_dataset(const Truth& t, double psi_deg, double d, double sigma_DN, int positions = 79,
                     unsigned seed = 7) {
  Dataset ds;
  std::mt19937_64 gen(seed);
  std::mt19937_64* g = sigma_DN > 0 ? &gen : nullptr;
  for (int i = 0; i < 30; ++i) ds.level_frames.push_back(frame(t, i / 29.0, 0.0, 0.0, sigma_DN, g));
  const double intensities[6] = {1.0, 0.5, 0.25, 0.1, 0.05, 0.025};
  std::vector<std::pair<double, double>> meta;
  for (double I : intensities)
    for (int m = 0; m < positions; ++m) {
      const double theta = 4.6036 * m;
      ds.stop_frames.push_back(frame(t, I, d, psi_deg + theta, sigma_DN, g));
      meta.emplace_back(theta, I);
    }
  for (int i = 0; i < 30; ++i) ds.levels.push_back({i / 29.0, ds.level_frames[i]});
  for (std::size_t s = 0; s < meta.size(); ++s)
    ds.stops.push_back({meta[s].first, meta[s].second, ds.stop_frames[s]});
  return ds;
}

// Tolerances of a fit of exact (noise-free) frames.
// Step 1 is a linear least-squares fit of f = K·I/2 + b to 30 exact values (f ≤ 2200 DN, I in
// [0, 1]); its design [I/2, 1] has a condition number of about 6, so rounding leaves about
// 6·2.2e-16·2200 DN ≈ 3e-12 DN in b and 3e-15 in K's relative value: kStep1RoundingDN = 1e-11 DN.
constexpr double kStep1RoundingDN = 1e-11;
// Step 2 stops when |Δx| < step_tolerance (1e-10: ε, ψ_0 in rad, k and d unitless). On exact data
// Gauss–Newton converges quadratically, so the error left after that last step is O(|Δx|²),
// far below it: the step tolerance bounds each unknown's error (in degrees: 5.7e-9°). The
// frames' own rounding (3e-15 relative, above) moves the solution by far less.
const double kStepTol = DofpStep2Options{}.step_tolerance;
const double kStepTolDeg = kStepTol * 180.0 / kPi;

// Table 1's raw row (or, with `true_gains`, its step-1 row with the truth's K and b) computed
// here, independently of calib/dofp: per stop of intensity 1 each cell's AoP from its pixels
// F = f (or (f − b)/K) by H17 Eq. 5 (α = 0, 90, 45, 135: ½·atan2(F45 − F135, F0 − F90)), their
// circular mean o_m, and wrap90((o_m − o_0) − (θ_m − θ_0)).
std::vector<double> orientation_errors_deg(const Truth& t, const Dataset& ds, bool true_gains = false) {
  std::vector<double> o, theta;
  for (const DofpPolarizedStop& st : ds.stops) {
    if (st.intensity != 1.0) continue;
    std::complex<double> sum = 0;
    for (int cy = 0; cy < t.H / 2; ++cy)
      for (int cx = 0; cx < t.W / 2; ++cx) {
        const std::size_t p = static_cast<std::size_t>(2 * cy) * t.W + 2 * cx;
        const auto F = [&](std::size_t q) { return true_gains ? (st.frame[q] - t.b[q]) / t.K[q] : st.frame[q]; };
        const double Q = F(p) - F(p + 1), U = F(p + t.W) - F(p + t.W + 1);
        sum += std::polar(1.0, std::atan2(U, Q));  // exp(i·2φ)
      }
    o.push_back(0.5 * std::arg(sum) * 180.0 / kPi);
    theta.push_back(st.theta_R_deg);
  }
  std::vector<double> e;
  for (std::size_t m = 1; m < o.size(); ++m) {
    double d = std::fmod((o[m] - o[0]) - (theta[m] - theta[0]), 180.0);
    if (d < -90) d += 180;
    if (d >= 90) d -= 180;
    e.push_back(d);
  }
  return e;
}

TEST(DofpCalibration, NoiseFreeFramesCalibrateBackToTheTruth) {
  const Truth t = make_truth(16, 12, 1, 1.0);
  const Dataset ds = make_dataset(t, 23.0, 0.8, 0.0);
  const DofpCalibration c = calibrate_dofp(t.W, t.H, ds.levels, ds.stops);
  ASSERT_EQ(c.step1.rank_deficient_pixels, 0);
  for (const DofpCellFit& f : c.step2.cells) EXPECT_TRUE(f.usable()) << f.message;
  ASSERT_EQ(c.step2.usable_cells, 8 * 6);
  const DofpTruth p = dofp_parameter_maps(c);
  double worst[6] = {};
  for (std::size_t i = 0; i < t.K.size(); ++i) {
    EXPECT_NEAR(p.K[i] / t.K[i], 1.0, kStep1RoundingDN / 1000.0) << i;  // K/2 ≥ 950 DN per unit I
    EXPECT_NEAR(p.b[i], t.b[i], kStep1RoundingDN) << i;
    EXPECT_NEAR(p.k[i], t.k[i], kStepTol) << i;
    EXPECT_NEAR(p.eps_deg[i], t.eps_deg[i], kStepTolDeg) << i;
    EXPECT_LT(c.step1.residual_rms_DN[i], kStep1RoundingDN);
    worst[0] = std::max(worst[0], std::abs(p.K[i] / t.K[i] - 1));
    worst[1] = std::max(worst[1], std::abs(p.b[i] - t.b[i]));
    worst[2] = std::max(worst[2], std::abs(p.k[i] - t.k[i]));
    worst[3] = std::max(worst[3], std::abs(p.eps_deg[i] - t.eps_deg[i]));
  }
  for (const DofpCellFit& f : c.step2.cells) {
    EXPECT_EQ(f.termination, FitTermination::Converged);
    EXPECT_EQ(f.rank, 8);
    // Quadratic convergence from a start within a few degrees and a few % of k: the error
    // squares each step (1e-2 → 1e-4 → 1e-8 → 1e-16), so a handful of steps; LM's damped first
    // steps take a few more. Far under max_iterations (50): a regression guard, not physics.
    EXPECT_LT(f.iterations, 15);
    EXPECT_NEAR(f.dop, 0.8, kStepTol);
    EXPECT_LT(f.final_rms_deg, kStepTolDeg);
    EXPECT_NEAR(f.psi0_deg, 23.0, kStepTolDeg);
    EXPECT_EQ(f.observations, 6 * 79);
    worst[4] = std::max(worst[4], f.final_rms_deg);
    worst[5] = std::max(worst[5], static_cast<double>(f.iterations));
  }
  std::printf("worst |K/K−1| %.2g, |b| %.2g DN, |k| %.2g, |eps| %.2g deg, rms %.2g deg, iterations %g\n",
              worst[0], worst[1], worst[2], worst[3], worst[4], worst[5]);
  // After step 2 the orientation is exact to the step tolerance; before it, it is the raw
  // row computed here from the frames (an independent implementation of Eq. 5 and the mean).
  EXPECT_LT(c.table1.rows[2].max_deg, kStepTolDeg);
  // Step 1's row likewise with the truth's K and b (step 1 recovers them to 1e-11 DN: 1e-14 rad).
  for (int row : {0, 1}) {
    const std::vector<double> e = orientation_errors_deg(t, ds, row == 1);
    ASSERT_EQ(e.size(), c.table1.rows[row].error_deg.size());
    for (std::size_t m = 0; m < e.size(); ++m)
      EXPECT_NEAR(c.table1.rows[row].error_deg[m], e[m], 1e-12) << row << " " << m;  // rounding of 48 unit phasors
  }
  EXPECT_GT(c.table1.rows[0].max_deg, 0.1);  // the truth's ε of ±1° show before calibration
  EXPECT_EQ(c.table1.theta_R_deg.size(), 78u);
}

// Step 2's closed-form start (docs/physics.md §14 "Solver") is exact on noise-free frames of
// Eq. 18: every cell starts at the truth (AoP residual at rounding level) and LM takes no step
// that is not below the tolerance, for the wrong analyzer order as well as the right one.
TEST(DofpCalibration, TheClosedFormStartIsExactOnNoiseFreeFrames) {
  const Truth t = make_truth(8, 6, 5, 1.0);
  const Dataset ds = make_dataset(t, -61.0, 0.7, 0.0);
  const DofpStep1 s1 = calibrate_dofp_step1(t.W, t.H, ds.levels);
  for (const double sense : {1.0, -1.0}) {
    DofpStep2Options o;
    o.table_sense = sense;
    std::vector<DofpPolarizedStop> stops = ds.stops;
    for (DofpPolarizedStop& s : stops) s.theta_R_deg *= sense;  // the same light either way
    const DofpStep2 s2 = calibrate_dofp_step2(s1, stops, o);
    ASSERT_EQ(s2.cells.size(), 12u);
    for (std::size_t c = 0; c < s2.cells.size(); ++c) {
      const DofpCellFit& f = s2.cells[c];
      ASSERT_TRUE(f.usable()) << f.message;
      EXPECT_LT(f.initial_rms_deg, 1e-9) << c;
      EXPECT_LE(f.iterations, 1) << c;
      EXPECT_NEAR(f.psi0_deg, -61.0, 1e-9) << c;
      EXPECT_NEAR(f.dop, 0.7, 1e-11) << c;
      const std::size_t p0 = (c / 4) * 2 * t.W + (c % 4) * 2;
      const std::size_t px[4] = {p0, p0 + 1, p0 + t.W, p0 + t.W + 1};
      for (int j = 1; j < 4; ++j) {
        EXPECT_NEAR(f.k[j], t.k[px[j]], 1e-11) << c << " " << j;
        EXPECT_NEAR(f.eps_deg[j], t.eps_deg[px[j]], 1e-9) << c << " " << j;
      }
    }
  }
}

TEST(DofpCalibration, OneGlobalSetRecoversAGlobalTruth) {
  Truth t = make_truth(8, 6, 2, 0.0);  // no per-pixel spread of k, ε
  const Dataset ds = make_dataset(t, -41.0, 0.6, 0.0, 40);
  DofpCalibrationOptions o;
  o.step2.scope = DofpStep2Scope::Global;
  const DofpCalibration c = calibrate_dofp(t.W, t.H, ds.levels, ds.stops, o);
  ASSERT_EQ(c.step2.cells.size(), 1u);
  ASSERT_TRUE(c.step2.cells[0].usable()) << c.step2.cells[0].message;
  EXPECT_EQ(c.step2.cells[0].observations, 12 * 6 * 40);
  for (int j = 1; j < 4; ++j) {
    const std::size_t p = static_cast<std::size_t>(j / 2) * t.W + j % 2;  // the first cell's pixel j
    EXPECT_NEAR(c.step2.cells[0].k[j], t.k[p], kStepTol);  // exact frames: the step tolerance
    EXPECT_NEAR(c.step2.cells[0].eps_deg[j], t.eps_deg[p], kStepTolDeg);
  }
}

// The analytic Jacobian (Appendix A's chain in matrix form) against central differences.
TEST(DofpCalibration, JacobianMatchesCentralDifferences) {
  const Truth t = make_truth(2, 2, 3, 1.0);
  std::vector<double> F, theta;
  for (int m = 0; m < 79; ++m) {
    theta.push_back(4.6036 * m);
    const std::vector<double> f = frame(t, 0.7, 0.85, 12.0 + theta.back(), 0.0, nullptr);
    for (int j = 0; j < 4; ++j) F.push_back((f[j] - t.b[j]) / t.K[j]);
  }
  DofpStep2Options o;
  Eigen::Matrix<double, 8, 1> x;  // away from the truth, residuals well inside ±90°
  x << rad(2.0), rad(-1.5), rad(0.3), 0.97, 0.91, 0.88, rad(13.0), 0.8;
  const Eigen::MatrixXd J = dofp_cell_jacobian(F, theta, x, o);
  ASSERT_EQ(J.rows(), 3 * 79);
  ASSERT_EQ(J.cols(), 8);
  const double h = 1e-6;
  for (int p = 0; p < 8; ++p) {
    Eigen::Matrix<double, 8, 1> xp = x, xm = x;
    xp[p] += h;
    xm[p] -= h;
    const Eigen::VectorXd fd =
        (dofp_cell_residuals(F, theta, xp, o) - dofp_cell_residuals(F, theta, xm, o)) / (2 * h);
    // Truncation O(h²·r''') ≈ 1e-12 and rounding O(ε/h) ≈ 1e-10.
    for (int m = 0; m < 3 * 79; ++m)
      EXPECT_NEAR(J(m, p), fd[m], 1e-8) << "unknown " << p << " row " << m;
    // Every unknown moves the residuals (no column is zero): each column holds ∂r/∂x of O(1)
    // (angles in rad, k and d unitless) over 237 rows; 1e-3 only excludes a zero column.
    EXPECT_GT(J.col(p).norm(), 1e-3) << p;
  }
  const Eigen::VectorXd r = dofp_cell_residuals(F, theta, x, o);
  EXPECT_LT(r.cwiseAbs().maxCoeff(), kPi / 4);
}

// The same for step 2's projected model (a cell whose pixels look 40° off the axis at azimuth 30°,
// one pixel apart with f_c = 40 px): columns x = [ε2 − ε1, ε3 − ε1, ε4 − ε1, k2, k3, k4, ε1, d0] and
// the ninth, ∂r/∂ψ_0 through every pixel's own projection, against central differences.
TEST(DofpCalibration, ProjectedJacobianMatchesCentralDifferences) {
  const Truth t = make_truth(2, 2, 3, 1.0);
  const double fc = 40.0, r = fc * std::tan(rad(40.0));
  std::array<Vec3, 4> views;
  for (int j = 0; j < 4; ++j) {
    const double x = r * std::cos(rad(30.0)) + j % 2 - 0.5, y = r * std::sin(rad(30.0)) + j / 2 - 0.5;
    const double n = std::sqrt(x * x + y * y + fc * fc);
    views[j] = {x / n, y / n, fc / n};
  }
  const double eps1 = 0.4, psi0 = 12.0;
  std::vector<double> F, theta;
  for (int m = 0; m < 79; ++m) {
    theta.push_back(4.6036 * m);
    const std::vector<double> f = frame(t, 0.7, 0.0, 0.0, 0.0, nullptr);  // K/2·I + b
    for (int j = 0; j < 4; ++j) {
      const double phi = rad(dofp_projected_aop_deg(views[j], psi0 + theta.back()));
      const double a = rad(t.alpha_deg[j] - t.eps_deg[j] - eps1);
      F.push_back((f[j] - t.b[j]) / t.K[j] * (1.0 + t.k[j] * 0.85 * std::cos(2.0 * phi - 2.0 * a)));
    }
  }
  DofpStep2Options o;
  o.view_projection = true;
  o.focal_px = fc;
  o.psi0_deg = 13.0;
  Eigen::Matrix<double, 8, 1> x;
  x << rad(2.0), rad(-1.5), rad(0.3), 0.97, 0.91, 0.88, rad(0.7), 0.8;
  const Eigen::MatrixXd J = dofp_cell_jacobian(F, theta, x, o, views);
  ASSERT_EQ(J.cols(), 9);
  const double h = 1e-6;
  for (int p = 0; p < 9; ++p) {
    Eigen::Matrix<double, 8, 1> xp = x, xm = x;
    DofpStep2Options op = o, om = o;
    if (p < 8) {
      xp[p] += h;
      xm[p] -= h;
    } else {
      op.psi0_deg += h * 180.0 / kPi;
      om.psi0_deg -= h * 180.0 / kPi;
    }
    const Eigen::VectorXd fd =
        (dofp_cell_residuals(F, theta, xp, op, views) - dofp_cell_residuals(F, theta, xm, om, views)) / (2 * h);
    for (int m = 0; m < 3 * 79; ++m) EXPECT_NEAR(J(m, p), fd[m], 1e-8) << "unknown " << p << " row " << m;
    EXPECT_GT(J.col(p).norm(), 1e-3) << p;
  }
  // ∂r/∂ψ_0 is −dφ_1/dψ_0 on the AoP rows up to the pixels' shifts: it varies over the turn (cos γ to
  // 1/cos γ), unlike ∂r/∂ε1 = −1.
  double lo = 1e9, hi = -1e9;
  for (int m = 0; m < 79; ++m) lo = std::min(lo, -J(3 * m, 8)), hi = std::max(hi, -J(3 * m, 8));
  EXPECT_LT(lo, 0.9);
  EXPECT_GT(hi, 1.1);
  // The residuals at the truth are zero with the projection, not without it.
  Eigen::Matrix<double, 8, 1> xt;
  xt << rad(t.eps_deg[1]), rad(t.eps_deg[2]), rad(t.eps_deg[3]), t.k[1], t.k[2], t.k[3], rad(eps1), 0.85;
  o.psi0_deg = psi0;
  EXPECT_LT(dofp_cell_residuals(F, theta, xt, o, views).cwiseAbs().maxCoeff(), 1e-12);
  DofpStep2Options off = o;
  off.view_projection = false;
  xt[6] = rad(psi0 + eps1);  // H17's ψ_0 per cell
  EXPECT_GT(dofp_cell_residuals(F, theta, xt, off).cwiseAbs().maxCoeff(), rad(1.0));
}

// Frames of a wide field (every pixel sees the port polarizer along its own view, as the model
// takes it): with the view's projection step 2 gives back the truth and Table 1's step-2 row is
// exact; H17's model (off) leaves degrees.
// Noise-free frames whose every pixel sees the port polarizer (at 23° + θ_R on the axis, DoP 0.8)
// along its own view, as step 2's projected model takes it.
Dataset projected_dataset(const Truth& t, const DofpStep2Options& o) {
  Dataset ds;
  for (int i = 0; i < 30; ++i) ds.level_frames.push_back(frame(t, i / 29.0, 0.0, 0.0, 0.0, nullptr));
  std::vector<std::pair<double, double>> meta;
  for (double I : {1.0, 0.5, 0.25})
    for (int m = 0; m < 79; ++m) {
      const double theta = 4.6036 * m;
      std::vector<double> f(t.K.size());
      for (std::size_t p = 0; p < f.size(); ++p) {
        const int col = static_cast<int>(p % t.W), row = static_cast<int>(p / t.W);
        const double phi = dofp_projected_aop_deg(dofp_pixel_view(t.W, t.H, o, col, row), 23.0 + theta);
        const double a = rad(t.alpha_deg[t.j(p)] - t.eps_deg[p]);
        f[p] = 0.5 * t.K[p] * I * (1.0 + t.k[p] * 0.8 * std::cos(2.0 * rad(phi) - 2.0 * a)) + t.b[p];
      }
      ds.stop_frames.push_back(f);
      meta.emplace_back(theta, I);
    }
  for (int i = 0; i < 30; ++i) ds.levels.push_back({i / 29.0, ds.level_frames[i]});
  for (std::size_t s = 0; s < meta.size(); ++s) ds.stops.push_back({meta[s].first, meta[s].second, ds.stop_frames[s]});
  return ds;
}

TEST(DofpCalibration, ViewProjectionCalibratesAWideFieldBackToTheTruth) {
  const Truth t = make_truth(16, 12, 1, 1.0);
  DofpStep2Options o;
  o.view_projection = true;
  o.focal_px = 6.0;  // a 106° × 90° field on 16 × 12 pixels
  const Dataset ds = projected_dataset(t, o);
  DofpCalibrationOptions co;
  co.step2 = o;
  const DofpCalibration c = calibrate_dofp(t.W, t.H, ds.levels, ds.stops, co);
  for (const DofpCellFit& f : c.step2.cells) EXPECT_TRUE(f.usable()) << f.message;
  ASSERT_EQ(c.step2.usable_cells, 8 * 6);
  const DofpTruth p = dofp_parameter_maps(c);
  for (std::size_t i = 0; i < t.K.size(); ++i) {
    EXPECT_NEAR(p.k[i], t.k[i], 1e-6) << i;
    EXPECT_NEAR(p.eps_deg[i], t.eps_deg[i], 1e-6) << i;
  }
  for (const DofpCellFit& f : c.step2.cells) EXPECT_NEAR(f.psi0_deg, 23.0, 1e-6);
  EXPECT_LT(c.table1.rows[2].max_deg, 1e-8);
  // H17's model on the same frames: the fit bends (k, ε) towards the projection, and Table 1's
  // mean over the cells keeps the projection's error.
  co.step2.view_projection = false;
  const DofpCalibration h = calibrate_dofp(t.W, t.H, ds.levels, ds.stops, co);
  EXPECT_GT(h.table1.rows[2].max_deg, 0.5);
}

TEST(DofpCalibration, ViewProjectionWithOneGlobalSet) {
  const Truth t = make_truth(16, 12, 2, 0.0);  // no per-pixel spread of k, ε
  DofpCalibrationOptions co;
  co.step2.view_projection = true;
  co.step2.focal_px = 6.0;
  co.step2.scope = DofpStep2Scope::Global;
  const Dataset ds = projected_dataset(t, co.step2);
  const DofpCalibration c = calibrate_dofp(t.W, t.H, ds.levels, ds.stops, co);
  ASSERT_TRUE(c.step2.cells[0].usable()) << c.step2.cells[0].message;
  for (int j = 1; j < 4; ++j) {
    const std::size_t p = static_cast<std::size_t>(j / 2) * t.W + j % 2;
    EXPECT_NEAR(c.step2.cells[0].k[j], t.k[p], 1e-9);
    EXPECT_NEAR(c.step2.cells[0].eps_deg[j], t.eps_deg[p], 1e-7);
  }
  EXPECT_LT(c.table1.rows[2].max_deg, 1e-8);
  // A projection without a focal length is refused.
  co.step2.focal_px = 0;
  EXPECT_THROW(calibrate_dofp(t.W, t.H, ds.levels, ds.stops, co), std::invalid_argument);
}

// Step 2 sums each cell's normal equations in lanes of 8 (SSE2, or AVX2 where the CPU has it);
// the scalar loop (the one the Jacobian test above checks) is the reference: the same sums up to
// the order of the additions, and the two instruction sets give the same bits. 79 observations
// leave a partial lane block (padding).
TEST(DofpCalibration, LanesSumTheSameNormalEquationsAsTheScalarLoop) {
  const Truth t = make_truth(2, 2, 5, 1.0);
  std::mt19937_64 gen(7);
  std::vector<double> F, theta;
  for (int m = 0; m < 79; ++m) {
    theta.push_back(4.6036 * m);
    const std::vector<double> f = frame(t, 0.6, 0.9, -20.0 + theta.back(), 3.0, &gen);
    for (int j = 0; j < 4; ++j) F.push_back((f[j] - t.b[j]) / t.K[j]);
  }
  DofpStep2Options o;
  Eigen::Matrix<double, 8, 1> x;
  x << rad(1.0), rad(-0.5), rad(0.7), 0.95, 0.92, 0.9, rad(-19.0), 0.85;
  DofpCellSums scalar, sse2, avx2;
  ASSERT_TRUE(dofp_cell_sums(F, theta, x, o, DofpSumsPath::Scalar, scalar));
  ASSERT_TRUE(dofp_cell_sums(F, theta, x, o, DofpSumsPath::LanesSse2, sse2));
  EXPECT_EQ(scalar.bad, -1);
  EXPECT_EQ(sse2.bad, -1);
  // Rounding of sums of 79 positive-and-negative terms: a few ulp of the largest term's scale.
  const double tol = 1e-12;
  for (int p = 0; p < 8; ++p) {
    for (int q = p; q < 8; ++q)
      EXPECT_NEAR(sse2.JtJ(p, q), scalar.JtJ(p, q),
                  tol * std::sqrt(scalar.JtJ(p, p) * scalar.JtJ(q, q))) << p << "," << q;
    EXPECT_NEAR(sse2.Jtr[p], scalar.Jtr[p], tol * std::sqrt(scalar.JtJ(p, p) * scalar.cost)) << p;
  }
  EXPECT_NEAR(sse2.cost, scalar.cost, tol * scalar.cost);
  EXPECT_NEAR(sse2.aop_ss, scalar.aop_ss, tol * scalar.aop_ss);
  EXPECT_GT(scalar.cost, 0);
  if (dofp_cell_sums(F, theta, x, o, DofpSumsPath::LanesAvx2, avx2)) {
    EXPECT_EQ(0, std::memcmp(avx2.JtJ.data(), sse2.JtJ.data(), sizeof(double) * 64));
    EXPECT_EQ(0, std::memcmp(avx2.Jtr.data(), sse2.Jtr.data(), sizeof(double) * 8));
    EXPECT_EQ(0, std::memcmp(&avx2.cost, &sse2.cost, sizeof(double)));
    EXPECT_EQ(0, std::memcmp(&avx2.aop_ss, &sse2.aop_ss, sizeof(double)));
  }
  // An observation without signal (four dark pixels: no AoP): the lanes hand the cell to the
  // scalar loop, which names it.
  for (int j = 0; j < 4; ++j) F[4 * 40 + j] = 0.0;
  ASSERT_TRUE(dofp_cell_sums(F, theta, x, o, DofpSumsPath::Scalar, scalar));
  ASSERT_TRUE(dofp_cell_sums(F, theta, x, o, DofpSumsPath::LanesSse2, sse2));
  EXPECT_EQ(scalar.bad, 40);
  EXPECT_EQ(sse2.bad, 40);
  EXPECT_EQ(sse2.cost, scalar.cost);
}

TEST(DofpCalibration, AnUndeterminedPixelIsReportedNotANaN) {
  Truth t = make_truth(8, 6, 4, 1.0);
  Dataset ds = make_dataset(t, 5.0, 0.8, 0.0, 20);
  // Pixel (column 3, row 2) saturates at every level but the first: rank 1.
  const std::size_t bad = 2 * 8 + 3;
  for (std::size_t i = 1; i < ds.level_frames.size(); ++i) ds.level_frames[i][bad] = 4095;
  DofpCalibrationOptions o;
  o.step1.saturation_DN = 4095;
  const DofpCalibration c = calibrate_dofp(t.W, t.H, ds.levels, ds.stops, o);
  EXPECT_EQ(c.step1.rank[bad], 1);
  EXPECT_EQ(c.step1.levels_used[bad], 1);
  EXPECT_EQ(c.step1.rank_deficient_pixels, 1);
  EXPECT_EQ(c.step1.K[bad], 0.0);
  const DofpCellFit& cell = c.step2.cells[1 * 4 + 1];  // cell (1, 1)
  EXPECT_EQ(cell.termination, FitTermination::RankDeficient);
  EXPECT_NE(cell.message.find("column 3, row 2"), std::string::npos) << cell.message;
  EXPECT_EQ(c.step2.usable_cells, 11);
  EXPECT_EQ(c.table1.cells_used, 11);
  std::vector<std::uint8_t> usable;
  const DofpTruth p = dofp_parameter_maps(c, &usable);
  for (std::size_t i = 0; i < p.K.size(); ++i)
    EXPECT_TRUE(std::isfinite(p.K[i]) && std::isfinite(p.b[i]) && std::isfinite(p.k[i]) &&
                std::isfinite(p.eps_deg[i]));
  EXPECT_EQ(usable[bad], 0);
  EXPECT_EQ(usable[0], 1);
  EXPECT_EQ(p.k[bad], 1.0);  // the ideal values where the cell was not fitted
  EXPECT_EQ(p.eps_deg[bad], 0.0);
}

TEST(DofpCalibration, OneTablePositionLeavesStep2RankDeficient) {
  const Truth t = make_truth(4, 2, 5, 1.0);
  const Dataset ds = make_dataset(t, 5.0, 0.8, 0.0, 2);  // six intensities, two angles
  const DofpStep1 s1 = calibrate_dofp_step1(t.W, t.H, ds.levels);
  const DofpStep2 s2 = calibrate_dofp_step2(s1, ds.stops);
  for (const DofpCellFit& f : s2.cells) {
    EXPECT_EQ(f.termination, FitTermination::RankDeficient);
    EXPECT_LT(f.rank, 8);
    EXPECT_TRUE(std::isfinite(f.initial_rms_deg));
  }
}

// H17's cost (the AoP residual alone) cannot tell every (k, ε): at a perfect fit its Jacobian
// has rank 3 of 7 (docs/physics.md §14).
TEST(DofpCalibration, TheAopResidualAloneLeavesTwoDirectionsUndetermined) {
  const Truth t = make_truth(4, 2, 11, 1.0);
  const Dataset ds = make_dataset(t, 5.0, 0.8, 0.0, 79);
  const DofpStep1 s1 = calibrate_dofp_step1(t.W, t.H, ds.levels);
  DofpStep2Options o;
  o.dop_weight = 0;
  o.fit_weight = 0;
  const DofpStep2 s2 = calibrate_dofp_step2(s1, ds.stops, o);
  for (const DofpCellFit& f : s2.cells) {
    EXPECT_EQ(f.termination, FitTermination::RankDeficient);
    EXPECT_EQ(f.rank, 3);
    EXPECT_LT(f.final_rms_deg, kStepTolDeg);  // the AoP is still fitted, to the step tolerance
    EXPECT_TRUE(std::isnan(f.dop));
  }
}

TEST(DofpCalibration, TooFewStopsAndBadInputAreSaid) {
  const Truth t = make_truth(4, 2, 6, 1.0);
  Dataset ds = make_dataset(t, 5.0, 0.8, 0.0, 1);
  const DofpStep1 s1 = calibrate_dofp_step1(t.W, t.H, ds.levels);
  const DofpStep2 s2 = calibrate_dofp_step2(s1, std::span(ds.stops).first(2));
  EXPECT_EQ(s2.cells[0].termination, FitTermination::TooFewObservations);
  ds.stop_frames[2][5] = std::nan("");
  try {
    calibrate_dofp_step2(s1, ds.stops);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("polarized stop 2: the pixel at column 1, row 1 is nan"),
              std::string::npos) << e.what();
  }
  EXPECT_THROW(calibrate_dofp_step1(3, 2, ds.levels), std::invalid_argument);
  std::vector<double> small(4);
  const DofpUnpolarizedLevel wrong[1] = {{1.0, small}};
  EXPECT_THROW(calibrate_dofp_step1(t.W, t.H, wrong), std::invalid_argument);
  DofpStep2Options o;
  o.table_sense = 0.5;
  EXPECT_THROW(calibrate_dofp_step2(s1, ds.stops, o), std::invalid_argument);
}

// Table 1's ordering (spec §2.7 item 3): before > after step 1 > after step 2, on a noisy truth.
TEST(DofpCalibration, TableOneOrderingOnANoisyTruth) {
  const Truth t = make_truth(64, 48, 8, 1.0);
  const Dataset ds = make_dataset(t, 30.0, 0.9, 2.0);
  const DofpCalibration c = calibrate_dofp(t.W, t.H, ds.levels, ds.stops);
  EXPECT_EQ(c.step2.usable_cells, 32 * 24);
  const auto& r = c.table1.rows;
  EXPECT_GT(r[0].std_deg, r[1].std_deg);
  EXPECT_GT(r[1].std_deg, r[2].std_deg);
  EXPECT_GT(r[0].max_deg, r[1].max_deg);
  EXPECT_GT(r[1].max_deg, r[2].max_deg);
  // After step 2, a bound from the noise (σ_f = 2 DN per pixel and frame), to first order, for the
  // stops of intensity I = 1 (Table 1's), d = 0.9, N = 768 cells. In calibrated units
  // F = (f − b)/K a cell's Q = F0 − F90 = I·k·d·cos 2φ (U likewise), so δφ = δQ⊥/(2·I·k·d):
  //  - the frame's noise: σ_Q = √2·σ_f/K, σ_φ = σ_f/(√2·K·I·k·d);
  //  - step 1's K from 30 levels I_i = i/29: σ_K/K = 2σ_f/(K·√S), S = Σ(I_i − Ī)² = 30·31/(12·29);
  //    it scales F ≤ (I/2)(1 + k·d): σ_Q = √2·(I/2)(1 + k·d)·σ_K/K;
  //  - step 1's b: σ_b = σ_f·√(ΣI_i²/(30·S)), σ_Q = √2·σ_b/K;
  //  - step 2's k, ε: 474 observations per cell, negligible (σ_φ/√474 each);
  // with the smallest K and k of the truth (a bound). The error e_m = (o_m − o_0) − θ_m of the
  // circular mean o over N cells has σ_e = √(2/N)·σ_φ,total; all 78 stops within 5σ_e
  // (P(|z| > 5)·78 = 4.5e-5).
  double sigma_e_deg = 0;
  {
    const double sigma_f = 2.0, I = 1.0, d = 0.9, N = 32 * 24;
    const double K = *std::min_element(t.K.begin(), t.K.end()), k = *std::min_element(t.k.begin(), t.k.end());
    double S = 0, sum_I2 = 0;
    for (int i = 0; i < 30; ++i) S += std::pow(i / 29.0 - 0.5, 2), sum_I2 += std::pow(i / 29.0, 2);
    const double phi_noise = sigma_f / (std::sqrt(2.0) * K * I * k * d);
    const double phi_K = std::sqrt(2.0) * 0.5 * I * (1 + k * d) * 2 * sigma_f / (K * std::sqrt(S)) / (2 * I * k * d);
    const double phi_b = std::sqrt(2.0) * sigma_f * std::sqrt(sum_I2 / (30 * S)) / K / (2 * I * k * d);
    sigma_e_deg = std::sqrt(2.0 / N) * std::hypot(phi_noise, phi_K, phi_b) * 180.0 / kPi;
    std::printf("sigma_e %.4g deg: step 2 max %.4g std %.4g deg\n", sigma_e_deg, r[2].max_deg, r[2].std_deg);
    EXPECT_LT(r[2].max_deg, 5 * sigma_e_deg);
  }
  // Step 1's row against the same frames without noise, with the truth's K and b (computed
  // here): they differ by the noise and step 1's estimates, within the same 5σ_e.
  const std::vector<double> exact = orientation_errors_deg(t, make_dataset(t, 30.0, 0.9, 0.0), true);
  ASSERT_EQ(exact.size(), r[1].error_deg.size());
  double worst = 0;
  for (std::size_t m = 0; m < exact.size(); ++m) worst = std::max(worst, std::abs(r[1].error_deg[m] - exact[m]));
  std::printf("step 1 against the exact curve: worst %.4g deg (the curve's max %.4g deg)\n", worst, r[1].max_deg);
  EXPECT_LT(worst, 5 * sigma_e_deg);
}

TEST(DofpCalibration, BitIdenticalForAnyThreadCount) {
  const Truth t = make_truth(32, 24, 9, 1.0);
  const Dataset ds = make_dataset(t, 30.0, 0.9, 2.0, 30);
  const auto run = [&](int threads, DofpStep2Scope scope) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    DofpCalibrationOptions o;
    o.step2.scope = scope;
    return calibrate_dofp(t.W, t.H, ds.levels, ds.stops, o);
  };
  for (DofpStep2Scope scope : {DofpStep2Scope::PerCell, DofpStep2Scope::Global}) {
    const DofpCalibration a = run(1, scope), b = run(2, scope), c4 = run(4, scope);
    for (const DofpCalibration* o : {&b, &c4}) {
      EXPECT_EQ(0, std::memcmp(a.step1.K.data(), o->step1.K.data(), a.step1.K.size() * 8));
      EXPECT_EQ(0, std::memcmp(a.step1.b.data(), o->step1.b.data(), a.step1.b.size() * 8));
      ASSERT_EQ(a.step2.cells.size(), o->step2.cells.size());
      for (std::size_t i = 0; i < a.step2.cells.size(); ++i) {
        const DofpCellFit &x = a.step2.cells[i], &y = o->step2.cells[i];
        EXPECT_EQ(0, std::memcmp(x.k.data(), y.k.data(), 32));
        EXPECT_EQ(0, std::memcmp(x.eps_deg.data(), y.eps_deg.data(), 32));
        EXPECT_EQ(0, std::memcmp(&x.final_rms_deg, &y.final_rms_deg, 8));
        EXPECT_EQ(x.iterations, y.iterations);
      }
      for (int k = 0; k < 3; ++k)
        EXPECT_EQ(0, std::memcmp(a.table1.rows[k].error_deg.data(), o->table1.rows[k].error_deg.data(),
                                 a.table1.rows[k].error_deg.size() * 8));
    }
  }
}

// The sense of the table angle matters: data turning the other way do not fit.
TEST(DofpCalibration, TheWrongTableSenseDoesNotFit) {
  const Truth t = make_truth(4, 2, 10, 1.0);
  Dataset ds = make_dataset(t, 10.0, 0.8, 0.0, 40);
  const DofpStep1 s1 = calibrate_dofp_step1(t.W, t.H, ds.levels);
  DofpStep2Options o;
  o.table_sense = -kDofpTableSense;
  const DofpStep2 s2 = calibrate_dofp_step2(s1, ds.stops, o);
  // A right fit of these exact frames leaves under kStepTolDeg (NoiseFreeFrames…); the wrong
  // sense leaves the AoP's 2θ_R drift, which (k, ε, ψ_0) of one cell cannot follow: over θ_R
  // spread uniformly on [0°, 184°] that is about 180°/√12 = 52° rms. 1° lies between the two.
  for (const DofpCellFit& f : s2.cells) EXPECT_FALSE(f.usable() && f.final_rms_deg < 1.0);
}

}  // namespace

#include <filesystem>
#include <fstream>
#include <sstream>

#include "polrig/io/exr.h"
#include "polrig/io/plot.h"
#include "polrig/report/dofp_calibration_report.h"

namespace {

std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The report's files hold what the calibration computed: params.exr's channels are the maps as
// float, table1.csv's rows the three rows.
TEST(DofpCalibrationReport, WritesParamsTableCellsAndPlots) {
  const Truth t = make_truth(16, 12, 12, 1.0);
  const Dataset ds = make_dataset(t, 30.0, 0.9, 2.0);
  const DofpCalibration c = calibrate_dofp(t.W, t.H, ds.levels, ds.stops);
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / fmt::format("polrig_dofp_report_{}", ::getpid());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const bool plots = gnuplot_available();
  const auto files = report_dofp_calibration(dir, c, plots);
  for (const auto& f : files) EXPECT_TRUE(std::filesystem::exists(dir / f.name)) << f.name;
  int w = 0, h = 0;
  const std::vector<ExrChannel> ch = read_exr(dir / "params.exr", w, h);
  EXPECT_EQ(w, 16);
  EXPECT_EQ(h, 12);
  const DofpTruth p = dofp_parameter_maps(c);
  for (const ExrChannel& x : ch) {
    const std::vector<double>* v = x.name == "K" ? &p.K : x.name == "b" ? &p.b
                                 : x.name == "k" ? &p.k : x.name == "eps_deg" ? &p.eps_deg : nullptr;
    if (!v) continue;
    for (std::size_t i = 0; i < v->size(); ++i) EXPECT_EQ(x.pixels[i], static_cast<float>((*v)[i]));
  }
  const std::string t1 = slurp(dir / "table1.csv");
  EXPECT_EQ(t1.substr(0, t1.find('\n')), "row,max_deg,mean_deg,std_deg");
  for (const auto& r : c.table1.rows)
    EXPECT_NE(t1.find(fmt::format("{},{},{},{}\n", r.name, r.max_deg, r.mean_deg, r.std_deg)),
              std::string::npos) << r.name;
  const std::string cells = slurp(dir / "cells.csv");
  EXPECT_EQ(std::count(cells.begin(), cells.end(), '\n'), 1 + 8 * 6);
  EXPECT_EQ(cells.find("nan"), std::string::npos);
  if (plots) {
    for (const char* png : {"errors.png", "map_K.png", "map_b.png", "map_k.png", "map_eps_deg.png"})
      EXPECT_GT(std::filesystem::file_size(dir / png), 1000u) << png;
    // The maps' axes are image pixels (each cell over its 2 × 2 pixels), labelled; the reference
    // pixel, each cell's TL (step 2's gauge k_1 = 1, ε_1 = 0), named in every map.
    const std::string maps = slurp(dir / "maps.gp");
    for (const char* part : {"set xlabel 'pixel column'", "set ylabel 'pixel row'", "set xrange [0:16]",
                             "set yrange [12:0]", "dx=2 dy=2 origin=(1,1)", "reference pixel: each cell's TL"}) {
      EXPECT_NE(maps.find(part), std::string::npos) << part;
    }
    std::size_t marks = 0;
    for (std::size_t at = 0; (at = maps.find("set title 'TL: the reference pixel'", at)) != std::string::npos; ++at) ++marks;
    EXPECT_EQ(marks, 4u);
  }
  std::filesystem::remove_all(dir);
}

}  // namespace

// ------------------------------------------------------------ the per-cell polarization of a frame
namespace {
// Eq. 18 without noise for one pixel, written here from the spec (§2.3), not from polrig's code.
double eq18_pixel_DN(double K, double b, double k, double alpha_deg, double eps_deg, double I, double d, double phi_deg) {
  const double r = std::numbers::pi / 180.0;
  return 0.5 * K * I * (1.0 + k * d * std::cos(2.0 * phi_deg * r - 2.0 * (alpha_deg - eps_deg) * r)) + b;
}
}  // namespace

TEST(DofpCellPolarization, RecoversTheLightOfEveryCellWithTheTrueParametersAndEq5WithTheNominalOnes) {
  const int W = 8, H = 6;
  const std::array<double, 4> mosaic = {0, 90, 45, 135};
  polrig::DofpTruth truth = polrig::nominal_dofp_parameters(W, H, mosaic);
  std::vector<double> frame(static_cast<std::size_t>(W * H)), ideal(frame.size());
  const double I = 3.0;
  for (int row = 0; row < H; ++row)
    for (int col = 0; col < W; ++col) {
      const std::size_t p = static_cast<std::size_t>(row) * W + col;
      const int cell = (row / 2) * (W / 2) + col / 2;
      const double phi = 7.0 + 11.0 * cell, d = 0.2 + 0.02 * cell;  // a different light per cell
      truth.K[p] = 1000.0 * (1.0 + 0.01 * ((p * 7) % 5));
      truth.b[p] = 3.0 + (p % 4);
      truth.k[p] = 0.9 + 0.01 * (p % 3);
      truth.eps_deg[p] = 0.5 * ((p % 5) - 2.0);
      frame[p] = eq18_pixel_DN(truth.K[p], truth.b[p], truth.k[p], truth.alpha_deg[p], truth.eps_deg[p], I, d, phi);
      ideal[p] = eq18_pixel_DN(1.0, 0.0, 1.0, truth.alpha_deg[p], 0.0, I, d, phi);
    }
  const polrig::DofpCellPolarization c = polrig::dofp_cell_polarization(frame, truth);
  const polrig::DofpCellPolarization n =
      polrig::dofp_cell_polarization(ideal, polrig::nominal_dofp_parameters(W, H, mosaic));
  ASSERT_EQ(c.cells_x, W / 2);
  ASSERT_EQ(c.cells_y, H / 2);
  // Rounding only: the cell's 4 × 3 least squares (an LDLT of AᵀA, condition ≈ 4) of values
  // F = (f − b)/K of O(1) gives the Stokes parameters to a few ε·κ ≈ 1e-15, so S0 and d (≥ 0.2)
  // to 1e-12 relative and φ to ≈ 1e-15/(2d) rad ≈ 1e-13°; 1e-9° also covers the AoP's
  // fmod/atan2 on angles of O(100°) (ε·100°·… ≈ 1e-14°) with room for the LDLT's pivots.
  for (int cell = 0; cell < c.cells_x * c.cells_y; ++cell) {
    const double phi = std::fmod(7.0 + 11.0 * cell, 180.0), d = 0.2 + 0.02 * cell;
    for (const polrig::DofpCellPolarization* r : {&c, &n}) {
      EXPECT_NEAR(r->aop_deg[static_cast<std::size_t>(cell)], phi, 1e-9) << cell;
      EXPECT_NEAR(r->dop[static_cast<std::size_t>(cell)], d, 1e-12) << cell;
      EXPECT_NEAR(r->S0[static_cast<std::size_t>(cell)], I, 1e-12) << cell;
    }
  }
  // Eq. 5 in closed form for α = (0, 90, 45, 135): q1 = (f1 − f2)/2, q2 = (f3 − f4)/2, q3 = Σf/4.
  const double f1 = ideal[0], f2 = ideal[1], f3 = ideal[static_cast<std::size_t>(W)], f4 = ideal[static_cast<std::size_t>(W) + 1];
  const double q1 = (f1 - f2) / 2, q2 = (f3 - f4) / 2, q3 = (f1 + f2 + f3 + f4) / 4;
  EXPECT_NEAR(n.dop[0], std::hypot(q1, q2) / q3, 1e-14);
}

TEST(DofpCellPolarization, RefusesMismatchedSizesAndBadParameters) {
  polrig::DofpTruth p = polrig::nominal_dofp_parameters(4, 2, {0, 90, 45, 135});
  std::vector<double> frame(8, 100.0);
  EXPECT_THROW(polrig::dofp_cell_polarization(std::vector<double>(7, 1.0), p), std::invalid_argument);
  p.K[5] = -1.0;
  EXPECT_THROW(polrig::dofp_cell_polarization(frame, p), std::invalid_argument);
  p.K[5] = 0.0;  // step 1's undetermined pixel (1, 1): its cell (0, 0) has no value, cell (1, 0) has
  const polrig::DofpCellPolarization undetermined = polrig::dofp_cell_polarization(frame, p);
  EXPECT_TRUE(std::isnan(undetermined.aop_deg[0]) && std::isnan(undetermined.dop[0]) && std::isnan(undetermined.S0[0]));
  EXPECT_TRUE(std::isfinite(undetermined.S0[1]));
  p = polrig::nominal_dofp_parameters(4, 2, {0, 0, 0, 0});  // four parallel analyzers: no Stokes plane
  try {
    polrig::dofp_cell_polarization(frame, p);
    ADD_FAILURE() << "parallel analyzers accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("cell (0, 0) do not span the Stokes plane"), std::string::npos) << e.what();
  }
  EXPECT_THROW(polrig::nominal_dofp_parameters(3, 2, {0, 90, 45, 135}), std::invalid_argument);
}

// ------------------------------------------------------------ one ψ_0 for the image (issue 23)
namespace {
// The camera's own frames (sim/dofp_frames.h: every pixel sees the port polarizer along its own
// view) of a camera with H17's 77° × 61° field on 64 × 48 pixels (f_c = 40.5 px, so a pixel's own
// view matters ten times more than on H17's sensor), noise-free through a 16-bit ADC; every analyzer
// off its nominal angle, TL included (ε = 0.5, 1.2, −0.8, 0.6° ± 0.3°), and off k = 1.
Rig gauge_rig() {
  Rig rig;
  rig.device_kind = "dofp-camera";
  rig.source.cos4.E_0 = 1.0;
  rig.source.polarizer_deg = 20.0;  // β = θ_R − ψ_P on the axis (docs/physics.md §13): ψ_0 = −20°
  rig.device.d = 0.999;
  DofpCameraSpec& c = rig.camera;
  c.width_px = 64, c.height_px = 48, c.focal_mm = 0.3;
  c.noise = false, c.adc_bits = 16;
  c.gain_DN = 50000, c.gain_spread = 0.02, c.mosaic_gain = {1.00, 1.06, 0.95, 1.03};
  c.offset_DN = 20, c.offset_spread_DN = 2;
  c.k = {0.98, 0.93, 0.96, 0.90}, c.k_spread = 0.01;
  c.eps_deg = {0.5, 1.2, -0.8, 0.6}, c.eps_spread_deg = 0.3;
  rig.schedule.start_deg = 0, rig.schedule.step_deg = 4.6036, rig.schedule.stop_deg = 359.0808;
  for (int i = 0; i < 30; ++i) rig.schedule.unpolarized_levels.push_back(i / 29.0);
  rig.schedule.intensities = {1.0};
  rig.seed = 23;
  return rig;
}

struct CameraRun {
  DofpTruth truth;
  std::vector<std::vector<double>> frames;
  std::vector<DofpUnpolarizedLevel> levels;
  std::vector<DofpPolarizedStop> stops;
};

CameraRun camera_run(const Rig& rig) {
  const DofpSimulator sim(rig);
  CameraRun r;
  r.truth = sim.truth();
  for (const DofpStop& s : sim.stops()) {
    const std::vector<std::uint16_t> raw = sim.frame(s, 0);
    r.frames.emplace_back(raw.begin(), raw.end());
  }
  for (std::size_t i = 0; i < sim.stops().size(); ++i) {
    const DofpStop& s = sim.stops()[i];
    if (s.polarized)
      r.stops.push_back({s.theta_R_deg, s.intensity, r.frames[i]});
    else
      r.levels.push_back({s.intensity, r.frames[i]});
  }
  return r;
}
}  // namespace

// Noise-free frames of the camera itself, rounded by a 16-bit ADC: with the view's projection
// step 2 fits one ψ_0 for the image and every ε per cell, TL's too, to what the rounding allows.
//
// Tolerances, from the ADC's rounding alone (|δf| ≤ ½ DN per value; the worst case, linear):
// - step 1, b = Σ w_i f_i and K = Σ v_i f_i over the 30 levels: |δb| ≤ ½·Σ|w_i|, |δK| ≤ ½·Σ|v_i|
//   (computed below from the levels: 0.40 DN and 2.4e-5 of K);
// - step 2, a pixel of modulation amplitude A = K/2·k·d (DN at I = 1, A_min ≈ 1.9e4 here) over N
//   evenly spread stops: its angle, a least-squares fit against the regressor 2A·sin, moves by at most
//   ½·Σ|sin|/(2A·Σsin²) = ½·(2N/π)/(A·N) = 1/(πA) rad, its amplitude by (2/π)/A relative. A
//   constant error of a pixel (step 1's δb, or δK on the mean level) is ⊥ sin and cos over a full
//   turn: it leaves ε and k alone. The cell's shared unknowns (ε_1's common rotation and d_0 from
//   the same four pixels) at most double a pixel's bound: ε to 2/(πA_min), k (a ratio k_j/k_1 of two
//   such amplitudes, plus step 1's δK/K) to 2·(2·2/(πA_min) + δK/K);
// - ψ_0, fitted from every cell at once: within ε's bound;
// - Table 1's step 2: a cell's AoP from its four values moves by at most ½·(|δq1| + |δq2|)/A ≤
//   ½/A_min, its fitted ε by the bound above; o_m − o_0 differences two stops: 2·(½/A_min + 2/(πA_min)).
// H17's gauge (ε_1 = 0 and ψ_0 per cell) fails every one of these: its cells put TL's 0.5° into
// their ψ_0, and the projection's nonlinearity in β leaves 1e-2° in the others and in Table 1.
TEST(DofpCalibration, ViewProjectionFitsOnePsi0AndEveryAnalyzerToTheAdcRounding) {
  const Rig rig = gauge_rig();
  const CameraRun run = camera_run(rig);
  const DofpTruth& t = run.truth;
  DofpCalibrationOptions co;
  co.step2.view_projection = true;
  co.step2.focal_px = focal_px(rig.camera);
  const DofpCalibration c = calibrate_dofp(t.width, t.height, run.levels, run.stops, co);

  // The rounding bounds.
  double sx = 0, sxx = 0;
  const double n = static_cast<double>(run.levels.size());
  for (const DofpUnpolarizedLevel& L : run.levels) sx += L.intensity / 2;
  const double xbar = sx / n;
  for (const DofpUnpolarizedLevel& L : run.levels) sxx += (L.intensity / 2 - xbar) * (L.intensity / 2 - xbar);
  double wb = 0, vK = 0;
  for (const DofpUnpolarizedLevel& L : run.levels) {
    const double dx = L.intensity / 2 - xbar;
    wb += std::abs(1.0 / n - xbar * dx / sxx);
    vK += std::abs(dx / sxx);
  }
  double A_min = 1e300, K_min = 1e300;
  for (std::size_t p = 0; p < t.K.size(); ++p) {
    A_min = std::min(A_min, 0.5 * t.K[p] * t.k[p] * rig.device.d);
    K_min = std::min(K_min, t.K[p]);
  }
  const double b_tol = 0.5 * wb, K_tol = 0.5 * vK / K_min;
  const double eps_tol = rad2deg(2.0 / (kPi * A_min)), k_tol = 2.0 * (4.0 / (kPi * A_min) + K_tol);
  const double table_tol = rad2deg(2.0 * (0.5 / A_min + 2.0 / (kPi * A_min)));
  EXPECT_LT(eps_tol, 2e-3);

  double worst_b = 0, worst_K = 0, worst_eps = 0, worst_k = 0;
  for (std::size_t p = 0; p < t.K.size(); ++p) {
    worst_b = std::max(worst_b, std::abs(c.step1.b[p] - t.b[p]));
    worst_K = std::max(worst_K, std::abs(c.step1.K[p] / t.K[p] - 1));
  }
  ASSERT_EQ(c.step2.usable_cells, static_cast<long long>(c.step2.cells.size()));
  for (int cy = 0; cy < c.step2.cells_y; ++cy)
    for (int cx = 0; cx < c.step2.cells_x; ++cx) {
      const DofpCellFit& f = c.step2.cells[static_cast<std::size_t>(cy) * c.step2.cells_x + cx];
      const std::size_t tl = static_cast<std::size_t>(2 * cy) * t.width + 2 * cx;
      for (int j = 0; j < 4; ++j) {
        const std::size_t p = tl + static_cast<std::size_t>(j / 2) * t.width + j % 2;
        worst_eps = std::max(worst_eps, std::abs(f.eps_deg[j] - t.eps_deg[p]));
        worst_k = std::max(worst_k, std::abs(f.k[j] - t.k[p] / t.k[tl]));
      }
    }
  EXPECT_LT(worst_b, b_tol);
  EXPECT_LT(worst_K, K_tol);
  EXPECT_LT(worst_eps, eps_tol);
  EXPECT_LT(worst_k, k_tol);
  EXPECT_TRUE(c.step2.psi0_fit.usable()) << c.step2.psi0_fit.message;
  EXPECT_NEAR(c.step2.psi0_deg, -20.0, eps_tol);
  for (const DofpCellFit& f : c.step2.cells) EXPECT_EQ(f.psi0_deg, c.step2.psi0_deg);
  EXPECT_LT(c.table1.rows[2].max_deg, table_tol);
  std::cout << fmt::format("b {:.3g} (tol {:.3g}) DN, K {:.3g} ({:.3g}), eps {:.3g} ({:.3g}) deg, k {:.3g} ({:.3g}), "
                           "psi0 {:.9g} deg ({} passes), Table 1 step 2 {:.3g} ({:.3g}) deg\n",
                           worst_b, b_tol, worst_K, K_tol, worst_eps, eps_tol, worst_k, k_tol, c.step2.psi0_deg,
                           c.step2.psi0_fit.evaluations, c.table1.rows[2].max_deg, table_tol);
}
