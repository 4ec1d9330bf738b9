// W16's radiometric and polarizer-angle calibration of the four cameras (spec sky-and-compasses.md
// §3.3 items 1–2; calib/four_camera.h): noise-free signals give back the truth, noisy frames
// within what their noise allows, the Jacobian against finite differences, the gauge and the frame
// offsets δ_j with large rolls, the refusals.
#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <gtest/gtest.h>

#include "polrig/calib/four_camera.h"
#include "polrig/calib/four_camera_geometry.h"
#include "polrig/io/exr.h"
#include "polrig/io/four_camera_calibration.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/compass/positioning.h"
#include "polrig/report/four_camera_dataset.h"
#include "polrig/report/locate_report.h"
#include "polrig/sim/four_camera_frames.h"
#include "polrig/units.h"
#include "support.h"

using namespace polrig;
namespace fs = std::filesystem;

namespace {

// A small calibration rig: the sphere (cos4 port, E_0 = 1.5) at `levels`, the polarized port
// (d = 0.999) turned over a full turn in `step` degrees. `cameras` adds device.cameras keys.
std::string rig_text(const std::string& cameras, bool noise, double step = 30,
                     const std::string& levels = "[0, 0.5, 1, 1.5, 2]") {
  return fmt::format(
      "device:\n  kind: four-camera\n  d: 0.999\n  cameras:\n    width_px: 120\n    height_px: 90\n"
      "    cx_px: [60, 60.5, 59.5, 60.2]\n    cy_px: [45, 45.3, 44.6, 45.1]\n    noise: {}\n{}"
      "source:\n  model: cos4\n  E_0: 1.5\n"
      "schedule:\n  start_deg: 0\n  step_deg: {}\n  stop_deg: {}\n  unpolarized_levels: {}\nseed: 7\n",
      noise ? "true" : "false", cameras, step, 360 - step, levels);
}

// Every stop's frames, noise-free signals (double) or raw DN.
struct Stops {
  std::vector<std::array<std::vector<double>, 4>> signal;
  std::vector<std::array<std::vector<std::uint16_t>, 4>> raw;
  std::vector<FourCameraFrames<double>> levels_d, polarized_d;
  std::vector<FourCameraFrames<std::uint16_t>> levels_u, polarized_u;
};
Stops stops_of(const FourCameraSimulator& sim, bool raw) {
  Stops s;
  for (const DofpStop& st : sim.stops()) {
    FourCameraSignal sig = sim.signal(st);
    if (raw) s.raw.push_back(sim.frames(sig));
    s.signal.push_back(std::move(sig.f));
  }
  for (std::size_t k = 0; k < sim.stops().size(); ++k) {
    const DofpStop& st = sim.stops()[k];
    FourCameraFrames<double> d{st.index, st.theta_R_deg, st.intensity, {}};
    for (std::size_t j = 0; j < 4; ++j) d.f[j] = s.signal[k][j];
    (st.polarized ? s.polarized_d : s.levels_d).push_back(d);
    if (raw) {
      FourCameraFrames<std::uint16_t> u{st.index, st.theta_R_deg, st.intensity, {}};
      for (std::size_t j = 0; j < 4; ++j) u.f[j] = s.raw[k][j];
      (st.polarized ? s.polarized_u : s.levels_u).push_back(u);
    }
  }
  return s;
}

FourCameraCalibrationOptions options_for(const FourCameraSimulator& sim) {
  FourCameraCalibrationOptions o;
  o.radiometric.intensity_per_level = 1.5;  // the rig's E_0
  o.radiometric.saturation_DN = 4095;
  (void)sim;
  return o;
}

}  // namespace

// Cameras that differ in intrinsics and are misaligned (the defaults' rotations): the recovered
// axes are exact up to the co-registration's bilinear interpolation of the port's slowly varying
// AoP (docs/physics.md §16: ≲ 2e-6° here), K and b to rounding (the sphere's light is uniform).
TEST(FourCameraCalibration, NoiseFreeSignalsGiveTheTruth) {
  const Rig rig = parse_rig(rig_text("", false), "cal").rig;
  const FourCameraSimulator sim(rig);
  const Stops s = stops_of(sim, false);
  const FourCameraModel& t = sim.truth();
  const FourCameraCalibration c = calibrate_four_camera<double>(
      t.camera, t.width, t.height, s.levels_d, s.polarized_d, options_for(sim));
  for (std::size_t j = 0; j < 4; ++j) {
    EXPECT_TRUE(c.radiometry.camera[j].usable()) << c.radiometry.camera[j].message;
    EXPECT_NEAR(c.radiometry.camera[j].K, t.K[j], 1e-12 * t.K[j]) << j;
    EXPECT_NEAR(c.radiometry.camera[j].b, t.b[j], 1e-10) << j;
    EXPECT_EQ(c.radiometry.camera[j].levels_used, 5);
    EXPECT_EQ(c.radiometry.camera[j].rank, 2);
  }
  ASSERT_TRUE(c.polarizer.usable()) << c.polarizer.summary.brief_report();
  EXPECT_EQ(c.polarizer.rank, 5);
  EXPECT_HAS(c.polarizer.summary.brief_report(), "rad^2 (the AoP residuals in rad");  // not Eq. 15's V^2
  for (std::size_t j = 0; j < 4; ++j) {
    EXPECT_NEAR(c.polarizer.eps_deg[j], rig.four_camera.eps_deg[j] - rig.four_camera.eps_deg[0], 2e-6) << j;
    EXPECT_EQ(c.model.axis_deg[j], 45.0 * static_cast<double>(j) + c.polarizer.eps_deg[j]);
    EXPECT_EQ(c.model.K[j], c.radiometry.camera[j].K);
  }
  EXPECT_NEAR(c.polarizer.dop, 0.999, 1e-7);
  EXPECT_NEAR(axis_difference_deg(c.polarizer.psi0_deg, rig.source.polarizer_deg), 0.0, 2e-6);
  EXPECT_LT(c.polarizer.residual_rms_deg, 1e-6);
  // Before: the nominal axes leave the cos 4φ error of the mounting errors (0.23°).
  EXPECT_GT(c.polarizer.residual_rms_before_deg, 0.1);
}

// Identical, aligned cameras: the samples fall on pixel centres up to θ − tan θ, so the fit meets
// the truth to solver precision (1e-10°; measured 4e-14°), and without the view's projection of the
// port polarizer the model is wrong by 0.004° rms: the projection is physics, not decoration.
TEST(FourCameraCalibration, AlignedCamerasGiveTheTruthToSolverPrecision) {
  const std::string cams =
      "    cx_px: [60, 60, 60, 60]\n    cy_px: [45, 45, 45, 45]\n    fx_px: [770, 770, 770, 770]\n"
      "    fy_px: [770, 770, 770, 770]\n    rot_x_deg: [0, 0, 0, 0]\n    rot_y_deg: [0, 0, 0, 0]\n"
      "    rot_z_deg: [0, 0, 0, 0]\n";
  std::string text = rig_text("", false);
  text.replace(text.find("    cx_px"), text.find("    noise") - text.find("    cx_px"), cams);
  const Rig rig = parse_rig(text, "cal").rig;
  const FourCameraSimulator sim(rig);
  const Stops s = stops_of(sim, false);
  const FourCameraModel& t = sim.truth();
  FourCameraCalibrationOptions o = options_for(sim);
  const FourCameraCalibration c = calibrate_four_camera<double>(t.camera, t.width, t.height, s.levels_d, s.polarized_d, o);
  ASSERT_TRUE(c.polarizer.usable()) << c.polarizer.summary.brief_report();
  for (std::size_t j = 1; j < 4; ++j) EXPECT_NEAR(c.polarizer.eps_deg[j], rig.four_camera.eps_deg[j], 1e-10) << j;
  EXPECT_NEAR(c.polarizer.dop, 0.999, 1e-12);
  EXPECT_LT(c.polarizer.residual_rms_deg, 1e-7);
  o.polarizer.view_projection = false;
  const FourCameraCalibration flat = calibrate_four_camera<double>(t.camera, t.width, t.height, s.levels_d, s.polarized_d, o);
  EXPECT_GT(flat.polarizer.residual_rms_deg, 1e-3);
}

// Large rolls about the axis (rot_z up to 30°): in camera 1's frame the data measure ε_j + δ_j; with
// the geometry known the fusion carries δ_j, so the fit gives ε_j in camera j's own frame. With the
// rolls left out of the geometry the same data give ε_j + δ_j (δ_j at the principal point, ≈ the
// roll with FourCameraFusion's sign).
TEST(FourCameraCalibration, LargeRollsGiveEachCamerasOwnAxis) {
  Rig rig = parse_rig(rig_text("", false), "cal").rig;
  rig.four_camera.rot_z_deg = {0, 20, -25, 30};  // beyond the rig keys' ±10°: set in code
  const FourCameraSimulator sim(rig);
  const Stops s = stops_of(sim, false);
  const FourCameraModel& t = sim.truth();
  const FourCameraCalibration c =
      calibrate_four_camera<double>(t.camera, t.width, t.height, s.levels_d, s.polarized_d, options_for(sim));
  ASSERT_TRUE(c.polarizer.usable()) << c.polarizer.summary.brief_report();
  for (std::size_t j = 1; j < 4; ++j) EXPECT_NEAR(c.polarizer.eps_deg[j], rig.four_camera.eps_deg[j], 1e-5) << j;

  std::array<CameraGeometry, 4> unrolled = t.camera;
  for (std::size_t j = 1; j < 4; ++j)
    unrolled[j].R = rotation_from_vector({deg2rad(rig.four_camera.rot_x_deg[j]), deg2rad(rig.four_camera.rot_y_deg[j]), 0});
  const FourCameraCalibration u =
      calibrate_four_camera<double>(unrolled, t.width, t.height, s.levels_d, s.polarized_d, options_for(sim));
  ASSERT_TRUE(u.polarizer.usable()) << u.polarizer.summary.brief_report();
  const VirtualCamera g = sim.fusion().grid();
  const std::size_t centre = static_cast<std::size_t>(std::floor(g.cy)) * static_cast<std::size_t>(g.width) +
                             static_cast<std::size_t>(std::floor(g.cx));
  for (std::size_t j = 1; j < 4; ++j) {
    const double delta = sim.fusion().frame_offset_deg(static_cast<int>(j), centre);
    fmt::print("camera {}: delta {:.6f}, unrolled eps {:.6f}, eps + delta {:.6f}\n", j + 1, delta, u.polarizer.eps_deg[j],
               rig.four_camera.eps_deg[j] + delta);
    EXPECT_GT(std::abs(delta), 19.0) << j;
    // The rolls left out also move the samples, which in the port's near-uniform light costs little.
    EXPECT_NEAR(u.polarizer.eps_deg[j], rig.four_camera.eps_deg[j] + delta, 1e-3) << j;
  }
}

// The analytic Jacobian against central differences at a point away from the solution.
TEST(FourCameraCalibration, JacobianMatchesFiniteDifferences) {
  const Rig rig = parse_rig(rig_text("", true), "cal").rig;
  const FourCameraSimulator sim(rig);
  const Stops s = stops_of(sim, true);
  const FourCameraModel& t = sim.truth();
  PolarizerOptions o;
  o.window_half_px = 4;
  const PolarizerSamples samples = polarizer_samples<std::uint16_t>(t, {0, 45, 90, 135}, s.polarized_u, o);
  Eigen::Matrix<double, 5, 1> x;
  x << 0.01, -0.004, 0.012, 0.3, 0.95;
  const Eigen::MatrixXd J = polarizer_jacobian(samples, x, o);
  ASSERT_EQ(J.rows(), static_cast<Eigen::Index>(2 * samples.pixels() * samples.theta_R_deg.size()));
  double worst = 0;
  for (int c = 0; c < 5; ++c) {
    const double h = 1e-6;
    Eigen::Matrix<double, 5, 1> xp = x, xm = x;
    xp(c) += h, xm(c) -= h;
    const Eigen::VectorXd fd = (polarizer_residuals(samples, xp, o) - polarizer_residuals(samples, xm, o)) / (2 * h);
    for (Eigen::Index k = 0; k < J.rows(); ++k)
      worst = std::max(worst, std::abs(fd(k) - J(k, c)) / (1.0 + std::abs(J(k, c))));
  }
  fmt::print("Jacobian: worst |fd − J|/(1 + |J|) = {:.3g}\n", worst);
  EXPECT_LT(worst, 1e-7);  // central differences: O(h²) ≈ 1e-12 plus rounding 1e-16/h ≈ 1e-10
}

// The AoP alone (the spec's reconstructed cost, w = 0) sees two of the axes' four combinations to
// first order: its Jacobian is nearly singular and the fit says so.
TEST(FourCameraCalibration, AopAloneIsRankDeficient) {
  const Rig rig = parse_rig(rig_text("", false), "cal").rig;
  const FourCameraSimulator sim(rig);
  const Stops s = stops_of(sim, false);
  const FourCameraModel& t = sim.truth();
  FourCameraCalibrationOptions o = options_for(sim);
  o.polarizer.dop_weight = 0;
  const FourCameraCalibration c = calibrate_four_camera<double>(t.camera, t.width, t.height, s.levels_d, s.polarized_d, o);
  fmt::print("AoP alone: {} (σ ratio {:.3g})\n", c.polarizer.summary.brief_report(), c.polarizer.singular_ratio);
  EXPECT_EQ(c.polarizer.summary.termination, FitTermination::RankDeficient);
  EXPECT_LT(c.polarizer.singular_ratio, 0.05);
}

// Polarized stops 90° apart turn the polarizer through two orientations only: each camera then sees
// one number, d·cos 2(ψ_0 − a_j), for five unknowns (ε_2..ε_4, ψ_0, d_0). The fit says so instead of
// "converging" (the views' small projection terms made the Jacobian look full rank: the old fit
// reported rank 5 of 5, a DoP of 1.02 and ε errors of 6–13°). Stops 60° apart are enough.
TEST(FourCameraCalibration, StopsNinetyDegreesApartAreAnIllPosedDesign) {
  for (const double step : {90.0, 60.0}) {
    const Rig rig = parse_rig(rig_text("", false, step), "cal").rig;
    const FourCameraSimulator sim(rig);
    const Stops s = stops_of(sim, false);
    const FourCameraModel& t = sim.truth();
    const FourCameraCalibration c =
        calibrate_four_camera<double>(t.camera, t.width, t.height, s.levels_d, s.polarized_d, options_for(sim));
    if (step == 90.0) {
      EXPECT_EQ(c.polarizer.summary.termination, FitTermination::RankDeficient) << c.polarizer.summary.brief_report();
      EXPECT_HAS(c.polarizer.summary.message, "too few orientations");
      EXPECT_HAS(c.polarizer.summary.message, "90° apart");
    } else {
      ASSERT_TRUE(c.polarizer.usable()) << c.polarizer.summary.brief_report();
      EXPECT_NEAR(c.polarizer.dop, 0.999, 1e-6);
    }
  }
}

// The default noise (10 e⁻/DN, 1 DN read noise, 12 bits): K_j, b_j within 4 standard errors, the
// standard errors themselves what the noise model predicts for a window mean (σ² = signal/10 +
// 1 + 1/12 DN² per pixel, over 65 × 65 px, propagated through the line), and ε_j within 4 of the
// fit's standard errors (the window's samples are independent: stride 2).
TEST(FourCameraCalibration, NoisyFramesWithinTheirNoise) {
  const Rig rig = parse_rig(rig_text("", true), "cal").rig;
  const FourCameraSimulator sim(rig);
  const Stops s = stops_of(sim, true);
  const FourCameraModel& t = sim.truth();
  const FourCameraCalibration c =
      calibrate_four_camera<std::uint16_t>(t.camera, t.width, t.height, s.levels_u, s.polarized_u, options_for(sim));
  const std::vector<double> levels = {0, 0.5, 1, 1.5, 2};
  for (std::size_t j = 0; j < 4; ++j) {
    const CameraRadiometry& r = c.radiometry.camera[j];
    ASSERT_TRUE(r.usable()) << r.message;
    // The predicted σ of K and b: σ_i² = (K·I_i/10 + 1 + 1/12)/N at each level, through the OLS line.
    const double N = static_cast<double>(r.window.pixels());
    double xm = 0, sxx = 0, vK = 0, vb = 0;
    for (double l : levels) xm += 1.5 * l / 5;
    for (double l : levels) sxx += (1.5 * l - xm) * (1.5 * l - xm);
    for (double l : levels) {
      const double ci = (1.5 * l - xm) / sxx, var = (t.K[j] * 1.5 * l / 10 + 1 + 1.0 / 12) / N;
      vK += ci * ci * var, vb += (0.2 - xm * ci) * (0.2 - xm * ci) * var;
    }
    fmt::print("camera {}: K {:.4f} ± {:.4f} (predicted {:.4f}) truth {}; b {:.4f} ± {:.4f} (predicted {:.4f}) truth {}\n",
               j + 1, r.K, r.K_se, std::sqrt(vK), t.K[j], r.b, r.b_se, std::sqrt(vb), t.b[j]);
    EXPECT_NEAR(r.K_se, std::sqrt(vK), 0.15 * std::sqrt(vK)) << j;
    EXPECT_NEAR(r.b_se, std::sqrt(vb), 0.15 * std::sqrt(vb)) << j;
    EXPECT_NEAR(r.K, t.K[j], 4 * r.K_se) << j;
    EXPECT_NEAR(r.b, t.b[j], 4 * r.b_se) << j;
  }
  ASSERT_TRUE(c.polarizer.usable()) << c.polarizer.summary.brief_report();
  fmt::print("polarizer: {}; rms {:.4f}° (before {:.4f}°)\n", c.polarizer.summary.brief_report(),
             c.polarizer.residual_rms_deg, c.polarizer.residual_rms_before_deg);
  for (std::size_t j = 1; j < 4; ++j) {
    fmt::print("eps {}: {:.5f} ± {:.5f} truth {}\n", j + 1, c.polarizer.eps_deg[j], c.polarizer.eps_se_deg[j],
               rig.four_camera.eps_deg[j]);
    EXPECT_NEAR(c.polarizer.eps_deg[j], rig.four_camera.eps_deg[j], 4 * c.polarizer.eps_se_deg[j]) << j;
  }
  fmt::print("d0 {:.6f} ± {:.6f}; psi0 {:.5f} ± {:.5f}\n", c.polarizer.dop, c.polarizer.dop_se, c.polarizer.psi0_deg,
             c.polarizer.psi0_se_deg);
  EXPECT_NEAR(axis_difference_deg(c.polarizer.psi0_deg, 0.0), 0.0, 4 * c.polarizer.psi0_se_deg);
}

// ---- The command: calibrate --method four-camera, locate --calibration ----

namespace {

// The calibration rig's checkerboard left out: these tests take the geometry from the truth (a board
// at an eighth of W16's resolution is too small for OpenCV's corner detector); the geometric part
// has its own test below.
const std::string kNoViews = " --set checkerboard.views=0";

// W16's sensor at an eighth of its resolution (130 × 98 px, f = 96.25 px: the same field).
const std::string kEighth =
    "--set device.cameras.width_px=130 --set device.cameras.height_px=98 "
    "--set device.cameras.cx_px=[65,65.2,64.8,65.1] --set device.cameras.cy_px=[49,48.9,49.2,48.8] "
    "--set device.cameras.fx_px=[96.25,96.4,96.1,96.3] --set device.cameras.fy_px=[96.25,96.4,96.1,96.3]";

class FourCameraCalibrationCli : public test::PolrigTest {
 protected:
  FourCameraCalibrationCli() : PolrigTest("polrig_fcal_", "logs") {}
  std::string rig(const char* name) const { return test::shell_quote(fs::path(POLRIG_SOURCE_DIR) / "rigs" / name); }
  std::string at(const std::string& name) const { return test::shell_quote(tmp / name); }
};

double field(const test::Csv& csv, const std::string& quantity, int camera, const std::string& column) {
  const std::size_t q = csv.col("quantity"), c = csv.col("camera"), k = csv.col(column);
  for (const auto& row : csv.rows)
    if (row[q] == quantity && row[c] == std::to_string(camera)) return std::stod(row[k]);
  ADD_FAILURE() << "no row " << quantity << " " << camera;
  return std::nan("");
}

}  // namespace

// simulate the calibration rig → calibrate → locate a sky dataset with the calibration: the fix and
// the heading are the truth model's within the calibration's error, propagated to them by
// re-locating with each parameter moved by its standard error.
TEST_F(FourCameraCalibrationCli, EndToEndTheCalibratedFixIsTheTruthsWithinItsError) {
  ok(fmt::format("simulate {} -o {} --layers all {}", rig("wang2016-calibration.yaml"), at("cal"), kEighth + kNoViews));
  const Result c = ok(fmt::format("calibrate {} --method four-camera -o {}", at("cal"), at("out")));
  EXPECT_HAS(c.out, "geometry from");
  EXPECT_HAS(c.out, "the simulation's truth");
  for (const char* f : {"calibration.yaml", "radiometric.csv", "polarizer.csv", "summary.csv", "errors.csv", "manifest.yaml"})
    EXPECT_TRUE(fs::exists(tmp / "out" / f)) << f;
  if (test::gnuplot_present()) {
    EXPECT_TRUE(test::starts_with_png_signature(tmp / "out" / "polarizer.png"));
  }
  const test::Csv errors = test::read_csv(tmp / "out" / "errors.csv");
  for (std::size_t r = 0; r < errors.rows.size(); ++r)
    EXPECT_LT(std::abs(std::stod(errors.rows[r][errors.col("error_over_se")])), 4.0) << errors.rows[r][0];
  const FourCameraCalibrationFile cal = read_four_camera_calibration(tmp / "out" / "calibration.yaml");
  EXPECT_HAS(cal.geometry_from, "truth.yaml");

  ok(fmt::format("simulate {} -o {} --layers all {} --set schedule.count=7 --set schedule.dwell_s=600",
                 rig("wang2016-static.yaml"), at("sky"), kEighth));
  const Result with_cal = ok(fmt::format("locate {} --prior 28,113 -o {} --calibration {}", at("sky"), at("loc_cal"),
                                         at("out/calibration.yaml")));
  EXPECT_HAS(with_cal.out, "fused with");
  ok(fmt::format("locate {} --prior 28,113 -o {}", at("sky"), at("loc_truth")));

  const FourCameraCalibrationFile truth = read_four_camera_calibration(tmp / "sky" / "truth.yaml");
  const auto fix = [&](const FourCameraModel& m) {
    return locate_four_camera_folder(tmp / "sky", {28, 113}, {}, {}, {}, m).location;
  };
  const Location t = fix(truth.model), k = fix(cal.model);
  // The truth model re-fused gives the dataset's own fused layers' fix (the same fusion).
  const test::Csv fix_truth = test::read_csv(tmp / "loc_truth" / "fix.csv");
  EXPECT_NEAR(t.fix.chosen.lat_deg, std::stod(fix_truth.rows[0][fix_truth.col("lat_deg")]), 1e-9);
  double var_km = 0, var_h = 0;
  const auto moved = [&](FourCameraModel m) {
    const Location l = fix(m);
    const double d = great_circle_km(l.fix.chosen.lat_deg, l.fix.chosen.lon_deg, t.fix.chosen.lat_deg, t.fix.chosen.lon_deg);
    const double h = std::remainder(l.heading_mean_deg - t.heading_mean_deg, 360.0);
    var_km += d * d, var_h += h * h;
  };
  for (int j = 0; j < 4; ++j) {
    FourCameraModel m = truth.model;
    m.K[static_cast<std::size_t>(j)] += field(errors, "K_DN", j + 1, "standard_error");
    moved(m);
    m = truth.model;
    m.b[static_cast<std::size_t>(j)] += field(errors, "b_DN", j + 1, "standard_error");
    moved(m);
    if (j > 0) {
      m = truth.model;
      m.axis_deg[static_cast<std::size_t>(j)] += field(errors, "eps_deg", j + 1, "standard_error");
      moved(m);
    }
  }
  const double d = great_circle_km(k.fix.chosen.lat_deg, k.fix.chosen.lon_deg, t.fix.chosen.lat_deg, t.fix.chosen.lon_deg);
  const double h = std::remainder(k.heading_mean_deg - t.heading_mean_deg, 360.0);
  fmt::print("calibrated against truth model: fix {:.3f} km (σ {:.3f} km), heading {:.4f}° (σ {:.4f}°)\n", d,
             std::sqrt(var_km), h, std::sqrt(var_h));
  EXPECT_LT(d, 4 * std::sqrt(var_km));
  EXPECT_LT(std::abs(h), 4 * std::sqrt(var_h));
}

// A measured dataset as a user assembles it (formats.md §6.14a "A measured dataset"): no truth.yaml,
// stops.csv's truth columns empty, each stop's EXR only the four cameras' raw UINT frames (no fused
// layers, no attributes), and optionally no rig.yaml. It calibrates and locates exactly as the
// simulated dataset it was made from, and locate without a calibration says what it needs.
void make_measured(const fs::path& from, const fs::path& to, bool keep_rig) {
  fs::copy(from, to, fs::copy_options::recursive);
  fs::remove(to / "truth.yaml");
  if (!keep_rig) fs::remove(to / "rig.yaml");
  // Empties the columns [first, last) of every data row of a CSV file.
  const auto forget = [](const fs::path& file, std::size_t first, std::size_t last) {
    const std::vector<std::string> lines = test::lines_of(test::read_file(file));
    std::string csv = lines.at(0) + "\n";
    for (std::size_t n = 1; n < lines.size(); ++n) {
      std::vector<std::string> c = test::split(lines[n]);
      ASSERT_GE(c.size(), last) << lines[n];
      for (std::size_t k = first; k < last; ++k) c[k].clear();
      csv += fmt::format("{}\n", fmt::join(c, ","));
    }
    test::write_file(file, csv);
  };
  forget(to / "stops.csv", 6, 12);  // heading_deg … sun_zenith_deg: the truth
  if (fs::exists(to / "checkerboard" / "poses.csv"))
    forget(to / "checkerboard" / "poses.csv", 2, 14);  // R_00 … t_z_mm: the boards' true poses
  for (const fs::directory_entry& e : fs::directory_iterator(to / "frames")) {
    ExrImage image = read_exr_image(e.path());
    ASSERT_EQ(image.uints.size(), 5u);  // cam1 … cam4 and valid
    image.uints.pop_back();
    ASSERT_EQ(image.uints.back().name, "cam4");
    image.floats.clear();
    image.attributes = {};
    write_exr_image(e.path(), image);
  }
}

TEST_F(FourCameraCalibrationCli, MeasuredDatasetsCalibrateAndLocateAsTheSimulatedOnes) {
  ok(fmt::format("simulate {} -o {} --layers all {}", rig("wang2016-calibration.yaml"), at("cal"), kEighth + kNoViews));
  ok(fmt::format("simulate {} -o {} --layers all {} --set schedule.count=3 --set schedule.dwell_s=1200",
                 rig("wang2016-static.yaml"), at("sky"), kEighth));
  make_measured(tmp / "cal", tmp / "mcal", true);
  make_measured(tmp / "sky", tmp / "msky", true);
  make_measured(tmp / "sky", tmp / "bare", false);

  // The geometry must now be given (no truth.yaml, no checkerboard views).
  const Result none = polrig(fmt::format("calibrate {} --method four-camera -o {}", at("mcal"), at("out")));
  EXPECT_EQ(none.status, 2);
  EXPECT_HAS(none.err, "no truth.yaml and no --geometry FILE");
  EXPECT_FALSE(fs::exists(tmp / "out"));
  const std::string geometry = at("cal/truth.yaml");
  ok(fmt::format("calibrate {} --method four-camera -o {} --geometry {}", at("cal"), at("sim_cal"), geometry));
  ok(fmt::format("calibrate {} --method four-camera -o {} --geometry {}", at("mcal"), at("meas_cal"), geometry));
  for (const char* f : {"radiometric.csv", "polarizer.csv", "summary.csv"})
    EXPECT_EQ(test::read_file(tmp / "meas_cal" / f), test::read_file(tmp / "sim_cal" / f)) << f;
  EXPECT_FALSE(fs::exists(tmp / "meas_cal" / "errors.csv"));  // no truth to compare with

  // locate: the same fix and headings from the raw frames with the calibration; no truth columns.
  const std::string cal = at("sim_cal/calibration.yaml");
  ok(fmt::format("locate {} --prior 28,113 -o {} --calibration {}", at("sky"), at("sim_loc"), cal));
  ok(fmt::format("locate {} --prior 28,113 -o {} --calibration {}", at("msky"), at("meas_loc"), cal));
  ok(fmt::format("locate {} --prior 28,113 -o {} --calibration {}", at("bare"), at("bare_loc"), cal));
  const test::Csv sim_fix = test::read_csv(tmp / "sim_loc" / "fix.csv");
  for (const char* dir : {"meas_loc", "bare_loc"}) {
    const test::Csv fix = test::read_csv(tmp / dir / "fix.csv");
    ASSERT_EQ(fix.rows.size(), sim_fix.rows.size()) << dir;
    for (const char* column : {"lat_deg", "lon_deg"})
      for (std::size_t r = 0; r < fix.rows.size(); ++r)
        EXPECT_EQ(fix.rows[r][fix.col(column)], sim_fix.rows[r][sim_fix.col(column)]) << dir << " " << column;
    const test::Csv heading = test::read_csv(tmp / dir / "heading.csv");
    const test::Csv sim_heading = test::read_csv(tmp / "sim_loc" / "heading.csv");
    ASSERT_EQ(heading.rows.size(), 3u) << dir;
    for (std::size_t r = 0; r < 3; ++r) {
      EXPECT_EQ(heading.rows[r][heading.col("heading_deg")], sim_heading.rows[r][sim_heading.col("heading_deg")]);
      EXPECT_EQ(heading.rows[r][heading.col("heading_true_deg")], "nan") << dir;
    }
    EXPECT_EQ(test::read_file(tmp / dir / "sun.csv"), test::read_file(tmp / "sim_loc" / "sun.csv")) << dir;
  }
  // The site as the truth when a rig.yaml gives it; none without one.
  const test::Csv with_rig = test::read_csv(tmp / "meas_loc" / "fix.csv");
  const test::Csv bare = test::read_csv(tmp / "bare_loc" / "fix.csv");
  EXPECT_EQ(with_rig.rows[0][with_rig.col("error_km")], sim_fix.rows[0][sim_fix.col("error_km")]);
  EXPECT_EQ(bare.rows[0][bare.col("error_km")], "nan");

  // Without a calibration there is nothing fused to locate from.
  const Result raw_only = polrig(fmt::format("locate {} --prior 28,113 -o {}", at("msky"), at("out")));
  EXPECT_EQ(raw_only.status, 2);
  EXPECT_HAS(raw_only.err, "give --calibration CAL.yaml");
  EXPECT_FALSE(fs::exists(tmp / "out"));
}

// Refusals, each before anything is written: a dataset without unpolarized levels, with one level,
// without raw frames; options that do not apply; a geometry of another size; locate with a bad
// calibration.yaml (file, line, key, value) or on a dataset without raw frames.
// --layers unless told: a calibration rig's dataset holds the raw frames its calibration reads, a
// sky rig's the AoP layers locate reads (default_four_camera_layers).
TEST_F(FourCameraCalibrationCli, ACalibrationRigKeepsTheRawFramesUnlessToldASkyRigTheAopLayers) {
  const auto channels = [](const fs::path& exr) {
    const ExrImage image = read_exr_image(exr);
    std::vector<std::string> names;
    for (const ExrChannel& c : image.floats) names.push_back(c.name);
    for (const ExrUintChannel& c : image.uints) names.push_back(c.name);
    std::sort(names.begin(), names.end());
    return names;
  };
  ok(fmt::format("simulate {} {} --set schedule.step_deg=60 --set schedule.stop_deg=300 -o {}",
                 rig("wang2016-calibration.yaml"), kEighth + kNoViews, at("cal")));
  EXPECT_EQ(channels(tmp / "cal" / "frames" / "stop_0000.exr"),
            (std::vector<std::string>{"AoP", "DoP", "S0", "S1", "S2", "cam1", "cam2", "cam3", "cam4", "valid"}));
  ok(fmt::format("calibrate {} --method four-camera -o {}", at("cal"), at("out")));
  ok(fmt::format("simulate {} {} --set schedule.count=1 -o {}", rig("wang2016-static.yaml"), kEighth, at("sky")));
  EXPECT_EQ(channels(tmp / "sky" / "frames" / "stop_0000.exr"), (std::vector<std::string>{"AoP", "DoP", "valid"}));
}

TEST_F(FourCameraCalibrationCli, RefusesWhatItCannotCalibrate) {
  const auto refused = [&](const std::string& args, const std::string& text) {
    const Result r = polrig(args);
    EXPECT_NE(r.status, 0) << args;
    EXPECT_HAS(r.err, text) << args;
    EXPECT_FALSE(fs::exists(tmp / "out")) << args;
  };
  // Stops 60° apart: the fewest the polarizer fit takes (90° apart is an ill-posed design).
  const std::string base = fmt::format("simulate {} {} --set schedule.step_deg=60 --set schedule.stop_deg=300 ",
                                       rig("wang2016-calibration.yaml"), kEighth + kNoViews);
  ok(base + "--layers all --set schedule.unpolarized_levels=[1] -o " + at("one"));
  refused(fmt::format("calibrate {} --method four-camera -o {}", at("one"), at("out")), "two distinct levels");
  std::string no_levels = test::read_file(fs::path(POLRIG_SOURCE_DIR) / "rigs" / "wang2016-calibration.yaml");
  no_levels.erase(no_levels.find("  unpolarized_levels:"));
  test::write_file(tmp / "no_levels.yaml", no_levels);
  ok(fmt::format("simulate {} {} --set schedule.step_deg=90 --set schedule.stop_deg=270 --layers all -o {}",
                 at("no_levels.yaml"), kEighth, at("none")));
  refused(fmt::format("calibrate {} --method four-camera -o {}", at("none"), at("out")), "no unpolarized stop");
  ok(base + "--layers fused -o " + at("fused"));
  refused(fmt::format("calibrate {} --method four-camera -o {}", at("fused"), at("out")), "--layers all");
  ok(base + "--layers all -o " + at("all"));
  refused(fmt::format("calibrate {} --method four-camera -o {} --drift angle", at("all"), at("out")), "--drift angle");
  refused(fmt::format("calibrate {} --method four-camera -o {} --view-projection", at("all"), at("out")), "--view-projection");
  refused(fmt::format("calibrate {} --method cs -o {} --geometry x.yaml", at("all"), at("out")), "--geometry x.yaml");
  refused(fmt::format("calibrate {} --method cs -o {} --distortion-terms 2", at("all"), at("out")),
          "--distortion-terms 2");
  refused(fmt::format("calibrate {} --method four-camera -o {} --geometry {} --distortion-terms 2", at("all"), at("out"),
                      at("all/truth.yaml")),
          "--distortion-terms 2: the geometric calibration's option");
  ok(fmt::format("simulate {} --set schedule.step_deg=90 --set schedule.stop_deg=270 --layers all -o {} "
                 "--set device.cameras.width_px=120 --set device.cameras.height_px=90 "
                 "--set device.cameras.cx_px=[60,60,60,60] --set device.cameras.cy_px=[45,45,45,45]{}",
                 rig("wang2016-calibration.yaml"), at("other"), kNoViews));
  refused(fmt::format("calibrate {} --method four-camera -o {} --geometry {}", at("all"), at("out"), at("other/truth.yaml")),
          "120 × 90 px");
  ok(fmt::format("calibrate {} --method four-camera -o {} --geometry {}", at("all"), at("geo"), at("all/truth.yaml")));
  EXPECT_HAS(test::read_file(tmp / "geo" / "calibration.yaml"), "geometry: \"" + (tmp / "all" / "truth.yaml").string());

  // A bad calibration.yaml: out-of-range, inconsistent, unknown key, camera 1 rotated.
  const std::string good = test::read_file(tmp / "geo" / "calibration.yaml");
  ok(fmt::format("simulate {} -o {} --layers all {} --set schedule.count=2", rig("wang2016-static.yaml"), at("sky"), kEighth));
  const auto bad = [&](const std::string& from, const std::string& to, const std::string& text) {
    std::string s = good;
    ASSERT_NE(s.find(from), std::string::npos) << from;
    s.replace(s.find(from), from.size(), to);
    test::write_file(tmp / "bad.yaml", s);
    refused(fmt::format("locate {} --prior 28,113 -o {} --calibration {}", at("sky"), at("out"), at("bad.yaml")), text);
  };
  bad("    K_DN: ", "    K_DN: -", "key 'cameras[0].K_DN': expected a gain in (0, 1e6] DN per unit intensity, got -");
  bad("    eps_deg: 0\n", "    eps_deg: 0.5\n", "cameras[0].axis_deg': expected polarizer_deg + eps_deg = 0.5");
  bad("    fx_px: ", "    fx_mm: ", "cameras[0].fx_mm': unknown key");
  bad("    rvec_deg: [0, 0, 0]", "    rvec_deg: [0, 0, 1]", "camera 1 defines the frame");
  bad("    cy_px: ", "    cy_px: nan #", "bad.yaml:");
  const Result line = polrig(fmt::format("locate {} --prior 28,113 -o {} --calibration {}", at("sky"), at("out"), at("bad.yaml")));
  EXPECT_HAS(line.err, "cameras[0].cy_px");
  // locate --calibration needs the raw frames.
  ok(fmt::format("simulate {} -o {} --layers aop {} --set schedule.count=2", rig("wang2016-static.yaml"), at("aop"), kEighth));
  refused(fmt::format("locate {} --prior 28,113 -o {} --calibration {}", at("aop"), at("out"), at("geo/calibration.yaml")),
          "--layers all");
}

// The library's refusals: no polarized stop, a single level, no level.
TEST(FourCameraCalibration, RefusesMissingStops) {
  const Rig rig = parse_rig(rig_text("", false), "cal").rig;
  const FourCameraSimulator sim(rig);
  const Stops s = stops_of(sim, false);
  const FourCameraModel& t = sim.truth();
  const FourCameraCalibrationOptions o = options_for(sim);
  EXPECT_THROW(calibrate_four_camera<double>(t.camera, t.width, t.height, s.levels_d,
                                             std::span<const FourCameraFrames<double>>{}, o),
               CalibrationError);
  EXPECT_THROW(calibrate_four_camera<double>(t.camera, t.width, t.height, std::span<const FourCameraFrames<double>>{},
                                             s.polarized_d, o),
               std::invalid_argument);
  try {
    calibrate_four_camera<double>(t.camera, t.width, t.height, std::span(s.levels_d).first(1), s.polarized_d, o);
    ADD_FAILURE() << "one level calibrated";
  } catch (const CalibrationError& e) {
    EXPECT_HAS(std::string(e.what()), "two distinct levels");
  }
  // Three table angles is the least the fit takes; two are too few observations.
  const FourCameraCalibration two =
      calibrate_four_camera<double>(t.camera, t.width, t.height, s.levels_d, std::span(s.polarized_d).first(2), o);
  EXPECT_EQ(two.polarizer.summary.termination, FitTermination::TooFewObservations);
}

// calibration.yaml reads back to the numbers written (shortest round-trip text), R_j1 through its
// rotation vector (Eigen's angle-axis against device/'s Rodrigues) to 1e-15, and truth.yaml reads
// as a calibration with the same per-camera keys.
TEST(FourCameraCalibrationFile, RoundTripAndTruthYaml) {
  Rig rig = parse_rig(rig_text("", false), "cal").rig;
  rig.four_camera.rot_z_deg = {0, 20, -25, 170};
  const FourCameraModel t = four_camera_truth(rig.four_camera);
  FourCameraCalibrationFile f;
  f.model = t;
  f.polarizer_deg = rig.four_camera.polarizer_deg;
  f.eps_deg = rig.four_camera.eps_deg;
  f.radiometric = f.polarizer = true;
  f.radiometric_from = "a \"quoted\" source";
  for (int j = 0; j < 4; ++j) f.position_mm[static_cast<std::size_t>(j)] = camera_position_mm(rig.four_camera, j);
  test::TempDir dir("polrig_fcal_file_");
  test::write_file(dir.path() / "c.yaml", four_camera_calibration_yaml(f));
  const FourCameraCalibrationFile back = read_four_camera_calibration(dir.path() / "c.yaml");
  EXPECT_EQ(back.radiometric_from, f.radiometric_from);
  for (std::size_t j = 0; j < 4; ++j) {
    EXPECT_EQ(back.model.K[j], t.K[j]);
    EXPECT_EQ(back.model.b[j], t.b[j]);
    EXPECT_EQ(back.model.axis_deg[j], t.axis_deg[j]);
    EXPECT_EQ(back.model.camera[j].fx, t.camera[j].fx);
    EXPECT_EQ(back.model.camera[j].cy, t.camera[j].cy);
    for (std::size_t k = 0; k < 9; ++k) EXPECT_NEAR(back.model.camera[j].R[k], t.camera[j].R[k], 1e-15) << j << k;
  }
  const Vec3 r = rotation_vector_deg(t.camera[3].R);
  EXPECT_NEAR(r[2], 170.0, 1e-12);
  test::write_file(dir.path() / "truth.yaml", four_camera_truth_yaml(rig.four_camera, t, virtual_camera(t)));
  const FourCameraCalibrationFile truth = read_four_camera_calibration(dir.path() / "truth.yaml");
  EXPECT_TRUE(truth.radiometric && truth.polarizer);
  EXPECT_EQ(truth.eps_deg[1], 0.4);
  EXPECT_EQ(truth.position_mm[2][1], 60.0);
}

// The three parts together: a dataset with checkerboard views gets its geometry from the geometric
// calibration (OpenCV), which the polarizer-angle fit then co-registers with; calibration.yaml holds
// geometry.csv's fit, and --distortion-terms reaches the fit. At a third of W16's resolution with
// 45 mm squares, where OpenCV's detector finds the board (tests/test_four_camera_geometry.cpp).
TEST_F(FourCameraCalibrationCli, WithCheckerboardViewsTheGeometryIsTheGeometricCalibrations) {
  const std::string third =
      "--set device.cameras.width_px=345 --set device.cameras.height_px=259 "
      "--set device.cameras.cx_px=[172.5,172.9,172.1,172.8] --set device.cameras.cy_px=[129.8,129.4,130.2,129.6] "
      "--set device.cameras.fx_px=[256.7,257.1,256.3,256.9] --set device.cameras.fy_px=[256.7,257.1,256.3,256.9] "
      "--set checkerboard.square_mm=45 --set checkerboard.views=12 --set schedule.step_deg=60 --set schedule.stop_deg=300";
  ok(fmt::format("simulate {} -o {} --layers all {}", rig("wang2016-calibration.yaml"), at("cal"), third));
  if (!four_camera_geometry_available()) {
    const Result r = polrig(fmt::format("calibrate {} --method four-camera -o {}", at("cal"), at("out")));
    EXPECT_NE(r.status, 0);
    EXPECT_HAS(r.err, "-DPOLRIG_OPENCV=ON");
    EXPECT_HAS(r.err, "--geometry");
    EXPECT_FALSE(fs::exists(tmp / "out"));
    GTEST_SKIP() << "polrig built without OpenCV (-DPOLRIG_OPENCV=OFF): the refusal checked, not the fit";
  }
  for (const auto& [out, terms] : {std::pair{"out4", 4}, std::pair{"out2", 2}}) {
    const Result c = ok(fmt::format("calibrate {} --method four-camera -o {} --distortion-terms {} --no-plots",
                                    at("cal"), at(out), terms));
    EXPECT_HAS(c.out, "the geometric calibration of its 12 checkerboard views");
    EXPECT_HAS(c.out, "cameras 1-4: converged");
    EXPECT_HAS(test::read_file(tmp / out / "manifest.yaml"), "geometry.csv");
    const FourCameraCalibrationFile cal = read_four_camera_calibration(tmp / out / "calibration.yaml");
    EXPECT_HAS(cal.geometry_from, "checkerboard");
    const test::Csv g = test::read_csv(tmp / out / "geometry.csv");
    ASSERT_EQ(g.rows.size(), 4u);
    for (std::size_t j = 0; j < 4; ++j) {
      const CameraGeometry& c = cal.model.camera[j];
      const auto v = [&](const char* col) { return std::stod(g.rows[j][g.col(col)]); };
      EXPECT_EQ(c.fx, v("fx_px")) << j;  // both written as shortest round trips of the same double
      EXPECT_EQ(c.cy, v("cy_px")) << j;
      EXPECT_EQ(c.k[0], v("k1")) << j;
      if (terms == 2) {
        EXPECT_EQ(v("k3"), 0.0) << j;
      }
    }
  }
  // Measured views (no truth.yaml, no board poses): the same geometric fit, the same calibration.
  make_measured(tmp / "cal", tmp / "measured", true);
  ok(fmt::format("calibrate {} --method four-camera -o {} --no-plots", at("measured"), at("mout")));
  const test::Csv sim = test::read_csv(tmp / "out4" / "geometry.csv");
  const test::Csv measured = test::read_csv(tmp / "mout" / "geometry.csv");
  ASSERT_EQ(measured.rows.size(), 4u);
  for (const char* col : {"fx_px", "fy_px", "cx_px", "cy_px", "k1", "k4", "rot_z_deg", "position_x_mm", "rms_px"})
    for (std::size_t j = 0; j < 4; ++j) EXPECT_EQ(measured.rows[j][measured.col(col)], sim.rows[j][sim.col(col)]) << col;
  EXPECT_EQ(test::read_file(tmp / "mout" / "polarizer.csv"), test::read_file(tmp / "out4" / "polarizer.csv"));
}

// A fisheye fit that converges to no lens (|k_i| > 10, too few or too alike views: 6 views at a
// quarter of W16's resolution give k4 = 11.2) is a calibration that cannot be done (exit 3, the
// fit's report), never a calibration.yaml that polrig's own reader refuses.
class SlowFourCameraCalibrationCli : public FourCameraCalibrationCli {};  // CTest label "slow"

TEST_F(SlowFourCameraCalibrationCli, AFitThatIsNoLensCannotCalibrate) {
  if (!four_camera_geometry_available()) GTEST_SKIP() << "polrig built without OpenCV";
  const std::string quarter =
      "--set device.cameras.width_px=258 --set device.cameras.height_px=194 "
      "--set device.cameras.fx_px=[192.5,192.8,192.225,192.65] --set device.cameras.fy_px=[192.5,192.8,192.225,192.65] "
      "--set device.cameras.cx_px=[129,129.6,128.925,129.475] --set device.cameras.cy_px=[97,96.95,97.575,97.15] "
      "--set checkerboard.views=6";
  ok(fmt::format("simulate {} -o {} --layers all --no-plots {}", rig("wang2016-calibration.yaml"), at("cal"), quarter));
  const Result r = polrig(fmt::format("calibrate {} --method four-camera -o {} --no-plots", at("cal"), at("out")));
  EXPECT_EQ(r.status, 3) << r.err;
  EXPECT_HAS(r.err, "the geometric calibration is not usable");
  EXPECT_HAS(r.err, "is no lens (|k| ≤ 10)");
  EXPECT_LACKS(r.err, "calibration.yaml");
  EXPECT_FALSE(fs::exists(tmp / "out"));
}
