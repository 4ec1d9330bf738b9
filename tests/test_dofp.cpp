// The DoFP camera (spec sky-and-compasses.md §2.1–2.5): geometry, overlap, truth, noise, frames.
#include <cmath>
#include <numbers>
#include <set>

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "polrig/calib/dofp.h"
#include "polrig/device/dofp_camera.h"
#include "polrig/io/dofp_dataset.h"
#include "polrig/io/exr.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/report/dofp_dataset.h"
#include "polrig/sim/dofp_frames.h"
#include "polrig/sky/sun.h"
#include "polrig/source/source.h"
#include "polrig/units.h"
#include "polrig/vector_log.h"

using namespace polrig;

namespace {

Rig camera_rig() {
  Rig rig;
  rig.device_kind = "dofp-camera";
  rig.source.cos4.E_0 = 1.0;
  rig.device.d = 0.9;
  rig.camera.noise = false;
  rig.camera.adc_bits = 16;
  rig.camera.gain_DN = 20000;
  rig.schedule.angles_deg = {0, 30};
  return rig;
}

Rig sky_camera_rig() {
  Rig rig = camera_rig();
  SourceSpec s = rig.source;
  s.model = "sky";
  s.sky.first_stop_utc = "2017-05-28T10:00:00Z";
  s.sky.sky.site.lat_deg = 28.2;
  s.sky.sky.site.lon_deg = 112.9;
  s.sky.mount.mount_deg = 20;
  rig.source = s;
  rig.light = make_source(s);
  // As load_rig: the sky sets the rig's d (its value at the first stop), so that the rig.yaml a
  // dataset carries loads back.
  if (const std::optional<double> d = rig.light->rig_degree_of_polarization(rig.source_view())) rig.device.d = *d;
  return rig;
}

// Spec §2.5 Eqs. 6–9, written out: the E-vector in frame l of a pixel whose image AoP is φ_pix
// (image-plane analyzer: φ = φ_pix − α).
Vec3 eq6_to_9_evector(const DofpCameraSpec& cam, int col, int row, double phi_pix_deg) {
  const double fc = cam.focal_mm / cam.pixel_um * 1000.0;
  const double xp = col + 0.5 - cam.width_px / 2.0, yp = row + 0.5 - cam.height_px / 2.0;
  const double gamma = std::atan(std::hypot(xp, yp) / fc), alpha = std::atan2(yp, xp);
  const double phi = deg2rad(phi_pix_deg) - alpha;
  const Vec3 P{std::cos(phi), std::sin(phi), 0};
  // Ry(γ)·P then Rz(α)·that.
  const Vec3 q{std::cos(gamma) * P[0] + std::sin(gamma) * P[2], P[1], -std::sin(gamma) * P[0] + std::cos(gamma) * P[2]};
  return {std::cos(alpha) * q[0] - std::sin(alpha) * q[1], std::sin(alpha) * q[0] + std::cos(alpha) * q[1], q[2]};
}

}  // namespace

TEST(DofpCamera, FieldOfViewFocalLengthAndCellsAsSpec2_1) {
  const DofpCameraSpec cam;
  EXPECT_NEAR(focal_px(cam), 405.4, 0.05);
  EXPECT_NEAR(fov_x_deg(cam), 76.6, 0.05);
  EXPECT_NEAR(fov_y_deg(cam), 61.3, 0.05);
  // Unit cells: every (col/2, row/2) holds the four positions once. H17 states 160 × 120 cells
  // (19,200) of 2 × 2 polarizers of one pixel each, which covers 320 × 240 pixels, not 640 × 480:
  // a 2 × 2-pixel cell on the whole sensor gives 320 × 240 = 76,800 (docs/physics.md §13).
  std::set<std::pair<int, int>> cells;
  std::array<int, 4> count{};
  for (int row = 0; row < cam.height_px; ++row)
    for (int col = 0; col < cam.width_px; ++col) {
      const int j = mosaic_position(col, row);
      ++count[static_cast<std::size_t>(j)];
      if (j == 0) cells.insert({col / 2, row / 2});
    }
  EXPECT_EQ(cells.size(), 76800u);
  EXPECT_EQ(count, (std::array<int, 4>{76800, 76800, 76800, 76800}));
  EXPECT_EQ(mosaic_position(1, 0), 1);  // TR
  EXPECT_EQ(mosaic_position(0, 1), 2);  // BL
  // The corner pixel's view: (x, y, f_c) normalised, x = −319.5, y = −239.5.
  const Vec3 v = pixel_view(cam, 0, 0);
  const double r = std::sqrt(319.5 * 319.5 + 239.5 * 239.5 + focal_px(cam) * focal_px(cam));
  EXPECT_NEAR(v[0], -319.5 / r, 1e-15);
  EXPECT_NEAR(v[1], -239.5 / r, 1e-15);
}

TEST(DofpCamera, OverlapExamplesOfSpec2_3) {
  const double w[] = {0.95, 0.05};
  const double a90[] = {0, 90}, a45[] = {0, 45};
  const Overlap o90 = overlap(w, a90);
  EXPECT_NEAR(o90.k, 0.900, 1e-12);
  EXPECT_NEAR(overlap_eps_deg(0, o90), 0.0, 1e-12);
  const Overlap o45 = overlap(w, a45);
  EXPECT_NEAR(o45.k, 0.951, 5e-4);
  EXPECT_NEAR(overlap_eps_deg(0, o45), -1.51, 5e-3);
}

TEST(DofpCamera, ShiftedMosaicMatchesProductsOfOneDimensionalOverlaps) {
  DofpCameraSpec cam;
  cam.width_px = 8, cam.height_px = 6;
  cam.misregistration_dx_px = 0.3, cam.misregistration_dy_px = -0.2;
  const DofpTruth t = make_dofp_truth(cam, 1);
  for (int row = 0; row < cam.height_px; ++row)
    for (int col = 0; col < cam.width_px; ++col) {
      // The pixel [col, col+1] sees mosaic columns col − 1 (fraction 0.3) and col (0.7); rows
      // row (0.8) and row + 1 (0.2).
      std::complex<double> c = 0;
      for (int dc : {-1, 0})
        for (int dr : {0, 1}) {
          const double wx = dc == -1 ? 0.3 : 0.7, wy = dr == 0 ? 0.8 : 0.2;
          const double a = cam.mosaic_deg[static_cast<std::size_t>(((row + dr) & 1) * 2 + ((col + dc) & 1))];
          c += wx * wy * std::polar(1.0, 2 * deg2rad(a));
        }
      const std::size_t i = static_cast<std::size_t>(row * cam.width_px + col);
      const double D = (cam.extinction_ratio - 1) / (cam.extinction_ratio + 1);  // default ER 1e9
      EXPECT_NEAR(t.k[i], std::abs(c) * D, 1e-12);
      const double eps = std::remainder(t.alpha_deg[i] - rad2deg(0.5 * std::arg(c)), 180.0);
      EXPECT_NEAR(std::remainder(t.eps_deg[i] - eps, 180.0), 0.0, 1e-10);
    }
}

TEST(DofpCamera, RotatedMosaicMatchesANumericIntegralOfEq16) {
  DofpCameraSpec cam;
  cam.misregistration_dx_px = 0.15, cam.misregistration_dy_px = 0.4, cam.misregistration_rotation_deg = 0.3;
  const DofpTruth t = make_dofp_truth(cam, 1);
  const double cx = 320, cy = 240, rot = deg2rad(0.3);
  constexpr int N = 1500;
  for (auto [col, row] : {std::pair{0, 0}, std::pair{639, 479}, std::pair{320, 241}, std::pair{101, 400}}) {
    const std::size_t i = static_cast<std::size_t>(row * 640 + col);
    for (double phi : {0.0, 33.0, 77.0, 131.0}) {
      // Eq. 16: the pixel's mean of ½·I·[1 + d·cos(2φ − 2α_q)] over its area, α_q the axis of the
      // mosaic cell under each point (the mosaic's cell (c, r) sits at centre + Rot·(m − centre) + d).
      const double I = 1, d = 0.8;
      double sum = 0;
      for (int a = 0; a < N; ++a)
        for (int b = 0; b < N; ++b) {
          const double px = col + (a + 0.5) / N - cx - 0.15, py = row + (b + 0.5) / N - cy - 0.4;
          const double mx = cx + std::cos(rot) * px + std::sin(rot) * py, my = cy - std::sin(rot) * px + std::cos(rot) * py;
          const int q = static_cast<int>(std::floor(mx)), r = static_cast<int>(std::floor(my));
          const double alpha = cam.mosaic_deg[static_cast<std::size_t>((r & 1) * 2 + (q & 1))] + 0.3;
          sum += 0.5 * I * (1 + d * std::cos(2 * deg2rad(phi - alpha)));
        }
      const double eq16 = sum / (double(N) * N);
      const double eq17 = 0.5 * I * (1 + t.k[i] * d * std::cos(2 * deg2rad(phi - (t.alpha_deg[i] - t.eps_deg[i]))));
      // The midpoint grid's area error on a straight boundary is ≤ 1/N of the pixel per edge crossing.
      EXPECT_NEAR(eq16, eq17, 2.0 / N) << col << "," << row << " φ " << phi;
    }
  }
}

TEST(DofpCamera, TruthSpreadsAndExtinction) {
  DofpCameraSpec cam;
  cam.gain_spread = 0.02, cam.offset_DN = 50, cam.offset_spread_DN = 3;
  cam.k = {0.99, 0.98, 0.97, 0.96};
  cam.eps_deg = {0, 1, -1, 0.5};
  cam.extinction_ratio = 100;
  const DofpTruth t = make_dofp_truth(cam, 7);
  double sK = 0, sK2 = 0, sb = 0;
  for (double K : t.K) sK += K, sK2 += K * K;
  for (double b : t.b) sb += b;
  const double n = double(t.K.size());
  EXPECT_NEAR(sK / n, 2000, 4 * 40 / std::sqrt(n));
  EXPECT_NEAR(std::sqrt(sK2 / n - (sK / n) * (sK / n)), 40, 0.5);
  EXPECT_NEAR(sb / n, 50, 4 * 3 / std::sqrt(n));
  EXPECT_DOUBLE_EQ(t.k[1], 0.98 * 99.0 / 101.0);  // TR of the first cell
  EXPECT_DOUBLE_EQ(t.eps_deg[640], -1);           // BL
  EXPECT_EQ(make_dofp_truth(cam, 7).K, t.K);
}

TEST(DofpCamera, MosaicGainScalesEachPositionsGain) {
  DofpCameraSpec cam;
  cam.width_px = 64, cam.height_px = 48;
  const DofpTruth plain = make_dofp_truth(cam, 3);
  cam.mosaic_gain = {1.0, 1.06, 0.95, 1.03};
  const DofpTruth t = make_dofp_truth(cam, 3);
  // Without a spread every pixel's K is exactly gain_DN·mosaic_gain[j] (the position's factor and
  // nothing else); k, ε and b are untouched.
  for (int row = 0; row < 48; ++row)
    for (int col = 0; col < 64; ++col) {
      const std::size_t i = static_cast<std::size_t>(row * 64 + col);
      const double g = cam.mosaic_gain[static_cast<std::size_t>((row % 2) * 2 + col % 2)];
      ASSERT_EQ(t.K[i], 2000.0 * g) << col << "," << row;
      ASSERT_EQ(t.k[i], plain.k[i]);
      ASSERT_EQ(t.b[i], plain.b[i]);
    }
  // With a spread the factor multiplies the same draw: K / K_plain = the factor.
  cam.gain_spread = 0.02;
  DofpCameraSpec one = cam;
  one.mosaic_gain = {1, 1, 1, 1};
  const DofpTruth a = make_dofp_truth(cam, 3), b = make_dofp_truth(one, 3);
  EXPECT_NEAR(a.K[65] / b.K[65], 1.03, 1e-15);  // row 1, column 1: BR
  for (double bad : {0.0, -1.0, std::nan("")}) {
    cam.mosaic_gain[2] = bad;
    EXPECT_THROW(make_dofp_truth(cam, 3), std::invalid_argument) << bad;
  }
}

TEST(DofpCamera, NormalQuantileInvertsTheNormalCdf) {
  for (double p : {1e-300, 1e-20, 1e-8, 0.001, 0.02425, 0.075, 0.3, 0.5, 0.6, 0.924, 0.99, 1 - 1e-12}) {
    const double x = normal_quantile(p);
    const double P = 0.5 * std::erfc(-x / std::sqrt(2.0));
    EXPECT_NEAR(P / p, 1.0, 1e-13) << p;
  }
}

TEST(DofpCamera, NoiseDeviateIsTheQuantileWithin2e5) {
  for (int i = 1; i < 100000; ++i) {
    const double u = i / 100000.0;
    ASSERT_NEAR(noise_deviate(u), normal_quantile(u), 2e-5) << u;
  }
}

TEST(DofpCamera, NoiseHasThePoissonGaussianVariance) {
  DofpCameraSpec cam;
  cam.adc_bits = 16;
  cam.electrons_per_DN = 10, cam.read_noise_DN = 2;
  constexpr int N = 200000;
  const double b = 100, s = 1000;
  double m = 0, m2 = 0;
  for (int i = 0; i < N; ++i) {
    const double v = expose_DN(cam, b + s, b, 42, 3, 1, static_cast<std::uint64_t>(i));
    m += v, m2 += v * v;
  }
  m /= N, m2 = m2 / N - m * m;
  // s/e + r² + 1/12 (the rounding), its estimate's SE ≈ var·√(2/N).
  const double var = s / 10 + 4 + 1.0 / 12;
  EXPECT_NEAR(m, b + s, 4 * std::sqrt(var / N));
  EXPECT_NEAR(m2, var, 4 * var * std::sqrt(2.0 / N));
  // Small λ: exact Poisson counts (1 electron per DN, no read noise): mean = var = λ.
  cam.electrons_per_DN = 1, cam.read_noise_DN = 0;
  const double lambda = 7.5;
  m = m2 = 0;
  int zeros = 0;
  for (int i = 0; i < N; ++i) {
    const double v = expose_DN(cam, b + lambda, b, 42, 4, 0, static_cast<std::uint64_t>(i)) - b;
    m += v, m2 += v * v, zeros += v == 0;
  }
  m /= N, m2 = m2 / N - m * m;
  EXPECT_NEAR(m, lambda, 4 * std::sqrt(lambda / N));
  EXPECT_NEAR(m2, lambda, 4 * lambda * std::sqrt((2 + 1 / lambda) / N));
  const double p0 = std::exp(-lambda);
  EXPECT_NEAR(double(zeros) / N, p0, 4 * std::sqrt(p0 / N));
  // The ADC clamps.
  cam.adc_bits = 12;
  EXPECT_EQ(expose_DN(cam, 1e6, 0, 1, 0, 0, 0), 4095);
  EXPECT_EQ(expose_DN(cam, -50, 0, 1, 0, 0, 0), 0);
}

TEST(DofpFrames, StopsUnpolarizedFirstThenIntensityMajor) {
  Schedule s;
  s.unpolarized_levels = {0, 0.5};
  s.intensities = {1, 0.25};
  s.angles_deg = {0, 90, 180};
  s.frames_per_stop = 5;
  s.speed_deg_s = 10, s.dwell_s = 1;
  const auto stops = dofp_stops(s);
  ASSERT_EQ(stops.size(), 8u);
  EXPECT_FALSE(stops[1].polarized);
  EXPECT_EQ(stops[1].intensity, 0.5);
  EXPECT_TRUE(stops[2].polarized);
  EXPECT_EQ(stops[5].intensity, 0.25);
  EXPECT_EQ(stops[5].theta_R_deg, 0);
  EXPECT_EQ(stops[4].frames, 5);
  EXPECT_DOUBLE_EQ(stops[4].t_s, 1 + 1 + 10 + 10);  // two dwells at 0°, 90° and 180° (9 s each + dwell)
  EXPECT_DOUBLE_EQ(stops[5].t_s, stops[4].t_s + 18 + 1);
}

TEST(DofpFrames, SphereRigAoPFollowsEqs6To9AndTheTable) {
  Rig rig = camera_rig();
  rig.source.polarizer_deg = 20;
  const DofpSimulator sim(rig);
  for (const DofpStop& stop : sim.stops()) {
    DofpTruthLayers L;
    const auto raw = sim.frame(stop, 0, &L);
    // On the axis the camera sees θ_R − ψ_P (docs/physics.md §1's sense); the four centre pixels
    // are 0.5 px off the axis, which moves the AoP by < 1e-5°.
    const double centre = std::remainder(L.AoP[240 * 640 + 320] - (stop.theta_R_deg - 20), 180.0);
    EXPECT_NEAR(centre, 0.0, 1e-4);
    // Everywhere: Eqs. 6–9 from the AoP give the E-vector of the port polarizer's axis projected
    // ⊥ the view (in frame l: X = Rot(θ_R)x̂, Y = −Rot(θ_R)ŷ, Z = −ẑ of the rig frame).
    const double th = deg2rad(stop.theta_R_deg), ps = deg2rad(20.0);
    const Vec3 p_l{std::cos(ps) * std::cos(th) + std::sin(ps) * std::sin(th),
                   std::cos(ps) * std::sin(th) - std::sin(ps) * std::cos(th), 0};
    for (int row = 0; row < 480; row += 37)
      for (int col = 0; col < 640; col += 41) {
        const std::size_t i = static_cast<std::size_t>(row * 640 + col);
        const Vec3 v = pixel_view(rig.camera, col, row);
        const Vec3 e_true = vec3::unit(vec3::sub(p_l, vec3::mul(v, vec3::dot(p_l, v))));
        const Vec3 e = eq6_to_9_evector(rig.camera, col, row, L.AoP[i]);
        EXPECT_NEAR(std::abs(vec3::dot(e, e_true)), 1.0, 1e-9);
        EXPECT_NEAR(L.DoP[i], 0.9, 1e-7);
        // Eq. 18 from the truth and the layers, rounded by the ADC.
        const DofpTruth& t = sim.truth();
        const double f = eq18_DN(t.K[i], t.b[i], t.k[i], t.eps_deg[i], t.alpha_deg[i], L.S0[i], L.DoP[i], L.AoP[i]);
        EXPECT_NEAR(raw[i], f, 0.5 + 1e-2);
      }
  }
}

// Step 2's view projection (calib/dofp.h, dofp_projected_aop_deg: a port polarizer's axis at β in
// frame l seen along a view, φ = arg(M·(cos β, sin β))) against the camera's own frame simulation:
// three ideal cameras whose four analyzers all sit at 0°, 45° and 90° give, per pixel, A·d·cos 2φ,
// A·d·sin 2φ and A = (f0 + f90)/2 of Eq. 18 in double precision, so φ of every pixel without the
// float truth layer. β = θ_R − ψ_P (the on-axis AoP, docs/physics.md §13).
// The row kernels (and the cos4 source's along) run once per instruction set: AVX2 where the CPU
// has it, else the baseline; both give the same frames and truth layers, bit for bit, for both
// analyzers, with noise, under the port and under the sky.
TEST(DofpFrames, BaselineAndAvx2PathsGiveTheSameBits) {
  for (const bool sky : {false, true})
    for (const DofpAnalyzer analyzer : {DofpAnalyzer::ImagePlane, DofpAnalyzer::InFront}) {
      Rig rig = sky ? sky_camera_rig() : camera_rig();
      rig.camera.noise = true;
      rig.camera.vignetting = !sky;
      const DofpSimulator sim(rig, analyzer);
      for (const DofpStop& stop : sim.stops()) {
        DofpTruthLayers best_layers, baseline_layers;
        const std::vector<std::uint16_t> best = sim.frame(stop, 1, &best_layers);
        set_baseline_paths_only(true);
        const std::vector<std::uint16_t> baseline = sim.frame(stop, 1, &baseline_layers);
        set_baseline_paths_only(false);
        EXPECT_EQ(best, baseline) << "sky " << sky << ", stop " << stop.index;
        for (auto m : {&DofpTruthLayers::S0, &DofpTruthLayers::S1, &DofpTruthLayers::S2, &DofpTruthLayers::AoP,
                       &DofpTruthLayers::DoP}) {
          const std::vector<float>&a = best_layers.*m, &b = baseline_layers.*m;
          ASSERT_EQ(a.size(), b.size());
          EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(float)), 0) << "sky " << sky;
        }
      }
    }
}

TEST(DofpFrames, ViewProjectionIsTheSimulatedAoPOfEveryPixel) {
  Rig rig = camera_rig();
  rig.source.polarizer_deg = 20;
  rig.device.d = 1.0;
  rig.schedule.angles_deg = {0, 30, 117.5};
  std::vector<DofpSimulator::StopSignal> f[3];
  const double axes[3] = {0, 45, 90};
  for (int a = 0; a < 3; ++a) {
    rig.camera.mosaic_deg = {axes[a], axes[a], axes[a], axes[a]};
    const DofpSimulator sim(rig);
    for (const DofpStop& stop : sim.stops()) f[a].push_back(sim.signal(stop));
  }
  double worst = 0, largest_departure = 0;
  for (std::size_t s = 0; s < f[0].size(); ++s) {
    const double beta = f[0][s].stop.theta_R_deg - 20.0;
    for (int row = 0; row < 480; ++row)
      for (int col = 0; col < 640; ++col) {
        const std::size_t i = static_cast<std::size_t>(row * 640 + col);
        const double A = 0.5 * (f[0][s].f[i] + f[2][s].f[i]);
        const double phi_sim = rad2deg(0.5 * std::atan2(f[1][s].f[i] - A, 0.5 * (f[0][s].f[i] - f[2][s].f[i])));
        const double phi = dofp_projected_aop_deg(pixel_view(rig.camera, col, row), beta);
        worst = std::max(worst, std::abs(std::remainder(phi - phi_sim, 180.0)));
        largest_departure = std::max(largest_departure, std::abs(std::remainder(phi - beta, 180.0)));
      }
  }
  EXPECT_LT(worst, 1e-9);
  // Not true by construction: the projection moves the AoP by degrees at the corners.
  EXPECT_GT(largest_departure, 5.0);
  // Along the azimuth 0 (a view in the x–z plane at zenith angle γ): tan φ = tan β / cos γ.
  const double g = deg2rad(35.0);
  EXPECT_NEAR(dofp_projected_aop_deg({std::sin(g), 0, std::cos(g)}, 30.0),
              rad2deg(std::atan(std::tan(deg2rad(30.0)) / std::cos(g))), 1e-12);
}

TEST(DofpFrames, UnpolarizedStopsAndVignetting) {
  Rig rig = camera_rig();
  rig.schedule.unpolarized_levels = {0.5};
  rig.camera.vignetting = true;
  const DofpSimulator sim(rig);
  DofpTruthLayers L;
  const auto raw = sim.frame(sim.stops()[0], 0, &L);
  EXPECT_EQ(L.DoP[1000], 0.0f);
  // cos⁴γ at the corner pixel.
  const double fc = focal_px(rig.camera), r2 = 319.5 * 319.5 + 239.5 * 239.5;
  EXPECT_NEAR(L.S0[0], 0.5 * std::pow(fc * fc / (fc * fc + r2), 2), 1e-7);
  EXPECT_EQ(raw[0], static_cast<std::uint16_t>(std::floor(0.5 * 20000 * L.S0[0] + 0.5)));
}

TEST(DofpFrames, SkyEVectorsArePerpendicularToTheSun) {
  Rig rig = sky_camera_rig();
  const DofpSimulator sim(rig);
  const Sky sky = rig.source.sky.resolved_sky();
  for (const DofpStop& stop : sim.stops()) {
    DofpTruthLayers L;
    sim.frame(stop, 0, &L);
    const Vec3 s = sun_direction_enu(sun_position(sky.first_stop.plus_seconds(stop.t_s), sky.site, sky.sun));
    const SensorAxesEnu a = sensor_axes_enu(rig.source.sky.resolved_mount(), stop.theta_R_deg);
    const Vec3 s_l{vec3::dot(s, a.x), vec3::dot(s, a.y), vec3::dot(s, a.z)};
    for (int row = 0; row < 480; row += 23)
      for (int col = 0; col < 640; col += 29) {
        const std::size_t i = static_cast<std::size_t>(row * 640 + col);
        if (L.DoP[i] < 0.05) continue;
        const Vec3 e = eq6_to_9_evector(rig.camera, col, row, L.AoP[i]);
        EXPECT_NEAR(vec3::dot(e, s_l), 0.0, 2e-6);  // the AoP is a float: 1e-5° at 180°
      }
    // The heading: X_l's azimuth is the mount's plus the table angle (clockwise from above).
    EXPECT_NEAR(*dofp_true_heading_deg(rig, stop), std::fmod(20 + stop.theta_R_deg, 360.0), 1e-12);
  }
}

TEST(DofpFrames, InFrontAnalyzerDiffersOffAxisAsSpec2_5) {
  Rig rig = camera_rig();
  rig.schedule.angles_deg = {0};
  DofpTruthLayers a, b;
  DofpSimulator(rig, DofpAnalyzer::ImagePlane).frame(DofpStop{}, 0, &a);
  DofpSimulator(rig, DofpAnalyzer::InFront).frame(DofpStop{}, 0, &b);
  // In front: the AoP's axis (cos φ, sin φ, 0) projected ⊥ v is along e, so (v × e) ⊥ that axis.
  const DofpCameraSpec& cam = rig.camera;
  for (int row : {0, 100, 479})
    for (int col : {0, 300, 639}) {
      const std::size_t i = static_cast<std::size_t>(row * 640 + col);
      const Vec3 v = pixel_view(cam, col, row);
      const Vec3 p{1, 0, 0};  // ψ_P = 0, θ_R = 0: the polarizer along X_l
      const Vec3 e = vec3::unit(vec3::sub(p, vec3::mul(v, v[0])));
      const Vec3 axis{std::cos(deg2rad(b.AoP[i])), std::sin(deg2rad(b.AoP[i])), 0};
      EXPECT_NEAR(vec3::dot(vec3::cross(v, e), axis), 0.0, 1e-6);
    }
  // Here the polarizer's own axis projects along e for every view: φ_pix = 0 in front exactly.
  EXPECT_NEAR(std::remainder(b.AoP[0], 180.0), 0.0, 1e-5);
  EXPECT_GT(std::abs(std::remainder(a.AoP[0] - b.AoP[0], 180.0)), 0.1);
}

TEST(DofpFrames, BitIdenticalForAnyThreadCount) {
  Rig rig = camera_rig();
  rig.camera.noise = true;
  rig.camera.gain_DN = 2000, rig.camera.adc_bits = 12;
  const DofpSimulator sim(rig);
  std::vector<std::uint16_t> one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = sim.frame(sim.stops()[1], 3);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = sim.frame(sim.stops()[1], 3);
  }
  EXPECT_EQ(one, two);
  EXPECT_NE(one, sim.frame(sim.stops()[1], 4));
}

TEST(DofpFrames, AStopsSignalMadeOnceGivesTheSameFramesAndLayers) {
  Rig rig = camera_rig();
  rig.camera.noise = true;
  rig.camera.gain_DN = 2000, rig.camera.adc_bits = 12;
  rig.schedule.unpolarized_levels = {0.5};  // stops: the level, then 0° and 30°
  const DofpSimulator sim(rig);
  ASSERT_EQ(sim.stops().size(), 3u);
  const DofpStop& stop = sim.stops()[2];
  DofpTruthLayers direct, once;
  const DofpSimulator::StopSignal signal = sim.signal(stop, &once);
  for (int f : {0, 1, 7}) {
    std::vector<std::uint16_t> split;
    {
      tbb::global_control c(tbb::global_control::max_allowed_parallelism, f == 1 ? 1 : 2);
      split = sim.frame(signal, f);
    }
    EXPECT_EQ(sim.frame(stop, f, f == 0 ? &direct : nullptr), split) << "frame " << f;
  }
  EXPECT_EQ(direct.S0, once.S0);
  EXPECT_EQ(direct.S1, once.S1);
  EXPECT_EQ(direct.AoP, once.AoP);
  EXPECT_EQ(direct.DoP, once.DoP);
  // The frames differ from one another (independent noise), the signal not.
  EXPECT_NE(sim.frame(signal, 0), sim.frame(signal, 1));
}

TEST(DofpFrames, RefusesRigsWithoutFramesOrLightAlongViews) {
  Rig rig;
  EXPECT_THROW(DofpSimulator{rig}, std::invalid_argument);
  Rig sky = sky_camera_rig();
  sky.schedule.unpolarized_levels = {1};
  EXPECT_THROW(DofpSimulator{sky}, std::invalid_argument);
}

namespace {
std::filesystem::path fresh_dir(const std::string& name) {
  const auto p = std::filesystem::temp_directory_path() / fmt::format("polrig_test_dofp_{}_{}", name, ::getpid());
  std::filesystem::remove_all(p);
  return p;
}
}  // namespace

TEST(DofpDataset, WritesAndReadsBackEveryFrameAndTheSums) {
  Rig rig = camera_rig();
  rig.camera.width_px = 32, rig.camera.height_px = 24;
  rig.camera.noise = true, rig.camera.gain_DN = 2000, rig.camera.adc_bits = 12;
  rig.camera.gain_spread = 0.03;
  rig.schedule.unpolarized_levels = {0, 0.5};
  rig.schedule.frames_per_stop = 3;
  const LoadedRig loaded{rig, "test", "", {}};
  const DofpSimulator sim(rig);
  for (DofpFrameStorage storage : {DofpFrameStorage::Every, DofpFrameStorage::Sum}) {
    const auto dir = fresh_dir(storage == DofpFrameStorage::Every ? "every" : "sum");
    DofpDatasetOptions o;
    o.storage = storage;
    o.truth_layers = true;
    write_dofp_dataset(loaded, dir, o, "polrig simulate test", false);
    EXPECT_THROW(write_dofp_dataset(loaded, dir, o, "again", false), std::runtime_error);  // never replaced
    const DofpDataset d = read_dofp_dataset(dir);
    EXPECT_EQ(d.width, 32);
    EXPECT_NEAR(d.f_c_px, 405.405, 1e-3);
    EXPECT_EQ(d.cx, 16);
    ASSERT_EQ(d.stops.size(), 4u);
    EXPECT_FALSE(d.stops[0].polarized);
    EXPECT_EQ(d.stops[2].theta_R_deg, 0);
    EXPECT_EQ(d.stops[3].theta_R_deg, 30);
    EXPECT_FALSE(d.stops[3].heading_deg);
    ASSERT_TRUE(d.truth);
    EXPECT_EQ(d.truth->K.size(), 32u * 24u);
    for (std::size_t i = 0; i < d.truth->K.size(); ++i) EXPECT_EQ(d.truth->K[i], static_cast<float>(sim.truth().K[i]));
    for (std::size_t s = 0; s < d.stops.size(); ++s) {
      std::vector<double> mean(32 * 24, 0.0);
      for (int f = 0; f < 3; ++f) {
        const auto raw = sim.frame(sim.stops()[s], f);
        for (std::size_t i = 0; i < raw.size(); ++i) mean[i] += raw[i];
        if (storage == DofpFrameStorage::Every) {
          EXPECT_EQ(read_dofp_frames(d, s)[static_cast<std::size_t>(f)], raw);
        }
      }
      for (double& m : mean) m /= 3;
      EXPECT_EQ(read_dofp_mean_frame(d, s), mean);
    }
    EXPECT_TRUE(std::filesystem::exists(dir / "manifest.yaml"));
    std::filesystem::remove_all(dir);
  }
}

TEST(DofpDataset, SkyStopsCarryUtcHeadingAndTheSun) {
  Rig rig = sky_camera_rig();
  rig.camera.width_px = 16, rig.camera.height_px = 12;
  const auto dir = fresh_dir("sky");
  write_dofp_dataset(LoadedRig{rig, "test", "", {}}, dir, {}, "polrig simulate test", false);
  const DofpDataset d = read_dofp_dataset(dir);
  ASSERT_EQ(d.stops.size(), 2u);
  EXPECT_EQ(d.stops[0].utc, "2017-05-28T10:00:00Z");
  EXPECT_NEAR(*d.stops[1].heading_deg, 50, 1e-12);
  const ExrImage image = read_exr_image(dir / d.stops[1].file);
  bool sun = false;
  for (const auto& [name, v] : image.attributes.vectors)
    if (name == "sun_enu") {
      const Sky sky = rig.source.sky.resolved_sky();
      const Vec3 s = sun_direction_enu(sun_position(sky.first_stop.plus_seconds(d.stops[1].t_s), sky.site, sky.sun));
      EXPECT_EQ(v, s);
      sun = true;
    }
  EXPECT_TRUE(sun);
  std::filesystem::remove_all(dir);
}

// The han2017 indoor dataset (spec §2.4: 30 unpolarized levels, 79 positions at 4.6036° × six
// intensities, 5 frames per stop) of the shipped rig file: its size on disk, printed with the time
// it took (docs/formats.md §6.14 quotes them). The issue aims under 300 MB (10^6 bytes) for the
// per-stop means. Slow: ~2,500 frames, ~1 GB written.
TEST(SlowDofpDataset, Han2017IndoorSize) {
  const LoadedRig rig = load_rig(std::string(POLRIG_SOURCE_DIR) + "/rigs/han2017-indoor.yaml");
  ASSERT_EQ(dofp_stops(rig.rig.schedule).size(), 30u + 79u * 6u);
  ASSERT_EQ(rig.rig.schedule.frames_per_stop, 5);
  for (DofpFrameStorage storage : {DofpFrameStorage::Sum, DofpFrameStorage::Every}) {
    const auto dir = fresh_dir("han2017");
    DofpDatasetOptions o;
    o.storage = storage;
    const auto t0 = std::chrono::steady_clock::now();
    write_dofp_dataset(rig, dir, o, "polrig simulate rigs/han2017-indoor.yaml", false);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::uintmax_t bytes = 0;
    for (const auto& e : std::filesystem::recursive_directory_iterator(dir))
      if (e.is_regular_file()) bytes += e.file_size();
    std::printf("han2017 indoor, %s: %.1f MB in %.1f s\n", storage == DofpFrameStorage::Sum ? "per-stop sums" : "every frame",
                bytes / 1e6, s);
    if (storage == DofpFrameStorage::Sum) {
      EXPECT_LT(bytes, 300e6);
    }
    std::filesystem::remove_all(dir);
  }
}
