// W16's four-camera sensor (spec sky-and-compasses.md §3.1–3.2, §3.6): the fusion's algebra, the
// fisheye lens, R_j1, the frames from the sky, co-registration and the fused image against the
// sky's own truth, the solar-meridian symmetry, the dataset and its reader, schedule.count.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "polrig/device/four_camera.h"
#include "polrig/io/four_camera_dataset.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/compass/orientation.h"
#include "polrig/report/four_camera_dataset.h"
#include "polrig/rig/error.h"
#include "polrig/rig/keys.h"
#include "polrig/sim/four_camera_frames.h"
#include "polrig/sky/sun.h"
#include "polrig/units.h"
#include "polrig/vector_log.h"
#include "support.h"

using namespace polrig;

namespace {

template <class F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const RigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected a RigError";
  return {};
}

// W16's static run's site and first stop (spec §3.5), a few stops; `extra` adds device.cameras keys.
std::string sky_rig_text(const std::string& cameras, double mount_deg = 0, int count = 2) {
  return fmt::format(
      "device:\n  kind: four-camera\n  cameras:\n{}"
      "source:\n  model: sky\n"
      "sky:\n  lat_deg: 28.221\n  lon_deg: 112.992\n  first_stop_utc: \"2015-12-16T06:37:00Z\"\n  p_max: 0.4\n"
      "  mount_deg: {}\n"
      "schedule:\n  start_deg: 0\n  step_deg: 0\n  count: {}\n  dwell_s: 1\n",
      cameras, mount_deg, count);
}

// A smaller camera with W16's field: the size and the focal length scaled by `s` (1: W16's).
std::string scaled(double s, bool misaligned, const std::string& more = "") {
  std::string t = fmt::format("    width_px: {}\n    height_px: {}\n    noise: false\n", static_cast<int>(1034 * s),
                              static_cast<int>(778 * s));
  const double f = 770 * s, cx = 0.5 * static_cast<int>(1034 * s), cy = 0.5 * static_cast<int>(778 * s);
  t += fmt::format("    fx_px: [{0}, {1}, {2}, {3}]\n    fy_px: [{0}, {1}, {2}, {3}]\n", f, f * 1.0015, f * 0.9986,
                   f * 1.0008);
  t += fmt::format("    cx_px: [{}, {}, {}, {}]\n    cy_px: [{}, {}, {}, {}]\n", cx, cx + 1.3 * s, cx - 1.1 * s, cx + 0.7 * s,
                   cy, cy - 0.9 * s, cy + 1.2 * s, cy - 0.4 * s);
  if (!misaligned) t += "    rot_x_deg: [0, 0, 0, 0]\n    rot_y_deg: [0, 0, 0, 0]\n    rot_z_deg: [0, 0, 0, 0]\n";
  return t + more;
}

double axial_diff(double a, double b) {
  double d = std::fmod(a - b, 180.0);
  if (d > 90) d -= 180;
  if (d < -90) d += 180;
  return d;
}

}  // namespace

// ---- Eqs. 3–5 -------------------------------------------------------------------------

TEST(FourCameraFusion, W16AxesGiveTheClosedForm) {
  // Spec §3.2: for (0, 45, 90, 135)°, x1 = (F1 − F3)/2, x2 = (F2 − F4)/2, x3 = ΣF/4.
  const std::array<double, 12> W = fusion_matrix({0, 45, 90, 135});
  const std::array<double, 12> closed = {0.5, 0, -0.5, 0, 0, 0.5, 0, -0.5, 0.25, 0.25, 0.25, 0.25};
  for (std::size_t i = 0; i < 12; ++i) EXPECT_NEAR(W[i], closed[i], 1e-15) << i;
}

TEST(FourCameraFusion, AnyThreeDistinctAxesInvertEq2) {
  // Eq. 2 forward (F_j = I·d·cos 2φ·cos 2φ_j + I·d·sin 2φ·sin 2φ_j + I), then Eq. 4 back.
  std::mt19937_64 g(7);
  std::uniform_real_distribution<double> u(0, 1);
  for (int trial = 0; trial < 200; ++trial) {
    PerCamera axes{};
    for (double& a : axes) a = 180 * u(g);
    const double I = 0.1 + u(g), d = u(g), phi = std::numbers::pi * u(g);
    std::array<double, 4> F{};
    for (std::size_t j = 0; j < 4; ++j) {
      const double a = 2 * deg2rad(axes[j]);
      F[j] = I * d * std::cos(2 * phi) * std::cos(a) + I * d * std::sin(2 * phi) * std::sin(a) + I;
    }
    std::array<double, 12> W;
    try {
      W = fusion_matrix(axes);
    } catch (const std::invalid_argument&) {
      continue;  // nearly coincident axes
    }
    const FusedStokes x = fuse_pixel(W, F);
    const double scale = 1.0;
    EXPECT_NEAR(x.S1, I * d * std::cos(2 * phi), 1e-9 * scale);
    EXPECT_NEAR(x.S2, I * d * std::sin(2 * phi), 1e-9 * scale);
    EXPECT_NEAR(x.S0, I, 1e-9 * scale);
  }
  EXPECT_THROW(fusion_matrix({0, 0, 90, 90}), std::invalid_argument);  // two axes: D has rank 2
}

// ---- The lens and R_j1 ------------------------------------------------------------------

TEST(FourCameraLens, EquidistantAndItsInverse) {
  CameraGeometry c;  // f = 770 px, k = 0
  // r = f·θ exactly: a ray 30° off the axis along +x lands 770·π/6 px right of c_x.
  const double t = deg2rad(30.0);
  const auto uv = project(c, {std::sin(t), 0.0, std::cos(t)});
  EXPECT_NEAR(uv[0] - c.cx, 770.0 * std::numbers::pi / 6.0, 1e-9);
  EXPECT_NEAR(uv[1], c.cy, 1e-12);
  // W16's field (spec §3.1: 77° × 57.7°): with f = 770 px the equidistant lens gives 2·517/770 rad
  // and 2·389/770 rad.
  FourCameraSpec spec;
  const FourCameraModel m = four_camera_truth(spec);
  EXPECT_NEAR(four_camera_fov_x_deg(m, 0), rad2deg(2 * 517.0 / 770.0), 1e-9);  // 76.93°
  EXPECT_NEAR(four_camera_fov_y_deg(m, 0), rad2deg(2 * 389.0 / 770.0), 1e-9);  // 57.89°
  // Round trips with a distorted lens, over the field.
  c.k = {-0.02, 0.004, -0.001, 0.0002};
  for (double u = 5; u < 1034; u += 97)
    for (double v = 3; v < 778; v += 71) {
      const Vec3 ray = unproject(c, u, v);
      EXPECT_NEAR(vec3::norm(ray), 1.0, 1e-14);
      const auto back = project(c, ray);
      EXPECT_NEAR(back[0], u, 1e-9);
      EXPECT_NEAR(back[1], v, 1e-9);
    }
}

TEST(FourCameraLens, RodriguesAgreesWithAnAxisRotation) {
  // A rotation vector along z of angle a is Rz(a): [cos −sin; sin cos].
  const double a = deg2rad(0.7);
  const auto R = rotation_from_vector({0, 0, a});
  EXPECT_NEAR(R[0], std::cos(a), 1e-16);
  EXPECT_NEAR(R[1], -std::sin(a), 1e-16);
  EXPECT_NEAR(R[3], std::sin(a), 1e-16);
  EXPECT_NEAR(R[8], 1.0, 1e-16);
  // Orthonormal for a general vector.
  const auto Q = rotation_from_vector({0.01, -0.02, 0.03});
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      double s = 0;
      for (int k = 0; k < 3; ++k) s += Q[static_cast<std::size_t>(i * 3 + k)] * Q[static_cast<std::size_t>(j * 3 + k)];
      EXPECT_NEAR(s, i == j ? 1.0 : 0.0, 1e-15);
    }
}

TEST(FourCameraLens, AFoldingLensOrARotatedCameraOneIsRefused) {
  FourCameraSpec spec;
  spec.k1 = {-0.5, 0, 0, 0};
  EXPECT_THROW(four_camera_truth(spec), std::invalid_argument);
  FourCameraSpec rotated;
  rotated.rot_z_deg[0] = 0.1;
  EXPECT_THROW(four_camera_truth(rotated), std::invalid_argument);
  EXPECT_HAS(error_of([&] { parse_rig(sky_rig_text("    rot_z_deg: [0.1, 0, 0, 0]\n"), "r.yaml"); }),
             "device.cameras.rot_z_deg");
}

// ---- Frames and fusion against the sky ---------------------------------------------------

namespace {
// Largest AoP and DoP error of the noise-free fused image (double) against the sky along the
// virtual camera 1's views, over the valid pixels at least `margin` px from the edge.
struct Errors {
  double aop = 0, dop = 0;
  long valid = 0;
};
Errors fused_errors(const Rig& rig) {
  const FourCameraSimulator sim(rig);
  const DofpStop& stop = sim.stops().front();
  const FourCameraSignal signal = sim.signal(stop);
  const FourCameraTruthLayers truth = sim.truth_on_grid(stop);
  const std::array<std::span<const double>, 4> f = {signal.f[0], signal.f[1], signal.f[2], signal.f[3]};
  Errors e;
  for (std::size_t i = 0; i < truth.S0.size(); ++i) {
    FusedStokes x;
    if (!sim.fusion().fuse_at(f, i, x)) continue;
    ++e.valid;
    double aop = rad2deg(0.5 * std::atan2(x.S2, x.S1));
    e.aop = std::max(e.aop, std::abs(axial_diff(aop, truth.AoP[i])));
    e.dop = std::max(e.dop, std::abs(std::hypot(x.S1, x.S2) / x.S0 - truth.DoP[i]));
  }
  return e;
}
}  // namespace

TEST(FourCameraFrames, TheFusedImageIsTheSkyUpToBilinearInterpolation) {
  // Noise-free, misaligned cameras with their own intrinsics: Eqs. 3–5 (with each camera's frame
  // offset δ_j) are exact, so what is left is the bilinear resampling's error, O(h²·g'') for a
  // pixel h: halving the pixel (doubling the size and f over the same field) divides it by about
  // four (measured: AoP 5.4e-4° → 2.0e-4°, DoP 5.5e-6 → 1.4e-6; aligned cameras 6.9e-4° → 1.4e-4°).
  // Without δ_j (W16's common axes) the misaligned error stays at 0.05° whatever the pixel.
  const Rig quarter = parse_rig(sky_rig_text(scaled(0.25, true)), "q").rig;
  const Rig half = parse_rig(sky_rig_text(scaled(0.5, true)), "h").rig;
  const Errors q = fused_errors(quarter), h = fused_errors(half);
  std::printf("fused against the sky: quarter AoP %.3g deg DoP %.3g; half AoP %.3g deg DoP %.3g\n", q.aop, q.dop,
              h.aop, h.dop);
  EXPECT_GT(q.valid, 0.95 * 258 * 194);
  EXPECT_LT(q.aop, 1e-3);
  EXPECT_LT(q.dop, 1e-5);
  EXPECT_LT(h.aop, q.aop / 2.0) << q.aop << " " << h.aop;
  EXPECT_LT(h.dop, q.dop / 3.0) << q.dop << " " << h.dop;
}

TEST(FourCameraFrames, OnAPixelGridTheFusedImageIsTheSkyTo1e9) {
  // Identical aligned cameras with f so long that the equidistant lens is a pinhole over the image
  // (f·θ³/3 ≈ 8e-7 px at the edge): every virtual pixel lands on a pixel centre of every camera, no
  // interpolation is left, and the fused AoP, DoP and S0 equal the sky's along camera 1's views.
  const std::string cams =
      "    width_px: 20\n    height_px: 16\n    noise: false\n"
      "    fx_px: [2e4, 2e4, 2e4, 2e4]\n    fy_px: [2e4, 2e4, 2e4, 2e4]\n"
      "    cx_px: [10, 10, 10, 10]\n    cy_px: [8, 8, 8, 8]\n"
      "    rot_x_deg: [0, 0, 0, 0]\n    rot_y_deg: [0, 0, 0, 0]\n    rot_z_deg: [0, 0, 0, 0]\n";
  const Rig rig = parse_rig(sky_rig_text(cams), "tiny").rig;
  const FourCameraSimulator sim(rig);
  const DofpStop& stop = sim.stops().front();
  const FourCameraSignal signal = sim.signal(stop);
  const FourCameraTruthLayers truth = sim.truth_on_grid(stop);
  const std::array<std::span<const double>, 4> f = {signal.f[0], signal.f[1], signal.f[2], signal.f[3]};
  int n = 0;
  for (std::size_t i = 0; i < truth.S0.size(); ++i) {
    FusedStokes x;
    if (!sim.fusion().fuse_at(f, i, x)) continue;
    ++n;
    EXPECT_NEAR(axial_diff(rad2deg(0.5 * std::atan2(x.S2, x.S1)), truth.AoP[i]), 0.0, 1e-9);
    EXPECT_NEAR(std::hypot(x.S1, x.S2) / x.S0, truth.DoP[i], 1e-9);
    EXPECT_NEAR(x.S0, truth.S0[i], 1e-9);
  }
  EXPECT_EQ(n, 20 * 16);
}

TEST(FourCameraFrames, TheFusedAopGivesTheSunByTheEigenvectorMethod) {
  // Independent route: compass/orientation.h's eigenvector method (W16 Eqs. 6–14) on the fused AoP of
  // the virtual camera 1 recovers the ephemeris' sun in camera 1's frame (the contract with the
  // locate glue), within the resampling's error.
  const Rig rig = parse_rig(sky_rig_text(scaled(0.25, true), 35.0), "q").rig;
  const FourCameraSimulator sim(rig);
  const DofpStop& stop = sim.stops().front();
  const FusedImage fused = sim.fuse(sim.signal(stop));
  std::vector<double> aop(fused.AoP.size());
  for (std::size_t i = 0; i < aop.size(); ++i)
    aop[i] = fused.valid[i] ? static_cast<double>(fused.AoP[i]) : std::numeric_limits<double>::quiet_NaN();
  const SkyPoints points = grid_points(fused.grid.width, fused.grid.height, 1.0, aop);
  const SunVectorSolution s = sun_vector_eigen(points, {fused.grid.f_c, fused.grid.cx, fused.grid.cy});
  ASSERT_TRUE(has_sun(s.status));
  const Vec3 truth = *sim.sun_in_camera1(stop);
  const double miss = rad2deg(std::acos(std::min(1.0, vec3::dot(s.sun, truth))));
  std::printf("eigenvector sun from the fused AoP (quarter resolution, misaligned): %.3g deg off\n", miss);
  EXPECT_LT(miss, 1e-3) << miss;
}

TEST(FourCameraFrames, NoInterpolationLeftTheFusedImageGivesTheSunTo1e9) {
  // The noise-free sun vector to 1e-9°, through the whole four-camera path: identical
  // aligned cameras whose Kannala–Brandt k's are tan θ's series (θ + θ³/3 + 2θ⁵/15 + 17θ⁷/315 +
  // 62θ⁹/2835), so each camera's lens is the virtual camera 1's pinhole to 1382/155925·θ¹¹·f ≈ 2e-10
  // px at the corner (θ = 0.124 rad, f = 200 px): every virtual pixel samples a pixel centre (the
  // bilinear weights are exactly 0 and 1) and no resampling error is left, unlike the test above.
  // A 14° × 11° field is enough for the eigenvector method (W16 Eqs. 6–14) on exact data. The
  // double-precision fusion (fuse_at) feeds it; the truth is the ephemeris' sun in camera 1's frame.
  const std::string cams =
      "    width_px: 40\n    height_px: 30\n    noise: false\n"
      "    fx_px: [200, 200, 200, 200]\n    fy_px: [200, 200, 200, 200]\n"
      "    cx_px: [20, 20, 20, 20]\n    cy_px: [15, 15, 15, 15]\n"
      "    k1: [0.3333333333333333, 0.3333333333333333, 0.3333333333333333, 0.3333333333333333]\n"
      "    k2: [0.13333333333333333, 0.13333333333333333, 0.13333333333333333, 0.13333333333333333]\n"
      "    k3: [0.05396825396825397, 0.05396825396825397, 0.05396825396825397, 0.05396825396825397]\n"
      "    k4: [0.021869488536155203, 0.021869488536155203, 0.021869488536155203, 0.021869488536155203]\n"
      "    rot_x_deg: [0, 0, 0, 0]\n    rot_y_deg: [0, 0, 0, 0]\n    rot_z_deg: [0, 0, 0, 0]\n";
  for (const double mount_deg : {35.0, 200.0}) {
    const Rig rig = parse_rig(sky_rig_text(cams, mount_deg), "pinhole-like").rig;
    const FourCameraSimulator sim(rig);
    const DofpStop& stop = sim.stops().front();
    const FourCameraSignal signal = sim.signal(stop);
    const std::array<std::span<const double>, 4> f = {signal.f[0], signal.f[1], signal.f[2], signal.f[3]};
    const VirtualCamera& grid = sim.fusion().grid();
    std::vector<double> aop(static_cast<std::size_t>(grid.width) * static_cast<std::size_t>(grid.height));
    for (std::size_t i = 0; i < aop.size(); ++i) {
      FusedStokes x;
      ASSERT_TRUE(sim.fusion().fuse_at(f, i, x)) << i;
      aop[i] = rad2deg(0.5 * std::atan2(x.S2, x.S1));
    }
    const SunVectorSolution s = sun_vector_eigen(grid_points(grid.width, grid.height, 1.0, aop),
                                                 {grid.f_c, grid.cx, grid.cy});
    ASSERT_TRUE(has_sun(s.status));
    const Vec3 truth = *sim.sun_in_camera1(stop);
    // atan2(|a × b|, a·b): acos near 1 resolves no better than 1e-6°.
    const double miss = rad2deg(std::atan2(vec3::norm(vec3::cross(s.sun, truth)), vec3::dot(s.sun, truth)));
    std::printf("eigenvector sun, no interpolation left, camera 1's X at %g deg: %.3g deg off\n", mount_deg, miss);
    EXPECT_LT(miss, 1e-9) << mount_deg;
  }
}

TEST(FourCameraFrames, HeadingSignTestOfSpec0) {
  // Spec §0: turn the device +10° anticlockwise seen from above (camera 1's X from azimuth 35° to
  // 25°: sky.mount_deg is X's geographic azimuth, clockwise): the heading from the fused image
  // (eigenvector sun, H = A_s + α_S, compass/orientation's camera_heading_deg) falls by 10°, and each
  // equals the true heading of stops.csv (dofp_true_heading_deg: X's azimuth).
  std::array<double, 2> heading{};
  for (int k = 0; k < 2; ++k) {
    const Rig rig = parse_rig(sky_rig_text(scaled(0.25, true), k == 0 ? 35.0 : 25.0), "h").rig;
    const FourCameraSimulator sim(rig);
    const DofpStop& stop = sim.stops().front();
    const FusedImage fused = sim.fuse(sim.signal(stop));
    std::vector<double> aop(fused.AoP.size());
    for (std::size_t i = 0; i < aop.size(); ++i)
      aop[i] = fused.valid[i] ? static_cast<double>(fused.AoP[i]) : std::numeric_limits<double>::quiet_NaN();
    const SunVectorSolution s = sun_vector_eigen(grid_points(fused.grid.width, fused.grid.height, 1.0, aop),
                                                 {fused.grid.f_c, fused.grid.cx, fused.grid.cy});
    ASSERT_TRUE(has_sun(s.status));
    const Sky sky = rig.source.sky.resolved_sky();
    heading[static_cast<std::size_t>(k)] =
        camera_heading_deg(sun_position(sky.first_stop, sky.site, sky.sun).azimuth_deg, s.sun_az_deg);
    double miss = heading[static_cast<std::size_t>(k)] - *dofp_true_heading_deg(rig, stop);
    miss -= 360.0 * std::round(miss / 360.0);
    EXPECT_NEAR(miss, 0.0, 1e-3);
  }
  double d = heading[1] - heading[0];
  d -= 360.0 * std::round(d / 360.0);
  EXPECT_NEAR(d, -10.0, 1e-3);
}

TEST(FourCameraFrames, AopAntisymmetricAndDopSymmetricAboutTheSolarMeridian) {
  // Spec §3.6 item 7 [SIM]: camera 1's X turned to the sun's azimuth (sky.mount_deg = A_s), the
  // solar meridian is the image's row axis through c_y; identical aligned cameras symmetric about
  // it. Pixel rows r and H − 1 − r mirror: DoP equal, AoP(r) = −AoP(H − 1 − r) mod 180°.
  const Sky sky = parse_rig(sky_rig_text(scaled(0.25, false)), "a").rig.source.sky.resolved_sky();
  const double A = sun_position(sky.first_stop, sky.site, sky.sun).azimuth_deg;
  const std::string same = fmt::format(
      "    width_px: 258\n    height_px: 194\n    noise: false\n    fx_px: [192.5, 192.5, 192.5, 192.5]\n"
      "    fy_px: [192.5, 192.5, 192.5, 192.5]\n    cx_px: [129, 129, 129, 129]\n    cy_px: [97, 97, 97, 97]\n"
      "    rot_x_deg: [0, 0, 0, 0]\n    rot_y_deg: [0, 0, 0, 0]\n    rot_z_deg: [0, 0, 0, 0]\n");
  const Rig rig = parse_rig(sky_rig_text(same, A), "m").rig;
  const FourCameraSimulator sim(rig);
  const FourCameraSignal signal = sim.signal(sim.stops().front());
  const std::array<std::span<const double>, 4> f = {signal.f[0], signal.f[1], signal.f[2], signal.f[3]};
  const int W = 258, H = 194;
  double worst_aop = 0, worst_dop = 0, asym = 0;
  for (int r = 0; r < H / 2; ++r)
    for (int c = 0; c < W; ++c) {
      FusedStokes a, b;
      const auto i = static_cast<std::size_t>(r * W + c), k = static_cast<std::size_t>((H - 1 - r) * W + c);
      if (!sim.fusion().fuse_at(f, i, a) || !sim.fusion().fuse_at(f, k, b)) continue;
      const double aop_a = rad2deg(0.5 * std::atan2(a.S2, a.S1)), aop_b = rad2deg(0.5 * std::atan2(b.S2, b.S1));
      worst_aop = std::max(worst_aop, std::abs(axial_diff(aop_a, -aop_b)));
      worst_dop = std::max(worst_dop, std::abs(std::hypot(a.S1, a.S2) / a.S0 - std::hypot(b.S1, b.S2) / b.S0));
      asym = std::max(asym, std::abs(axial_diff(aop_a, aop_b)));  // the AoP itself is not symmetric
    }
  // Mirrored samples have mirrored weights up to their float rounding (2⁻²⁴ of a pixel-to-pixel
  // difference, ~1e-2 relative here): ~1e-9 rad.
  EXPECT_LT(worst_aop, 1e-7);
  EXPECT_LT(worst_dop, 1e-9);
  EXPECT_GT(asym, 10.0);
}

TEST(FourCameraFrames, RawFramesFollowEq1AndTheNoiseIsDeterministic) {
  // A uniform unpolarized port (cos4, the polarizer out: an unpolarized level): every camera reads
  // K_j·E_0 + b_j.
  const std::string text =
      "device:\n  kind: four-camera\n  cameras:\n    width_px: 40\n    height_px: 30\n    noise: false\n"
      "    fx_px: [30, 30, 30, 30]\n    fy_px: [30, 30, 30, 30]\n    cx_px: [20, 20, 20, 20]\n    cy_px: [15, 15, 15, 15]\n"
      "source:\n  model: cos4\n  E_0: 1.5\nschedule:\n  angles_deg: [0]\n  unpolarized_levels: [1]\n";
  Rig rig = parse_rig(text, "u").rig;
  {
    const FourCameraSimulator sim(rig);
    const FourCameraSignal s = sim.signal(sim.stops().front());
    for (std::size_t j = 0; j < 4; ++j)
      for (double v : s.f[j]) EXPECT_NEAR(v, rig.four_camera.gain_DN[j] * 1.5 + rig.four_camera.offset_DN[j], 1e-9);
  }
  rig.four_camera.noise = true;
  const FourCameraSimulator a(rig);
  const auto fa = a.frames(a.signal(a.stops().front()));
  std::vector<std::uint16_t> fb;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    const FourCameraSimulator b(rig);
    fb = b.frames(b.signal(b.stops().front()))[2];
  }
  EXPECT_EQ(fa[2], fb);
  EXPECT_NE(fa[0], fa[1]);  // each camera its own stream
}

TEST(FourCameraFrames, APolarizedPortFollowsMalusOnTheAxis) {
  // The sphere rig's polarized port (cos4, device.d, the port polarizer at ψ_P = source.polarizer_deg):
  // on the optical axis it is seen at θ_R − ψ_P from X towards Y (docs/physics.md §1, §13), so the
  // axial pixel of each aligned camera reads Eq. 1 written out by hand:
  // K_j·E_0·[1 + d·cos(2(θ_R − ψ_P) − 2(φ_j + ε_j))] + b_j.
  const std::string text =
      "device:\n  kind: four-camera\n  d: 0.8\n  cameras:\n    width_px: 41\n    height_px: 31\n    noise: false\n"
      "    fx_px: [30, 30, 30, 30]\n    fy_px: [30, 30, 30, 30]\n    cx_px: [20.5, 20.5, 20.5, 20.5]\n"
      "    cy_px: [15.5, 15.5, 15.5, 15.5]\n"
      "    rot_x_deg: [0, 0, 0, 0]\n    rot_y_deg: [0, 0, 0, 0]\n    rot_z_deg: [0, 0, 0, 0]\n"
      "source:\n  model: cos4\n  E_0: 1.5\n  polarizer_deg: 12\nschedule:\n  angles_deg: [0, 70]\n";
  const Rig rig = parse_rig(text, "p").rig;
  const FourCameraSimulator sim(rig);
  const std::size_t axial = 15 * 41 + 20;
  for (const DofpStop& stop : sim.stops()) {
    const FourCameraSignal s = sim.signal(stop);
    for (std::size_t j = 0; j < 4; ++j) {
      const FourCameraSpec& c = rig.four_camera;
      const double a = deg2rad(2 * (stop.theta_R_deg - 12.0) - 2 * (c.polarizer_deg[j] + c.eps_deg[j]));
      EXPECT_NEAR(s.f[j][axial], c.gain_DN[j] * 1.5 * (1 + 0.8 * std::cos(a)) + c.offset_DN[j], 1e-9)
          << stop.theta_R_deg << " " << j;
    }
  }
}

// ---- fuse(): float SIMD lanes against fuse_at's double precision ---------------------------

namespace {
// Half W16's resolution (517 × 389: not a whole number of fuse()'s 64-pixel chunks), misaligned
// cameras with their own intrinsics, noise on.
Rig half_noisy_rig() {
  std::string cams = scaled(0.5, true);
  cams.replace(cams.find("noise: false"), 12, "noise: true");
  return parse_rig(sky_rig_text(cams, 35.0), "half").rig;
}

bool same_layers(const FusedImage& a, const FusedImage& b) {
  return a.S0 == b.S0 && a.S1 == b.S1 && a.S2 == b.S2 && a.AoP == b.AoP && a.DoP == b.DoP && a.valid == b.valid;
}

// The largest error of fuse()'s layers against fuse_at (double) over the pixels both call valid,
// each over its bound from float rounding (docs/physics.md §16 "Fusion"): with u = 2⁻²⁴ and m the
// largest |F_j| any tap can give (its DN plus the offset, over K_j), the float bilinear sum and
// F_j = (f − b)·(1/K_j) are within 14·u·m, the differences F_j − F_4 within 30·u·m, W's entries
// rounded to float within u·|W_rj|, three products and two sums: |ΔS_r| ≤ 40·u·m·(1 + Σ_j |W_rj|)
// (W from fusion_matrix at the pixel's axes a_j + δ_j, an independent route to the same matrix).
// AoP: (|ΔS1| + |ΔS2|)/(2·√(S1² + S2²)) plus the float atan2's own error (Highway's arctangent
// polynomial within 4 ulp, the octant's and the degrees' roundings: ≤ 16·u·180°). DoP:
// (|ΔS1| + |ΔS2| + d·|ΔS0|)/S0 + 6·u·d.
struct LaneErrors {
  double S = 0, aop = 0, dop = 0;  // worst error / bound
  double S_abs = 0, aop_deg = 0, dop_abs = 0;
  long compared = 0, disagree = 0;
};
template <class T>
LaneErrors lane_errors(const FourCameraSimulator& sim, const std::array<std::span<const T>, 4>& f, const FusedImage& fast,
                       double m) {
  const double u = std::ldexp(1.0, -24);
  const FourCameraFusion& fusion = sim.fusion();
  LaneErrors e;
  for (std::size_t i = 0; i < fast.S0.size(); ++i) {
    FusedStokes x;
    const bool seen = fusion.fuse_at(f, i, x);
    PerCamera axes = sim.truth().axis_deg;
    for (int j = 0; j < 4; ++j) axes[static_cast<std::size_t>(j)] += fusion.frame_offset_deg(j, i);
    const std::array<double, 12> W = fusion_matrix(axes);
    std::array<double, 3> dS{};
    for (std::size_t r = 0; r < 3; ++r)
      dS[r] = 40 * u * m * (1 + std::abs(W[4 * r]) + std::abs(W[4 * r + 1]) + std::abs(W[4 * r + 2]) + std::abs(W[4 * r + 3]));
    const bool ref_valid = seen && x.S0 > 0;
    if (ref_valid != (fast.valid[i] == 1)) {
      // Only where S0 is within its rounding of 0.
      if (!seen || std::abs(x.S0) > dS[2]) ++e.disagree;
      continue;
    }
    if (!ref_valid) continue;
    ++e.compared;
    const double d1 = std::abs(fast.S1[i] - x.S1), d2 = std::abs(fast.S2[i] - x.S2), d0 = std::abs(fast.S0[i] - x.S0);
    e.S = std::max({e.S, d1 / dS[0], d2 / dS[1], d0 / dS[2]});
    e.S_abs = std::max({e.S_abs, d1, d2, d0});
    const double rho = std::hypot(x.S1, x.S2), d = rho / x.S0;
    const double aop = rad2deg(0.5 * std::atan2(x.S2, x.S1));
    const double aop_err = std::abs(axial_diff(fast.AoP[i], aop < 0 ? aop + 180 : aop));
    const double aop_bound = rad2deg((dS[0] + dS[1]) / (2 * rho)) + 16 * u * 180;
    e.aop = std::max(e.aop, aop_err / aop_bound);
    e.aop_deg = std::max(e.aop_deg, aop_err);
    const double dop_err = std::abs(fast.DoP[i] - d);
    e.dop = std::max(e.dop, dop_err / ((dS[0] + dS[1] + d * dS[2]) / x.S0 + 6 * u * d));
    e.dop_abs = std::max(e.dop_abs, dop_err);
    EXPECT_GE(fast.AoP[i], 0.0f);
    EXPECT_LT(fast.AoP[i], 180.0f);
  }
  return e;
}
}  // namespace

TEST(FourCameraFusion, FusedLayersAreFuseAtsDoubleWithinFloatRounding) {
  const FourCameraSimulator sim(half_noisy_rig());
  const FourCameraSignal signal = sim.signal(sim.stops().front());
  const auto raw = sim.frames(signal);
  const FourCameraModel& t = sim.truth();
  // m: the largest |F| a tap can give, (max f + |b|)/K (the float path subtracts b from the sample).
  double m_raw = 0, m_signal = 0;
  for (std::size_t j = 0; j < 4; ++j) {
    const double top_raw = *std::max_element(raw[j].begin(), raw[j].end());
    const double top_signal = *std::max_element(signal.f[j].begin(), signal.f[j].end());
    m_raw = std::max(m_raw, (top_raw + std::abs(t.b[j])) / t.K[j]);
    m_signal = std::max(m_signal, (top_signal + std::abs(t.b[j])) / t.K[j]);
  }
  const LaneErrors r = lane_errors<std::uint16_t>(sim, {raw[0], raw[1], raw[2], raw[3]}, sim.fuse(raw), m_raw);
  const LaneErrors s =
      lane_errors<double>(sim, {signal.f[0], signal.f[1], signal.f[2], signal.f[3]}, sim.fuse(signal), m_signal);
  std::printf("fuse() against fuse_at: raw worst |dS| %.3g (%.2f of its bound), AoP %.3g deg (%.2f), DoP %.3g (%.2f); "
              "signal |dS| %.3g (%.2f), AoP %.3g deg (%.2f), DoP %.3g (%.2f); m %.3g\n",
              r.S_abs, r.S, r.aop_deg, r.aop, r.dop_abs, r.dop, s.S_abs, s.S, s.aop_deg, s.aop, s.dop_abs, s.dop, m_raw);
  for (const LaneErrors& e : {r, s}) {
    EXPECT_GT(e.compared, 0.95 * 517 * 389);
    EXPECT_EQ(e.disagree, 0);
    EXPECT_LE(e.S, 1.0);
    EXPECT_LE(e.aop, 1.0);
    EXPECT_LE(e.dop, 1.0);
  }
}

TEST(FourCameraFusion, FusedLayersAreTheSameBitsForAnyThreadCountAndCodePath) {
  const FourCameraSimulator sim(half_noisy_rig());
  const FourCameraSignal signal = sim.signal(sim.stops().front());
  const auto raw = sim.frames(signal);
  const FusedImage a = sim.fuse(raw), as = sim.fuse(signal);
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    EXPECT_TRUE(same_layers(a, sim.fuse(raw)));
    EXPECT_TRUE(same_layers(as, sim.fuse(signal)));
  }
  if (!avx2_paths()) GTEST_SKIP() << "this CPU has no AVX2: only the baseline path exists";
  set_baseline_paths_only(true);
  const FusedImage b = sim.fuse(raw), bs = sim.fuse(signal);
  set_baseline_paths_only(false);
  EXPECT_TRUE(same_layers(a, b));
  EXPECT_TRUE(same_layers(as, bs));
}

// ---- The schedule and the keys ------------------------------------------------------------

TEST(FourCameraSchedule, CountGivesAStaticTimeSeries) {
  const Rig rig = parse_rig(sky_rig_text(scaled(0.125, false), 0, 3601), "s").rig;
  const std::vector<double> angles = rig.schedule.table_angles_deg();
  ASSERT_EQ(angles.size(), 3601u);
  EXPECT_EQ(angles.back(), 0.0);
  const std::vector<double> t = rig.schedule.stop_times_s();
  EXPECT_EQ(t.back(), 3600.0);
  EXPECT_HAS(error_of([&] { parse_rig("schedule: {step_deg: 0}\n", "z.yaml"); }), "schedule.step_deg");
  // rig_to_yaml round trip: count written, stop_deg not.
  const std::string yaml = rig_to_yaml(rig);
  EXPECT_HAS(yaml, "count: 3601");
  EXPECT_LACKS(yaml, "stop_deg");
  EXPECT_EQ(rig_to_yaml(parse_rig(yaml, "back").rig), yaml);
  EXPECT_LACKS(rig_to_yaml(Rig{}), "count");
}

TEST(FourCameraSchedule, TheCamerasKeysRoundTripAndBelongToTheFourCamera) {
  const Rig rig = parse_rig(sky_rig_text(scaled(0.5, true, "    k1: [0.01, -0.01, 0.02, 0]\n")), "k").rig;
  EXPECT_EQ(rig.four_camera.k1[2], 0.02);
  const std::string yaml = rig_to_yaml(rig);
  EXPECT_HAS(yaml, "kind: four-camera");
  EXPECT_HAS(yaml, "cameras:");
  EXPECT_EQ(rig_to_yaml(parse_rig(yaml, "back").rig), yaml);
  EXPECT_HAS(error_of([&] { parse_rig("device:\n  cameras:\n    width_px: 100\n", "six.yaml"); }),
             "only device.kind four-camera reads it");
  EXPECT_HAS(error_of([&] { parse_rig(sky_rig_text("    k1: [2, 0, 0, 0]\n"), "k.yaml"); }), "device.cameras.k1");
}

// ---- The dataset --------------------------------------------------------------------------

TEST(FourCameraDataset, WrittenAndReadBack) {
  const polrig::test::TempDir tmp("polrig_test_four_camera_");
  const LoadedRig loaded = parse_rig(sky_rig_text(scaled(0.125, true), 0, 2), "d");
  write_four_camera_dataset(loaded, tmp.path() / "d", {FourCameraLayers::All}, "test", false);
  const FourCameraDataset d = read_four_camera_dataset(tmp.path() / "d");
  ASSERT_EQ(d.stops.size(), 2u);
  EXPECT_EQ(d.width, 129);
  ASSERT_TRUE(d.camera.has_value());
  EXPECT_EQ(d.camera->f_c_px, 770 * 0.125);
  EXPECT_EQ(d.stops[1].utc, "2015-12-16T06:37:01Z");
  ASSERT_TRUE(d.stops[0].sun_camera1.has_value());
  const FourCameraSimulator sim(loaded.rig);
  const Vec3 s = *sim.sun_in_camera1(sim.stops()[0]);
  for (std::size_t k = 0; k < 3; ++k) EXPECT_EQ((*d.stops[0].sun_camera1)[k], s[k]);
  // The raw frames bit for bit, the fused AoP as written (float), NaN where not valid.
  const auto raw = read_four_camera_raw(d, 1);
  const auto again = sim.frames(sim.signal(sim.stops()[1]));
  EXPECT_EQ(raw[3], again[3]);
  const FusedImage fused = sim.fuse(again);
  const FusedAopDop read = read_four_camera_fused(d, 1);
  for (std::size_t i = 0; i < read.aop_deg.size(); ++i) {
    if (fused.valid[i]) EXPECT_EQ(read.aop_deg[i], static_cast<double>(fused.AoP[i]));
    else EXPECT_TRUE(std::isnan(read.aop_deg[i]));
  }
  // Whole or not at all: an existing folder is not replaced.
  EXPECT_ANY_THROW(write_four_camera_dataset(loaded, tmp.path() / "d", {}, "test", false));
}

// ---- W16's rigs (spec §3.5–3.6) ---------------------------------------------------------------

TEST(FourCameraRigs, W16sStaticAndRotationRunsReproduceTheEphemerisAndTheDop) {
  const LoadedRig s = load_rig(std::string(POLRIG_SOURCE_DIR) + "/rigs/wang2016-static.yaml");
  const FourCameraSimulator sim(s.rig);
  ASSERT_EQ(sim.stops().size(), 3601u);
  const Sky sky = s.rig.source.sky.resolved_sky();
  const auto sun_at = [&](const Sky& k, double t) { return sun_position(k.first_stop.plus_seconds(t), k.site, k.sun); };
  // Spec §1.1 (independently checked ephemeris): A_s 200.87° at 13:37 and 215.42° at 14:37 (W16:
  // β = 201.0° → 215.5°); θ_s 60.75° at 14:37 (W16: ≈ 60.7°).
  EXPECT_NEAR(sun_at(sky, 0).azimuth_deg, 200.87, 0.006);
  EXPECT_NEAR(sun_at(sky, 3600).azimuth_deg, 215.42, 0.006);
  EXPECT_NEAR(90 - sun_at(sky, 3600).elevation_deg, 60.75, 0.006);
  EXPECT_EQ(sim.stops().back().t_s, 3600.0);
  // The largest DoP along the virtual camera 1's views ≈ 40% (W16 §4) at both ends of the hour.
  for (std::size_t k : {std::size_t{0}, std::size_t{3600}}) {
    const FourCameraTruthLayers t = sim.truth_on_grid(sim.stops()[k]);
    const double dmax = *std::max_element(t.DoP.begin(), t.DoP.end());
    EXPECT_GT(dmax, 0.39) << k;
    EXPECT_LE(dmax, 0.40) << k;
  }
  // The sun in camera 1's frame: camera 1's X south (mount 180°), so α_S measured clockwise from
  // above, −atan2(s_y, s_x), is β − 180° (W16: α_S 20.9° at β = 201.0°).
  const Vec3 s0 = *sim.sun_in_camera1(sim.stops()[0]);
  EXPECT_NEAR(-rad2deg(std::atan2(s0[1], s0[0])), sun_at(sky, 0).azimuth_deg - 180.0, 1e-9);

  const LoadedRig r = load_rig(std::string(POLRIG_SOURCE_DIR) + "/rigs/wang2016-rotation.yaml");
  const std::vector<double> angles = r.rig.schedule.table_angles_deg();
  ASSERT_EQ(angles.size(), 27u);
  EXPECT_NEAR(angles[1], 30 * 360.0 / 391.0, 1e-9);   // 27.6215°
  EXPECT_NEAR(angles[13], 390 * 360.0 / 391.0, 1e-9);  // 359.08°
  const std::vector<double> t = r.rig.schedule.stop_times_s();
  EXPECT_NEAR(t.back(), 180.0, 1e-3);  // 16:40 → 16:43
  const Sky rsky = r.rig.source.sky.resolved_sky();
  EXPECT_NEAR(90 - sun_at(rsky, 0).elevation_deg, 80.45, 0.006);  // W16: ≈ 80.4°
  const FourCameraSimulator rsim(r.rig);
  const FourCameraTruthLayers rt = rsim.truth_on_grid(rsim.stops()[0]);
  const double rmax = *std::max_element(rt.DoP.begin(), rt.DoP.end());
  EXPECT_GT(rmax, 0.58);  // W16: up to 60%
  EXPECT_LE(rmax, 0.60);
}
