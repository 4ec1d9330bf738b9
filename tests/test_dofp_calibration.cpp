// The two-step DoFP calibration (calib/dofp.h) against frames made here, in the test, straight
// from Eq. 18 with a known per-pixel truth (spec sky-and-compasses.md §2.3–2.4).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>

#include <cmath>
#include <complex>
#include <cstring>
#include <numbers>
#include <random>
#include <span>

#include <Eigen/Dense>
#include <tbb/global_control.h>

#include <fmt/format.h>

#include "polrig/calib/dofp.h"
#include "polrig/calib/dofp_polarization.h"

namespace {
using namespace polrig;

constexpr double kPi = std::numbers::pi;
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

TEST(DofpCalibration, NoiseFreeFramesCalibrateBackToTheTruth) {
  const Truth t = make_truth(16, 12, 1, 1.0);
  const Dataset ds = make_dataset(t, 23.0, 0.8, 0.0);
  const DofpCalibration c = calibrate_dofp(t.W, t.H, ds.levels, ds.stops);
  ASSERT_EQ(c.step1.rank_deficient_pixels, 0);
  ASSERT_EQ(c.step2.usable_cells, 8 * 6);
  const DofpTruth p = dofp_parameter_maps(c);
  for (std::size_t i = 0; i < t.K.size(); ++i) {
    EXPECT_NEAR(p.K[i] / t.K[i], 1.0, 1e-6) << i;
    EXPECT_NEAR(p.b[i], t.b[i], 1e-6) << i;
    EXPECT_NEAR(p.k[i], t.k[i], 1e-6) << i;
    EXPECT_NEAR(p.eps_deg[i], t.eps_deg[i], 1e-6) << i;
    EXPECT_LT(c.step1.residual_rms_DN[i], 1e-9);
  }
  for (const DofpCellFit& f : c.step2.cells) {
    EXPECT_EQ(f.rank, 8);
    EXPECT_LT(f.iterations, 15);
    EXPECT_NEAR(f.dop, 0.8, 1e-9);
    EXPECT_LT(f.final_rms_deg, 1e-9);
    EXPECT_NEAR(f.psi0_deg, 23.0, 1e-6);
    EXPECT_EQ(f.observations, 6 * 79);
  }
  // After step 2 the orientation is exact; before it is not.
  EXPECT_LT(c.table1.rows[2].max_deg, 1e-8);
  EXPECT_GT(c.table1.rows[0].max_deg, 0.1);
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
    EXPECT_NEAR(c.step2.cells[0].k[j], t.k[p], 1e-9);
    EXPECT_NEAR(c.step2.cells[0].eps_deg[j], t.eps_deg[p], 1e-7);
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
    EXPECT_GT(J.col(p).norm(), 1e-3) << p;
  }
  const Eigen::VectorXd r = dofp_cell_residuals(F, theta, x, o);
  EXPECT_LT(r.cwiseAbs().maxCoeff(), kPi / 4);
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
    EXPECT_LT(f.final_rms_deg, 1e-6);  // the AoP is still fitted
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
  EXPECT_LT(r[2].max_deg, 0.05);
  // After step 1 the error is near-sinusoidal in 2θ_R (H17 §4.1): a fit of
  // a + c·cos 2θ + s·sin 2θ + c4·cos 4θ + s4·sin 4θ explains most of its variance.
  Eigen::MatrixXd X(static_cast<Eigen::Index>(r[1].error_deg.size()), 5);
  Eigen::VectorXd y(X.rows());
  for (Eigen::Index m = 0; m < X.rows(); ++m) {
    const double th = rad(c.table1.theta_R_deg[m]);
    X.row(m) << 1, std::cos(2 * th), std::sin(2 * th), std::cos(4 * th), std::sin(4 * th);
    y[m] = r[1].error_deg[m];
  }
  const Eigen::VectorXd beta = X.colPivHouseholderQr().solve(y);
  const double explained = 1.0 - (y - X * beta).squaredNorm() / (y.array() - y.mean()).matrix().squaredNorm();
  EXPECT_GT(explained, 0.95);
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
