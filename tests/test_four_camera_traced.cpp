// W16's four cameras under the traced sphere (source/traced_*: the light along each camera's
// views, docs/physics.md §13, §16), as the DoFP camera's TracedCamera tests do: on camera 1's axis
// the fused image is the port film's closed form (d = (τ_M − τ_m)/(τ_M + τ_m), the E-vector along
// the film's axis turned by the table: φ = ψ + θ_R, S0 the wall's radiance straight up times
// (τ_M + τ_m)/2 from the test's own tracer); with noise each camera's own reading of that ray gives
// the same port intensity within the Monte-Carlo error of its frames, and the fused AoP, DoP are
// the film's within theirs.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "polrig/io/rig_yaml.h"
#include "polrig/sim/four_camera_frames.h"
#include "polrig/source/sphere_tracer.h"
#include "polrig/units.h"
#include "support.h"

using namespace polrig;

namespace {

// The small theory sphere of tests/test_source.cpp's TracedCamera (a point lamp at the centre, no
// baffle, the port film at ψ = 30° in the scene frame, the cameras' pinhole 20 mm below the port).
constexpr double kFilmDeg = 30.0, kTauM = 0.62, kTaum = 0.18;
const char* kScene =
    "port: {diameter: 100, polarizer: {axis_deg: 30, tau_M: 0.62, tau_m: 0.18}}\n"
    "lamps:\n  - {position: [0, 0, 0], radius: 0, power: 100}\nbaffles: []\n"
    "sensor: {L_o: 20}\n"
    "trace: {photons: 20000, plane_samples: 64}\n";

SceneSpec reference_scene() {
  SceneSpec scene;
  scene.lamps = {LampSpec{{0, 0, 0}, 0.0, 100.0, 0.0}};
  scene.baffles.clear();
  scene.port.polarizer = {kFilmDeg, kTauM, kTaum};
  scene.trace.photons = 20000;
  scene.trace.plane_samples = 64;
  return scene;
}

// An eighth of W16's sensor (the same field: ±38° × ±29°, inside the port's 68°), camera 1's
// principal point on a pixel centre (64.5, 48.5), the other cameras misaligned as the defaults.
struct TracedRig {
  test::TempDir dir{"polrig_test_four_camera_traced_"};
  LoadedRig rig;
  explicit TracedRig(bool noise) {
    const std::string scene = (dir.path() / "scene.yaml").string();
    test::write_file(scene, kScene);
    rig = parse_rig(fmt::format("device:\n  kind: four-camera\n  cameras:\n    width_px: 129\n    height_px: 97\n"
                                "    fx_px: [96.25, 96.4, 96.1125, 96.325]\n    fy_px: [96.25, 96.4, 96.1125, 96.325]\n"
                                "    cx_px: [64.5, 65.3, 64.9625, 65.2375]\n    cy_px: [48.5, 48.975, 49.2875, 49.075]\n"
                                "    gain_DN: [{}]\n    noise: {}\n"
                                "source: {{model: traced, scene: {}}}\n"
                                "schedule: {{angles_deg: [0, 40, 100]}}\n",
                                kGains, noise ? "true" : "false", scene),
                    "traced.yaml");
  }
  static constexpr const char* kGains = "4, 4.12, 3.92, 4.06";
};

// The wall's radiance straight up from the port's centre (the reference's own tracer), times the
// film's transmission at normal incidence.
double axis_S0() {
  const SceneSpec scene = reference_scene();
  const SphereTracer tracer(scene);
  const SphereSolution sol = tracer.solve();
  const double L = tracer.radiance(sol, tracer.first_hit({0, 0, scene.port_plane_z()}, {0, 0, 1}, 0.0));
  return L * 0.5 * (kTauM + kTaum);
}

double axial_difference_deg(double a, double b) { return std::remainder(a - b, 180.0); }

}  // namespace

TEST(TracedFourCamera, OnCameraOnesAxisTheFusedImageIsThePortFilm) {
  const TracedRig r(false);
  const FourCameraSimulator sim(r.rig.rig);
  const VirtualCamera& g = sim.fusion().grid();
  ASSERT_EQ(g.cx, 64.5);
  ASSERT_EQ(g.cy, 48.5);
  const std::size_t axis = 48 * static_cast<std::size_t>(g.width) + 64;  // pixel (64, 48): centre on the axis
  const double d = (kTauM - kTaum) / (kTauM + kTaum), S0 = axis_S0();
  ASSERT_EQ(sim.stops().size(), 3u);
  for (const DofpStop& stop : sim.stops()) {
    const FusedImage f = sim.fuse(sim.signal(stop));
    ASSERT_TRUE(f.valid[axis]);
    std::printf("θ_R %g: AoP %.6f (film %g), DoP %.8f, S0 %.6g (tracer %.6g)\n", stop.theta_R_deg, f.AoP[axis],
                std::fmod(stop.theta_R_deg + kFilmDeg, 180.0), f.DoP[axis], f.S0[axis], S0);
    // Cameras 2–4 see the axis between their pixel centres: bilinear resampling, error ≤ (h²/8)·|f''|
    // with h = 1 px. S0, d and φ change by < 1e-3 (relative, or rad) within 5° (8.4 px) of the axis
    // (S0 by 1.7e-4 even at 30°), so |f''| ≲ 2·1e-3/8.4² px⁻² and the error ≲ 4e-6: bounds 1e-5 of
    // S0, 1e-5 in d, 1e-5 rad = 6e-4° in AoP. The layers are float (6e-8).
    EXPECT_NEAR(axial_difference_deg(f.AoP[axis], stop.theta_R_deg + kFilmDeg), 0.0, 6e-4) << stop.theta_R_deg;
    EXPECT_NEAR(f.DoP[axis], d, 1e-5) << stop.theta_R_deg;
    EXPECT_NEAR(f.S0[axis], S0, 1e-5 * S0) << stop.theta_R_deg;
    // Every virtual pixel sees the port (the field lies inside the port's 68°).
    std::size_t seen = 0;
    for (std::uint8_t v : f.valid) seen += v;
    EXPECT_EQ(seen, f.valid.size());
  }
}

TEST(TracedFourCamera, WithNoiseEachCameraSeesTheSamePortAndTheFusionTheFilm) {
  const TracedRig r(true);
  const FourCameraSimulator sim(r.rig.rig);
  const FourCameraModel& m = sim.truth();
  const VirtualCamera& g = sim.fusion().grid();
  const std::size_t axis = 48 * static_cast<std::size_t>(g.width) + 64;
  const double d = (kTauM - kTaum) / (kTauM + kTaum), S0 = axis_S0();
  const DofpStop& stop = sim.stops().at(1);  // θ_R = 40°: φ = 70° in camera 1's image
  const double phi = deg2rad(stop.theta_R_deg + kFilmDeg);
  const FourCameraSignal signal = sim.signal(stop);
  constexpr int kFrames = 32;
  // Per camera: where camera 1's axis ray lands (its R_j1 and lens), and the bilinear mean of its
  // raw DN there over the frames, as the port intensity I_j = (f − b)/(K·(1 + d·cos(2φ_j − 2a_j)))
  // with φ_j the film's E-vector (cos φ, sin φ, 0) of camera 1's axis seen in camera j's image
  // (R_j1, the meridional conversion of spec §3.4: camera j's roll moves it by up to 0.5°).
  const auto rotate = [](const std::array<double, 9>& R, const Vec3& x) {
    return Vec3{R[0] * x[0] + R[1] * x[1] + R[2] * x[2], R[3] * x[0] + R[4] * x[1] + R[5] * x[2],
                R[6] * x[0] + R[7] * x[1] + R[8] * x[2]};
  };
  std::array<std::vector<double>, 4> I;
  std::vector<double> aop, dop;
  for (int frame = 0; frame < kFrames; ++frame) {
    std::array<std::vector<std::uint16_t>, 4> raw;
    {
      tbb::global_control c(tbb::global_control::max_allowed_parallelism, frame % 2 + 1);
      raw = sim.frames(signal, frame);
    }
    if (frame == 0) {
      tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
      EXPECT_EQ(sim.frames(signal, 0), raw);  // the same bits for 1 and 2 threads
    }
    for (int j = 0; j < 4; ++j) {
      const CameraGeometry& cam = m.camera[static_cast<std::size_t>(j)];
      const Vec3 ray = rotate(cam.R, {0, 0, 1});
      const auto p = project(cam, ray);
      const double u = p[0] - 0.5, v = p[1] - 0.5;
      const int c0 = static_cast<int>(std::floor(u)), r0 = static_cast<int>(std::floor(v));
      const double a = u - c0, b = v - r0;
      const auto at = [&](int c, int rr) {
        return static_cast<double>(raw[static_cast<std::size_t>(j)][static_cast<std::size_t>(rr * m.width + c)]);
      };
      const double f = (1 - a) * (1 - b) * at(c0, r0) + a * (1 - b) * at(c0 + 1, r0) + (1 - a) * b * at(c0, r0 + 1) +
                       a * b * at(c0 + 1, r0 + 1);
      const double phi_j = image_plane_aop_rad(ray, rotate(cam.R, {std::cos(phi), std::sin(phi), 0}));
      const double malus = 1 + d * std::cos(2 * phi_j - 2 * deg2rad(m.axis_deg[static_cast<std::size_t>(j)]));
      I[static_cast<std::size_t>(j)].push_back((f - m.b[static_cast<std::size_t>(j)]) /
                                               (m.K[static_cast<std::size_t>(j)] * malus));
    }
    const FusedImage fused = sim.fuse(raw);
    aop.push_back(axial_difference_deg(fused.AoP[axis], stop.theta_R_deg + kFilmDeg));
    dop.push_back(fused.DoP[axis] - d);
  }
  const auto mean = [](const std::vector<double>& x) {
    double s = 0;
    for (double v : x) s += v;
    return s / static_cast<double>(x.size());
  };
  const auto se = [&](const std::vector<double>& x) {
    const double mu = mean(x);
    double s = 0;
    for (double v : x) s += (v - mu) * (v - mu);
    return std::sqrt(s / static_cast<double>(x.size() - 1) / static_cast<double>(x.size()));
  };
  for (std::size_t j = 0; j < 4; ++j) {
    std::printf("camera %zu: port intensity %.6g ± %.2g (tracer %.6g)\n", j + 1, mean(I[j]), se(I[j]), S0);
    // The ADC rounds (≤ 0.5 DN, averaged by the noise) and the bilinear sample of a field that
    // varies over a pixel: both far below the noise of 32 frames.
    EXPECT_NEAR(mean(I[j]), S0, 3.5 * se(I[j])) << "camera " << j + 1;
  }
  std::printf("fused AoP − film %.4f ± %.4f deg, DoP − film %.5f ± %.5f\n", mean(aop), se(aop), mean(dop), se(dop));
  EXPECT_NEAR(mean(aop), 0.0, 3.5 * se(aop));
  // The DoP of noisy Stokes is biased up by ≈ σ²/(2d) (Rice): far below the SE here at d = 0.55.
  EXPECT_NEAR(mean(dop), 0.0, 3.5 * se(dop));
}
