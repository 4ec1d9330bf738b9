// compass/orientation: the sun vector and heading from a DoFP camera's sky image (H17 Eqs. 6–14,
// spec §2.5). The sky images are rendered here from sky/'s single-scattering Rayleigh sky
// (sky_light: its AoP in the local meridian frame, or its E-vector), projected into the image
// with a few lines of this file's own (φ in frame i from the sky, then φ_pix = φ + α), never with
// the solver's forward code. The camera is H17's: 640 × 480 pixels, f_c = 405.4 px, in unit cells
// of 2 × 2 pixels: 320 × 240 cells over the whole field. (H17 and spec §2.1 say 160 × 120 cells,
// 19,200 units, which 640 × 480 pixels in 2 × 2 cells do not give; the solver takes any points.)
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <limits>
#include <string>
#include <unistd.h>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "polrig/compass/heading.h"
#include "polrig/compass/orientation.h"
#include "polrig/report/orientation_report.h"
#include "polrig/sky/rayleigh.h"
#include "polrig/units.h"

namespace {
using namespace polrig;
using Eigen::AngleAxisd;
using Eigen::Matrix3d;
using Eigen::Vector3d;

constexpr int kCols = 320, kRows = 240;  // unit cells
constexpr double kFc = 405.4;            // px (spec §2.1)
const CameraIntrinsics kCamera{kFc, 320.0, 240.0};

Vector3d sun_enu(double A, double h) {  // spec §0: A from north towards east
  const double a = deg2rad(A), e = deg2rad(h);
  return {std::cos(e) * std::sin(a), std::cos(e) * std::cos(a), std::sin(e)};
}

// The camera's axes in ENU: columns X_l, Y_l, Z_l. A level camera whose X_l points at geographic
// azimuth H: X_l = (sin H, cos H, 0), Z_l = up, Y_l = Z_l × X_l.
Matrix3d level_camera(double H) {
  const Vector3d x{std::sin(deg2rad(H)), std::cos(deg2rad(H)), 0}, z{0, 0, 1};
  Matrix3d c;
  c.col(0) = x;
  c.col(1) = z.cross(x);
  c.col(2) = z;
  return c;
}

// The true heading of a level camera: the geographic azimuth of its X_l.
double true_heading(const Matrix3d& c) {
  const double a = rad2deg(std::atan2(c(0, 0), c(1, 0)));
  return a < 0 ? a + 360 : a;
}

// The cells' image AoP (degrees) of a sky seen by camera C (l → ENU).
// level: φ in frame i is sky_light's χ (from e_θ towards e_φ of the ENU meridian frame, which
// for a level camera are X_i and Y_i). Otherwise: the E-vector taken into frame l and measured
// from X_i = (cos γ cos α, cos γ sin α, −sin γ) towards Y_i = (−sin α, cos α, 0).
std::vector<double> render_aop(const Matrix3d& C, const Vector3d& s, bool level,
                               std::vector<double>* dop = nullptr) {
  SkyModel model;
  model.P_max.constant = 0.65;
  std::vector<double> aop;
  for (int r = 0; r < kRows; ++r)
    for (int c = 0; c < kCols; ++c) {
      const double dx = 2.0 * c + 1.0 - 320.0, dy = 2.0 * r + 1.0 - 240.0;
      const double alpha = std::atan2(dy, dx), gamma = std::atan(std::hypot(dx, dy) / kFc);
      const Vector3d v = (C * Vector3d(dx, dy, kFc)).normalized();
      const SkyLight L = sky_light({s.x(), s.y(), s.z()}, {v.x(), v.y(), v.z()}, model);
      double phi;
      if (level) {
        phi = deg2rad(L.aop_deg);
      } else {
        const Vector3d e_l = C.transpose() * Vector3d(L.e_vector[0], L.e_vector[1], L.e_vector[2]);
        const Vector3d xi{std::cos(gamma) * std::cos(alpha), std::cos(gamma) * std::sin(alpha),
                          -std::sin(gamma)};
        const Vector3d yi{-std::sin(alpha), std::cos(alpha), 0};
        phi = std::atan2(e_l.dot(yi), e_l.dot(xi));
      }
      aop.push_back(rad2deg(phi + alpha));
      if (dop) dop->push_back(L.dop);
    }
  return aop;
}

double angle_between_deg(const Vec3& a, const Vector3d& b) {
  const Vector3d u{a[0], a[1], a[2]};
  return rad2deg(std::atan2(u.cross(b).norm(), u.dot(b)));
}

// The sun in frame l: Cᵀ·s.
Vector3d sun_in_camera(const Matrix3d& C, const Vector3d& s) { return C.transpose() * s; }

TEST(Orientation, FieldOfViewAndCellCount) {
  // Spec §2.7 item 1: 76.6° × 61.3°; the cells' centres cover the image (1 … 639, 1 … 479).
  EXPECT_NEAR(2 * rad2deg(point_view(0.0, 240.0, {3.0 / 7.4e-3, 320, 240}).gamma_rad), 76.6, 0.05);
  EXPECT_NEAR(2 * rad2deg(point_view(320.0, 0.0, {3.0 / 7.4e-3, 320, 240}).gamma_rad), 61.3, 0.05);
  const SkyPoints p = grid_points(kCols, kRows, 2.0, std::vector<double>(kCols * kRows, 0.0));
  EXPECT_EQ(p.aop_deg.size(), 76800u);
  EXPECT_DOUBLE_EQ(p.x_px[0], 1.0);
  EXPECT_DOUBLE_EQ(p.y_px[kCols], 3.0);
  EXPECT_DOUBLE_EQ(p.x_px.back(), 639.0);
  EXPECT_DOUBLE_EQ(p.y_px.back(), 479.0);
}

TEST(Orientation, EigenvectorRecoversTheSunOfARayleighSky) {
  // The spec's check (§2.5): θ_s = 60.75°, A_s = 35°, and three more sun zenith angles; the
  // camera level at several headings.
  double worst = 0;
  for (double theta_s : {60.75, 10.0, 30.0, 80.0})
  for (double H : {0.0, 37.0, 123.4, 250.0, 359.0}) {
    const Vector3d s = sun_enu(35.0, 90.0 - theta_s);
    const Matrix3d C = level_camera(H);
    const SkyPoints p = grid_points(kCols, kRows, 2.0, render_aop(C, s, true));
    const SunVectorSolution sol = sun_vector_eigen(p, kCamera);
    ASSERT_EQ(sol.status, SunVectorStatus::Ok) << H;
    EXPECT_EQ(sol.root, SunRoot::AboveHorizon);
    EXPECT_EQ(sol.vectors_used, kCols * kRows);
    const double error = angle_between_deg(sol.sun, sun_in_camera(C, s));
    worst = std::max(worst, error);
    EXPECT_LT(error, 1e-9) << H;
    EXPECT_NEAR(sol.sun_el_deg, 90.0 - theta_s, 1e-9);
    // Heading: the geographic azimuth of X_l, to the same precision.
    EXPECT_LT(std::abs(heading_difference_deg(camera_heading_deg(35.0, sol.sun_az_deg), H)), 1e-9)
        << H;
    // Every rendered E-vector is ⊥ s; λ₁ carries the rounding of EEᵀ's sums, about ε·λ₃, so
    // √(λ₁/N) ≈ √(ε·λ₃/N) ≤ √(2.2e-16) = 1.5e-8.
    EXPECT_LT(sol.rms_residual, 1e-7);
  }
  RecordProperty("worst_error_deg", std::to_string(worst));  // docs/validation.md: 5.4e-13°
  std::printf("worst sun error %.3g deg\n", worst);
}

TEST(Orientation, EigenvectorRecoversTheSunWithATiltedCamera) {
  // The E-vector route of the rendering (not the level-only χ shortcut): the camera rolled 7°
  // and pitched −4°; the sun's direction in frame l is recovered, whatever the tilt.
  const Vector3d s = sun_enu(200.0, 22.0);
  const Matrix3d C = level_camera(71.0) * AngleAxisd(deg2rad(7.0), Vector3d::UnitY()).toRotationMatrix() *
                     AngleAxisd(deg2rad(-4.0), Vector3d::UnitX()).toRotationMatrix();
  const SkyPoints p = grid_points(kCols, kRows, 2.0, render_aop(C, s, false));
  const SunVectorSolution sol = sun_vector_eigen(p, kCamera);
  ASSERT_EQ(sol.status, SunVectorStatus::Ok);
  EXPECT_LT(angle_between_deg(sol.sun, sun_in_camera(C, s)), 1e-9);
}

TEST(Orientation, WithoutTheConversionTheSunIsWrong) {
  // Spec §2.5: without φ = φ_pix − α "e is wrong by α". Feeding the frame-i angle φ where φ_pix
  // belongs must move the sun far off: the test fails if the conversion were a no-op.
  const Vector3d s = sun_enu(35.0, 29.25);
  const Matrix3d C = level_camera(10.0);
  std::vector<double> aop = render_aop(C, s, true);
  for (int r = 0; r < kRows; ++r)
    for (int c = 0; c < kCols; ++c)
      aop[static_cast<std::size_t>(r * kCols + c)] -= rad2deg(std::atan2(2.0 * r + 1 - 240, 2.0 * c + 1 - 320));
  const SunVectorSolution sol = sun_vector_eigen(grid_points(kCols, kRows, 2.0, aop), kCamera);
  EXPECT_GT(angle_between_deg(sol.sun, sun_in_camera(C, s)), 1.0);
}

TEST(Orientation, HeadingSignTestOfSpec0) {
  // Spec §0: rotate the device by +10° anticlockwise seen from above (an active right-hand
  // rotation about the up axis); the heading, clockwise from north, must fall by 10°.
  const Vector3d s = sun_enu(250.0, 35.0);
  const Matrix3d C0 = level_camera(80.0);
  const Matrix3d C1 = AngleAxisd(deg2rad(10.0), Vector3d::UnitZ()).toRotationMatrix() * C0;
  double h[2];
  int i = 0;
  for (const Matrix3d* C : {&C0, &C1}) {
    const SkyPoints p = grid_points(kCols, kRows, 2.0, render_aop(*C, s, true));
    const auto est = orient_frame(p, kCamera, 250.0);
    ASSERT_TRUE(est[0].heading_deg.has_value());
    h[i] = *est[0].heading_deg;
    EXPECT_NEAR(heading_difference_deg(h[i], true_heading(*C)), 0.0, 1e-9);
    ++i;
  }
  EXPECT_NEAR(heading_difference_deg(h[1], h[0]), -10.0, 1e-9);
}

TEST(Orientation, ComparatorsRecoverTheSunAzimuthOnACleanSky) {
  // Single point: the four cells around the principal point sit at γ = √2/f_c = 0.20° from the
  // zenith. There e ∝ s × ẑ; moving the view by δ (|δ| = γ) turns e's horizontal part by at most
  // cos θ_s·|δ| / sin θ_s (the horizontal part of s × δ over |s × ẑ| = sin θ_s), so one cell is
  // off by up to γ·cot θ_s (0.11° here). The four cells are symmetric under δ → −δ, so the first
  // order cancels in their axial mean, leaving the second: (γ·cot θ_s)² rad (2.2e-4° here).
  // Line detection: the band |φ − 90°| < 1° is mirror-symmetric about the meridian (as the
  // Rayleigh field is) but the cell grid is not; the accumulator's resolution, half a bin
  // (0.25°), bounds the line it finds (measured: under 0.03° after the mean-shift refinement).
  const double theta_s = 60.75;
  const double gamma = std::sqrt(2.0) / kFc;
  const double tol_single = rad2deg(std::pow(gamma / std::tan(deg2rad(theta_s)), 2));
  const double tol_line = 0.5 * OrientationSettings{}.hough_bin_deg;
  for (double H : {0.0, 33.3, 91.0, 200.0, 301.7}) {
    const Vector3d s = sun_enu(35.0, 90.0 - theta_s);
    const Matrix3d C = level_camera(H);
    const SkyPoints p = grid_points(kCols, kRows, 2.0, render_aop(C, s, true));
    const Vector3d s_l = sun_in_camera(C, s);
    const double az = rad2deg(std::atan2(s_l.y(), s_l.x()));
    // Without a prior: the meridian only.
    const SunAzimuthSolution sp0 = sun_azimuth_single_point(p, kCamera);
    EXPECT_EQ(sp0.status, SunAzimuthStatus::Ambiguous180);
    EXPECT_EQ(sp0.points_used, 4);
    EXPECT_LT(std::abs(axis_difference_deg(sp0.meridian_deg, az)), tol_single) << H;
    // With a prior 60° off: the sun's half.
    const SunAzimuthSolution sp = sun_azimuth_single_point(p, kCamera, {}, az + 60.0);
    EXPECT_EQ(sp.status, SunAzimuthStatus::Ok);
    EXPECT_LT(std::abs(heading_difference_deg(sp.sun_az_deg, az)), tol_single) << H;
    const SunAzimuthSolution ln = sun_azimuth_line(p, kCamera, {}, az - 60.0);
    EXPECT_EQ(ln.status, SunAzimuthStatus::Ok);
    EXPECT_GT(ln.points_used, 100);
    EXPECT_LT(std::abs(heading_difference_deg(ln.sun_az_deg, az)), tol_line) << H;
    // Through orient_frame: all three headings near the truth.
    const auto est = orient_frame(p, kCamera, 35.0);
    for (const OrientationEstimate& e : est) {
      ASSERT_TRUE(e.heading_deg.has_value()) << orientation_method_name(e.method);
      EXPECT_LT(std::abs(heading_difference_deg(*e.heading_deg, H)), std::max(tol_single, tol_line));
    }
  }
}

TEST(Orientation, SunBelowTheHorizonNeedsAPrior) {
  // Spec §2.5 / Table 3: h_s = −0.5°. The s_z > 0 rule takes the antisun (flagged near-horizon);
  // a prior from the ephemeris and a heading known to 20° takes the sun.
  const double A = 290.0, h = -0.5, H = 140.0;
  const Vector3d s = sun_enu(A, h);
  const Matrix3d C = level_camera(H);
  const SkyPoints p = grid_points(kCols, kRows, 2.0, render_aop(C, s, true));
  const SunVectorSolution bare = sun_vector_eigen(p, kCamera);
  EXPECT_EQ(bare.status, SunVectorStatus::NearHorizon);
  EXPECT_EQ(bare.root, SunRoot::AboveHorizon);
  EXPECT_LT(angle_between_deg(bare.sun, -sun_in_camera(C, s)), 1e-9);  // the antisun
  EXPECT_NEAR(bare.sun_el_deg, 0.5, 1e-9);

  OrientationSettings with_prior;
  with_prior.prior_sun = sun_in_level_camera(A, 0.0, H + 20.0);
  const SunVectorSolution sol = sun_vector_eigen(p, kCamera, with_prior);
  EXPECT_EQ(sol.status, SunVectorStatus::Ok);
  EXPECT_EQ(sol.root, SunRoot::Prior);
  EXPECT_LT(angle_between_deg(sol.sun, sun_in_camera(C, s)), 1e-9);
  EXPECT_NEAR(sol.sun_el_deg, -0.5, 1e-9);
  EXPECT_NEAR(heading_difference_deg(camera_heading_deg(A, sol.sun_az_deg), H), 0.0, 1e-9);

  // A sun just above the horizon without a prior: right, but flagged.
  const Vector3d s_up = sun_enu(A, 0.5);
  const SunVectorSolution up =
      sun_vector_eigen(grid_points(kCols, kRows, 2.0, render_aop(C, s_up, true)), kCamera);
  EXPECT_EQ(up.status, SunVectorStatus::NearHorizon);
  EXPECT_LT(angle_between_deg(up.sun, sun_in_camera(C, s_up)), 1e-9);
}

TEST(Orientation, DopWeightingIgnoresUnpolarizedPoints) {
  // Corrupt 2000 cells' AoP and give them DoP 0: weighted by DoP they drop out; unweighted they
  // pull the sun away.
  const Vector3d s = sun_enu(120.0, 40.0);
  const Matrix3d C = level_camera(15.0);
  std::vector<double> dop;
  std::vector<double> aop = render_aop(C, s, true, &dop);
  for (std::size_t k = 0; k < 2000; ++k) {
    aop[k * 9] += 37.0;
    dop[k * 9] = 0.0;
  }
  const SkyPoints p = grid_points(kCols, kRows, 2.0, aop, dop);
  OrientationSettings w;
  w.dop_weighting = true;
  const SunVectorSolution weighted = sun_vector_eigen(p, kCamera, w);
  EXPECT_EQ(weighted.vectors_used, kCols * kRows - 2000);
  EXPECT_LT(angle_between_deg(weighted.sun, sun_in_camera(C, s)), 1e-9);
  const SunVectorSolution plain = sun_vector_eigen(p, kCamera);
  EXPECT_GT(angle_between_deg(plain.sun, sun_in_camera(C, s)), 0.1);
  // min_dop leaves them out too, unweighted.
  OrientationSettings cut;
  cut.min_dop = 0.01;
  EXPECT_LT(angle_between_deg(sun_vector_eigen(p, kCamera, cut).sun, sun_in_camera(C, s)), 1e-9);
}

TEST(Orientation, AnalyzerInFrontDiffersFromMeridionalBySpecsBound) {
  // Spec §2.5: the two conversions differ by up to 6.8° at γ = 38°, α = 45°.
  const double r = kFc * std::tan(deg2rad(38.0));
  const double x = 320.0 + r * std::cos(deg2rad(45.0)), y = 240.0 + r * std::sin(deg2rad(45.0));
  double worst = 0;
  for (int k = 0; k < 1800; ++k) {
    const double phi_pix = 0.1 * k;
    const Vec3 a = point_e_vector(phi_pix, x, y, kCamera, AopConversion::Meridional);
    const Vec3 b = point_e_vector(phi_pix, x, y, kCamera, AopConversion::AnalyzerInFront);
    const Vector3d bv{b[0], b[1], b[2]};
    double ang = angle_between_deg(a, bv);
    if (ang > 90) ang = 180 - ang;
    worst = std::max(worst, ang);
  }
  EXPECT_NEAR(worst, 6.8, 0.05);
  // Both are ⊥ the view.
  const Vector3d v = Vector3d(x - 320.0, y - 240.0, kFc).normalized();
  for (AopConversion c : {AopConversion::Meridional, AopConversion::AnalyzerInFront}) {
    const Vec3 e = point_e_vector(17.0, x, y, kCamera, c);
    EXPECT_NEAR(e[0] * v.x() + e[1] * v.y() + e[2] * v.z(), 0.0, 1e-15);
    EXPECT_NEAR(std::hypot(e[0], e[1], e[2]), 1.0, 1e-15);
  }
}

TEST(Orientation, BadInputGivesAStatusNotNaN) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // No points.
  const SkyPoints none;
  SunVectorSolution sol = sun_vector_eigen(none, kCamera);
  EXPECT_EQ(sol.status, SunVectorStatus::TooFewVectors);
  EXPECT_EQ(sol.vectors_used, 0);
  EXPECT_FALSE(has_sun(sol.status));
  // All NaN.
  const SkyPoints all_nan = grid_points(kCols, kRows, 2.0, std::vector<double>(kCols * kRows, nan));
  sol = sun_vector_eigen(all_nan, kCamera);
  EXPECT_EQ(sol.status, SunVectorStatus::TooFewVectors);
  for (double v : {sol.sun_az_deg, sol.sun_el_deg, sol.relative_gap, sol.rms_residual})
    EXPECT_TRUE(std::isfinite(v));
  EXPECT_EQ(sun_azimuth_single_point(all_nan, kCamera).status, SunAzimuthStatus::NoPoints);
  EXPECT_EQ(sun_azimuth_line(all_nan, kCamera).status, SunAzimuthStatus::NoPoints);
  const auto est = orient_frame(all_nan, kCamera, 100.0);
  for (const OrientationEstimate& e : est) {
    EXPECT_FALSE(e.solved);
    EXPECT_FALSE(e.heading_deg.has_value());
    EXPECT_TRUE(std::isfinite(e.sun_az_deg));
  }
  EXPECT_EQ(est[0].status, "too-few-vectors");
  EXPECT_EQ(est[1].status, "no-points");
  // One point.
  SkyPoints one;
  one.x_px = {100};
  one.y_px = {100};
  one.aop_deg = {30};
  EXPECT_EQ(sun_vector_eigen(one, kCamera).status, SunVectorStatus::TooFewVectors);
  // Many copies of one point: one E-vector, a two-dimensional null space.
  SkyPoints same;
  same.x_px.assign(50, 100.0);
  same.y_px.assign(50, 80.0);
  same.aop_deg.assign(50, 30.0);
  sol = sun_vector_eigen(same, kCamera);
  EXPECT_EQ(sol.status, SunVectorStatus::Degenerate);
  EXPECT_EQ(sol.vectors_used, 50);
  // Inconsistent arrays, bad intrinsics, bad settings: exceptions naming the value.
  SkyPoints bad = one;
  bad.y_px.clear();
  EXPECT_THROW(sun_vector_eigen(bad, kCamera), std::invalid_argument);
  EXPECT_THROW(sun_vector_eigen(one, {0.0, 320, 240}), std::invalid_argument);
  EXPECT_THROW(grid_points(2, 2, 2.0, {1, 2, 3}), std::invalid_argument);
  OrientationSettings s;
  s.hough_bin_deg = -1;
  EXPECT_THROW(sun_azimuth_line(one, kCamera, s), std::invalid_argument);
  s = {};
  s.prior_sun = Vec3{0, 0, 0};
  EXPECT_THROW(sun_vector_eigen(one, kCamera, s), std::invalid_argument);
  try {
    s = {};
    s.zenith_radius_px = nan;
    sun_azimuth_single_point(one, kCamera, s);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("zenith_radius_px"), std::string::npos) << e.what();
  }
}

TEST(Orientation, NamesRoundTrip) {
  for (AopConversion c : {AopConversion::Meridional, AopConversion::AnalyzerInFront})
    EXPECT_EQ(parse_aop_conversion(aop_conversion_name(c)), c);
  EXPECT_FALSE(parse_aop_conversion("other").has_value());
}

TEST(Orientation, ReportWritesOneRowPerFrameAndMethod) {
  // Two frames of a clean sky at known headings, and one all-NaN frame: orientation.csv's rows,
  // its `nan` cells where nothing is defined, and the error against the true heading.
  const Vector3d s = sun_enu(35.0, 29.25);
  std::vector<FrameOrientation> frames;
  for (int k = 0; k < 2; ++k) {
    const double H = 100.0 + 9.2072 * k;
    const SkyPoints p = grid_points(kCols, kRows, 2.0, render_aop(level_camera(H), s, true));
    frames.push_back({k, orient_frame(p, kCamera, 35.0), H});
  }
  const SkyPoints blank = grid_points(kCols, kRows, 2.0,
                                      std::vector<double>(kCols * kRows, std::nan("")));
  frames.push_back({2, orient_frame(blank, kCamera, 35.0), std::nullopt});
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("polrig_test_orientation_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto files = report_orientation(dir, frames, false);
  ASSERT_EQ(files.size(), 1u);
  std::ifstream in(dir / "orientation.csv");
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "frame,method,sun_az_deg,sun_el_deg,heading_deg,heading_error_deg,status");
  std::vector<std::string> rows;
  while (std::getline(in, line)) rows.push_back(line);
  ASSERT_EQ(rows.size(), 9u);
  EXPECT_EQ(rows[0].substr(0, 14), "0,eigenvector,");
  EXPECT_EQ(rows[1].substr(0, 15), "0,single-point,");
  EXPECT_NE(rows[1].find(",nan,"), std::string::npos);  // a comparator has no elevation
  EXPECT_EQ(rows[8], "2,line-detection,nan,nan,nan,nan,no-points");
  EXPECT_EQ(rows[6], "2,eigenvector,nan,nan,nan,nan,too-few-vectors");
  for (int r : {0, 3}) {  // the eigenvector's heading error, column 6
    std::stringstream ss(rows[static_cast<std::size_t>(r)]);
    std::string c;
    for (int i = 0; i < 6; ++i) std::getline(ss, c, ',');
    EXPECT_LT(std::abs(std::stod(c)), 1e-9) << rows[static_cast<std::size_t>(r)];
  }
  // A defined value that is not finite: an error naming the frame and column.
  frames[0].estimates[0].heading_deg = std::numeric_limits<double>::infinity();
  try {
    report_orientation(dir, frames, false);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("heading_deg"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
