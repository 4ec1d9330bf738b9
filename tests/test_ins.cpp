// ins/: the strapdown INS half of issue 24 (spec sky-and-compasses.md §4.3, §4.4, §4.7). Every
// check is against an independent reference: textbook WGS-84 numbers, Somigliana's closed form
// written here, the closed forms of Titterton & Weston ch. 12 (Schuler, gyro drift), the Gauss–
// Markov and Allan closed forms, central differences, and χ² bands. Tolerances are derived in the
// comment beside each.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <GeographicLib/NormalGravity.hpp>
#include <unsupported/Eigen/MatrixFunctions>

#include "almanac_sun.h"
#include "polrig/ins/allan.h"
#include "polrig/ins/attitude.h"
#include "polrig/ins/earth.h"
#include "polrig/ins/error_model.h"
#include "polrig/ins/filter.h"
#include "polrig/ins/imu.h"
#include "polrig/ins/mechanization.h"
#include "polrig/ins/smoother.h"
#include "polrig/ins/trajectory.h"
#include "polrig/ins/zupt.h"
#include "polrig/random.h"
#include "polrig/units.h"

namespace {
using namespace polrig;
double rad(double deg) { return deg * kPi / 180.0; }
double deg(double r) { return r * 180.0 / kPi; }

// WGS-84's defining and derived constants (NIMA TR8350.2, Table 3.1 and 3.3).
constexpr double kA = 6378137.0;
constexpr double kE2 = 6.69437999014e-3;       // first eccentricity squared
constexpr double kGammaE = 9.7803253359;       // normal gravity at the equator (m/s²)
constexpr double kSomiglianaK = 0.00193185265241;
constexpr double kF = 1.0 / 298.257223563;
constexpr double kM = 0.00344978650684;        // ω²a²b/GM
constexpr double kStandardG = 9.80665;

// Somigliana's closed form on the ellipsoid and TR8350.2's Eq. 4-3 above it.
double somigliana(double L, double h = 0) {
  const double s2 = std::sin(L) * std::sin(L);
  const double g0 = kGammaE * (1 + kSomiglianaK * s2) / std::sqrt(1 - kE2 * s2);
  return g0 * (1 - 2 / kA * (1 + kF + kM - 2 * kF * s2) * h + 3 * h * h / (kA * kA));
}

// Z21's site (spec §4.5) and the start of its run, 2019-09-18 16:14 Beijing time = 08:14 UTC.
const double kLat = rad(39.979), kLon = rad(116.339);
constexpr double kZ21StartUnix = 1568794440.0;

InsState state_of(const TruthSample& t) {
  InsState s;
  s.q_bn = Eigen::Quaterniond(t.C_bn);
  s.v_n = t.v_n;
  s.lat_rad = t.lat_rad;
  s.lon_rad = t.lon_rad;
  s.h_m = t.h_m;
  s.t_s = t.t_s;
  return s;
}

// The INS over the samples from `s`; states[k] is at the end of imu[k − 1] (states[0] = s).
std::vector<InsState> run_ins(InsState s, const std::vector<ImuSample>& imu,
                              const MechanizationOptions& options = {}) {
  std::vector<InsState> states{s};
  states.reserve(imu.size() + 1);
  for (std::size_t k = 0; k < imu.size(); ++k) {
    s = mechanize(s, imu[k == 0 ? 0 : k - 1], imu[k], options);
    states.push_back(s);
  }
  return states;
}

double attitude_error_rad(const Eigen::Matrix3d& C_true, const InsState& s) {
  return Eigen::AngleAxisd(C_true * s.C_bn().transpose()).angle();
}

double north_error_m(const TruthSample& t, const InsState& s) {
  return (s.lat_rad - t.lat_rad) * (earth_radii(t.lat_rad).R_M + t.h_m);
}
double east_error_m(const TruthSample& t, const InsState& s) {
  return (s.lon_rad - t.lon_rad) * (earth_radii(t.lat_rad).R_N + t.h_m) * std::cos(t.lat_rad);
}

TrajectorySpec static_spec(double duration_s, double rate_hz, Euler attitude = {}) {
  TrajectorySpec spec;
  spec.lat_rad = kLat;
  spec.lon_rad = kLon;
  spec.h_m = 50;
  spec.attitude = attitude;
  spec.imu_rate_hz = rate_hz;
  spec.segments = {{SegmentKind::Static, duration_s, 0}};
  return spec;
}

// A drive with every segment kind: accelerate, cruise, turn, climb and level off, turn back, brake.
TrajectorySpec moving_spec(double rate_hz) {
  TrajectorySpec spec;
  spec.lat_rad = kLat;
  spec.lon_rad = kLon;
  spec.h_m = 100;
  spec.attitude = {rad(1.0), rad(0.0), rad(30.0)};
  spec.imu_rate_hz = rate_hz;
  spec.segments = {{SegmentKind::Static, 10, 0},          {SegmentKind::Accelerate, 20, 1.0},
                   {SegmentKind::Accelerate, 30, 0.0},    {SegmentKind::Turn, 30, rad(3.0)},
                   {SegmentKind::Climb, 10, rad(0.5)},    {SegmentKind::Accelerate, 40, 0.0},
                   {SegmentKind::Climb, 10, rad(-0.5)},   {SegmentKind::Turn, 30, rad(-4.0)},
                   {SegmentKind::Accelerate, 40, -0.5},   {SegmentKind::Static, 20, 0}};
  return spec;
}

// The p-quantile of χ²(n)/n by Wilson–Hilferty (relative error < 1e-3 for n ≥ 10), z the normal quantile.
double chi2_mean_quantile(double n, double z) {
  const double a = 2.0 / (9.0 * n);
  const double c = 1 - a + z * std::sqrt(a);
  return c * c * c;
}

// ---------------------------------------------------------------------------------------------
// The Earth
// ---------------------------------------------------------------------------------------------

TEST(InsEarth, RadiiMatchWgs84TextbookValues) {
  // Equator: R_N = a, R_M = a(1 − e²); pole: both a/√(1 − e²) (TR8350.2: 6399593.6258 m).
  EXPECT_NEAR(earth_radii(0).R_N, kA, 1e-6);
  EXPECT_NEAR(earth_radii(0).R_M, kA * (1 - kE2), 1e-3);
  EXPECT_NEAR(earth_radii(kPi / 2).R_N, 6399593.6258, 1e-3);
  EXPECT_NEAR(earth_radii(kPi / 2).R_M, 6399593.6258, 1e-3);
  // At the Z21 site, the Gaussian mean radius √(R_M R_N) the Schuler tests use.
  const EarthRadii r = earth_radii(kLat);
  const double w = std::sqrt(1 - kE2 * std::pow(std::sin(kLat), 2));
  EXPECT_NEAR(r.R_N, kA / w, 1e-3);
  EXPECT_NEAR(r.R_M, kA * (1 - kE2) / (w * w * w), 1e-3);
}

TEST(InsEarth, NormalGravityMatchesSomigliana) {
  // GeographicLib's exact normal gravity against the closed form: 2e-6 m/s² is the spec's bound
  // (GRS80-series formulas differ by ~1.4e-6); TR8350.2's height series is good to ~1e-8 at 2 km.
  for (double L_deg : {0.0, 30.0, 39.979, 60.0, 90.0})
    for (double h : {0.0, 500.0, 2000.0}) {
      EXPECT_NEAR(normal_gravity(rad(L_deg), h), somigliana(rad(L_deg), h), 2e-6) << L_deg << "° " << h << " m";
      EXPECT_EQ(gravity_n(rad(L_deg), h).head<2>(), Eigen::Vector2d::Zero());
    }
  EXPECT_NEAR(normal_gravity(0, 0), 9.7803253359, 1e-9);         // GeographicLib's equatorial gravity
  EXPECT_NEAR(normal_gravity(kPi / 2, 0), 9.8321849379, 1e-9);   // and polar
  // The gradient: ∂g/∂L of the closed form by a 5-point stencil, and the free-air −3.086e-6 /s²
  // (TR8350.2: −2γ/a·(1 + f + m − 2f sin²L) = −3.083e-6 at 40°; 1e-8 covers the stencils).
  const GravityGradient gg = gravity_gradient(kLat, 0);
  const double d = 1e-3;
  const double dg_dL = (-somigliana(kLat + 2 * d) + 8 * somigliana(kLat + d) - 8 * somigliana(kLat - d) +
                        somigliana(kLat - 2 * d)) / (12 * d);
  EXPECT_NEAR(gg.dg_dL, dg_dL, 1e-8);
  EXPECT_NEAR(gg.dg_dh, (somigliana(kLat, 10) - somigliana(kLat, -10)) / 20, 1e-10);
  EXPECT_NEAR(gg.dg_dh, -3.086e-6, 0.01e-6);
}

// normal_gravity's height series against GeographicLib's exact ellipsoidal gravity (Gravity(),
// an independent route: the ellipsoidal harmonic, not a series), every latitude: exact on the
// ellipsoid (both are Somigliana's there), and the series' error growing ≤ 1.1e-10 m/s² per metre of
// height, 7e-7 m/s² at 10 km — the spec's class (§4.7: compare gravity to ≥ 2e-6) and 0.07 µg
// beside an accelerometer's 50 µg.
TEST(InsEarth, NormalGravitysHeightSeriesMatchesGeographicLibsExactGravity) {
  const auto worst_at = [](double h) {
    double worst = 0;
    for (double L_deg = -90; L_deg <= 90; L_deg += 7.5) {
      double gy = 0, gz = 0;
      GeographicLib::NormalGravity::WGS84().Gravity(L_deg, h, gy, gz);
      worst = std::max(worst, std::abs(normal_gravity(rad(L_deg), h) + gz));
    }
    return worst;
  };
  std::printf("normal gravity: worst |series − exact| %.3g (0 m), %.3g (50 m), %.3g (10 km) m/s²\n", worst_at(0),
              worst_at(50), worst_at(10000));
  EXPECT_LT(worst_at(0), 1e-13);
  for (double h : {-500.0, 50.0, 2000.0, 10000.0}) EXPECT_LT(worst_at(h), 1.2e-10 * std::abs(h)) << h;
}

TEST(InsEarth, EarthRateIsWgs84sAlongTheLocalNorthAndUp) {
  EXPECT_DOUBLE_EQ(kEarthRate, 7.292115e-5);
  const Eigen::Vector3d w = omega_ie_n(kLat);
  EXPECT_NEAR(w.norm(), 7.292115e-5, 1e-18);
  EXPECT_NEAR(deg(std::atan2(w.z(), w.y())), 39.979, 1e-12);  // the axis lies at elevation L in the meridian
  EXPECT_EQ(w.x(), 0.0);
  // Moving north at v over the meridian turns ENU about −east at v/(R_M + h): the frame's
  // rate of change of latitude (a 10 m/s north drive at 1000 m).
  const Eigen::Vector3d w_en = omega_en_n({0, 10, 0}, kLat, 1000);
  EXPECT_NEAR(w_en.x(), -10 / (kA * (1 - kE2) / std::pow(1 - kE2 * std::pow(std::sin(kLat), 2), 1.5) + 1000), 1e-15);
  EXPECT_EQ(w_en.y(), 0.0);
}

// ---------------------------------------------------------------------------------------------
// Attitude
// ---------------------------------------------------------------------------------------------

TEST(InsAttitude, EulerSensesAndRoundTrip) {
  // Yaw 30°: the forward axis points 30° clockwise from north.
  const Eigen::Matrix3d C = C_bn_from_euler({0, 0, rad(30)});
  EXPECT_TRUE(C.col(1).isApprox(Eigen::Vector3d(0.5, std::sqrt(3) / 2, 0), 1e-15));
  // Pitch 10°: the nose goes up; roll 10°: the right wing goes down.
  EXPECT_NEAR(C_bn_from_euler({0, rad(10), 0}).col(1).z(), std::sin(rad(10)), 1e-15);
  EXPECT_NEAR(C_bn_from_euler({rad(10), 0, 0}).col(0).z(), -std::sin(rad(10)), 1e-15);
  // Spec §0: turn the device 10° anticlockwise seen from above; the heading falls by 10°.
  const Euler e{rad(3), rad(-4), rad(100)};
  const Eigen::Matrix3d turned = Eigen::AngleAxisd(rad(10), Eigen::Vector3d::UnitZ()) * C_bn_from_euler(e);
  EXPECT_NEAR(deg(euler_from_C_bn(turned).yaw_rad), 90.0, 1e-12);
  const Euler back = euler_from_C_bn(C_bn_from_euler(e));
  EXPECT_NEAR(back.roll_rad, e.roll_rad, 1e-15);
  EXPECT_NEAR(back.pitch_rad, e.pitch_rad, 1e-15);
  EXPECT_NEAR(back.yaw_rad, e.yaw_rad, 1e-14);
  // The quaternion of a rotation vector against Eigen's AngleAxis (and at a tiny angle, its series).
  const Eigen::Vector3d phi(0.3, -0.2, 0.5);
  EXPECT_TRUE(quaternion_from_rotation_vector(phi).toRotationMatrix().isApprox(
      Eigen::AngleAxisd(phi.norm(), phi.normalized()).toRotationMatrix(), 1e-15));
  const Eigen::Vector3d tiny(3e-6, -1e-6, 2e-6);
  EXPECT_TRUE(quaternion_from_rotation_vector(tiny).toRotationMatrix().isApprox(
      Eigen::AngleAxisd(tiny.norm(), tiny.normalized()).toRotationMatrix(), 1e-15));
}

// ---------------------------------------------------------------------------------------------
// The IMU and its errors
// ---------------------------------------------------------------------------------------------

std::vector<ImuSample> zero_samples(std::size_t n, double dt) {
  std::vector<ImuSample> s(n);
  for (std::size_t k = 0; k < n; ++k) s[k].t_s = static_cast<double>(k + 1) * dt;
  return s;
}

TEST(InsImu, Z21DefaultsAreTable1InSi) {
  const ImuErrorSpec z = z21_imu_errors();
  // The filter's default noise is the same IMU's: white noise only (Z21's biases are constants).
  const ErrorModelNoise n = FilterSettings{}.noise;
  EXPECT_EQ(n.arw, z.gyro.white_noise);
  EXPECT_EQ(n.vrw, z.accel.white_noise);
  EXPECT_TRUE(std::isinf(n.gyro_tau_s.x()));
  EXPECT_NEAR(FilterSettings{}.sigma_H_rad, rad(0.1), 1e-18);
  EXPECT_NEAR(z.gyro.turn_on_bias_sigma.x(), 2.4240684e-5, 1e-12);  // 5°/h in rad/s
  EXPECT_NEAR(z.gyro.white_noise.y(), 1.4544410e-4, 1e-11);         // 0.5°/√h in rad/√s
  EXPECT_NEAR(z.accel.turn_on_bias_sigma.z(), 4.903325e-4, 1e-12);  // 50 µg in m/s²
  EXPECT_NEAR(z.accel.white_noise.x(), 2.4516625e-4, 1e-12);        // 25 µg/√Hz in m/s/√s
}

TEST(InsImu, GaussMarkovStepIsExact) {
  // Δt/τ = 0.1: the exact step gives ρ = e^{−0.1} = 0.904837 and variance σ²; an Euler step
  // (1 − Δt/τ, σ√(2Δt/τ)) would give ρ = 0.9 and 1.053 σ². With N = 2e5 samples the AR(1)
  // estimates have sd(ρ̂) ≈ √((1 − ρ²)/N) = 0.00095 and sd(σ̂²)/σ² ≈ √(2(1 + ρ²)/((1 − ρ²)N)) = 1.0 %:
  // tolerances 4 sd, which the Euler step's errors (5 sd each) would fail.
  const double sigma = 2e-5, tau = 10, dt = 1;
  const std::size_t n = 200000;
  ImuErrorSpec spec;
  spec.rate_hz = 1 / dt;
  spec.gyro.bias_instability.setConstant(sigma);
  spec.gyro.correlation_time_s.setConstant(tau);
  const CorruptedImu c = corrupt_imu(zero_samples(n, dt), spec, 7);
  for (int axis = 0; axis < 3; ++axis) {
    double s2 = 0, s11 = 0, m = 0;
    for (std::size_t k = 0; k < n; ++k) m += c.gyro_bias[k][axis];
    m /= n;
    for (std::size_t k = 0; k < n; ++k) {
      const double b = c.gyro_bias[k][axis] - m;
      s2 += b * b;
      if (k + 1 < n) s11 += b * (c.gyro_bias[k + 1][axis] - m);
    }
    EXPECT_NEAR(s2 / n / (sigma * sigma), 1.0, 0.04) << axis;
    EXPECT_NEAR(s11 / s2, std::exp(-dt / tau), 0.0038) << axis;
  }
  // The increments carry the bias times Δt and nothing else here.
  EXPECT_DOUBLE_EQ(c.samples[5].dtheta.y(), c.gyro_bias[5].y() * dt);
  // The error model takes the same process: ε̇ = −ε/τ with Q_c = 2σ²/τ.
  const ErrorModelNoise noise = error_model_noise(spec);
  EXPECT_EQ(noise.gyro_tau_s, Eigen::Vector3d::Constant(tau));
  EXPECT_DOUBLE_EQ(process_noise_density(InsState{}, noise)(kGyroBias, kGyroBias), 2 * sigma * sigma / tau);
  EXPECT_TRUE(std::isinf(noise.accel_tau_s.z()));
}

TEST(InsImu, CorruptionIsCounterBasedAndDeterministic) {
  ImuErrorSpec spec = z21_imu_errors();
  spec.gyro.bias_instability.setConstant(1e-5);
  spec.accel.random_walk.setConstant(1e-5);
  spec.gyro.scale_factor_sigma.setConstant(1e-3);
  spec.accel.misalignment_sigma_rad = 1e-3;
  const std::vector<ImuSample> ideal = zero_samples(1000, 0.01);
  const CorruptedImu a = corrupt_imu(ideal, spec, 42), b = corrupt_imu(ideal, spec, 42);
  const CorruptedImu prefix = corrupt_imu(std::vector<ImuSample>(ideal.begin(), ideal.begin() + 10), spec, 42);
  const CorruptedImu other = corrupt_imu(ideal, spec, 43);
  for (std::size_t k = 0; k < 10; ++k) {
    EXPECT_EQ(a.samples[k].dtheta, b.samples[k].dtheta);
    EXPECT_EQ(a.samples[k].dv, prefix.samples[k].dv);  // a sample's noise depends on its index only
    EXPECT_NE(a.samples[k].dv, other.samples[k].dv);
  }
  EXPECT_EQ(a.drawn.gyro_bias, b.drawn.gyro_bias);
  EXPECT_NE(a.drawn.gyro_bias, other.drawn.gyro_bias);
  EXPECT_EQ(a.drawn.accel_scale_misalignment.diagonal(), Eigen::Vector3d::Zero());  // no accel scale set
  EXPECT_NE(a.drawn.accel_scale_misalignment(0, 1), 0.0);
  EXPECT_THROW(corrupt_imu({{0.0}, {0.0}}, spec, 1), std::invalid_argument);  // a zero interval
}

TEST(InsImu, WhiteNoiseOfAnIncrementIsDensityTimesRootDt) {
  // σ(dθ) = N√Δt; over 3·1e5 deviates the sample variance's sd is √(2/n) = 0.26 %: 1.5 % is ~6 sd.
  ImuErrorSpec spec;
  spec.rate_hz = 100;
  spec.gyro.white_noise.setConstant(rad(0.5) / 60);
  const std::size_t n = 100000;
  const CorruptedImu c = corrupt_imu(zero_samples(n, 0.01), spec, 3);
  double s2 = 0;
  for (const ImuSample& s : c.samples) s2 += s.dtheta.squaredNorm();
  EXPECT_NEAR(std::sqrt(s2 / (3.0 * n)) / (rad(0.5) / 60 * 0.1), 1.0, 0.015);
}

// ---------------------------------------------------------------------------------------------
// The trajectory and its ideal IMU
// ---------------------------------------------------------------------------------------------

TEST(InsTrajectory, StaticIncrementsAreTheClosedForm) {
  // ω_ib^b = C_n^b ω_ie^n and f^b = −C_n^b g^n, with g from Somigliana (2e-6 m/s² · 0.1 s).
  const Euler e{rad(2), rad(-3), rad(120)};
  const Trajectory tr = generate_trajectory(static_spec(1, 10, e));
  ASSERT_EQ(tr.imu.size(), 10u);
  ASSERT_EQ(tr.truth.size(), 11u);
  const Eigen::Matrix3d C_nb = C_bn_from_euler(e).transpose();
  const Eigen::Vector3d w(0, kEarthRate * std::cos(kLat), kEarthRate * std::sin(kLat));
  for (const ImuSample& s : tr.imu) {
    EXPECT_LT((s.dtheta - C_nb * w * 0.1).norm(), 1e-18);
    EXPECT_LT((s.dv - C_nb * Eigen::Vector3d(0, 0, somigliana(kLat, 50)) * 0.1).norm(), 2e-7);
  }
  EXPECT_EQ(tr.truth.back().lat_rad, kLat);
  EXPECT_NEAR(tr.truth.back().t_s, 1.0, 1e-12);
}

TEST(InsTrajectory, RefusesSegmentsOffTheSampleGridAndStaticWhileMoving) {
  TrajectorySpec spec = static_spec(1.05, 10);
  EXPECT_THROW(generate_trajectory(spec), std::invalid_argument);
  spec = static_spec(1, 10);
  spec.speed_mps = 3;
  EXPECT_THROW(generate_trajectory(spec), std::invalid_argument);
  spec.speed_mps = 0;
  spec.substeps = 3;
  EXPECT_THROW(generate_trajectory(spec), std::invalid_argument);
}

TEST(InsTrajectory, MovingTruthFollowsItsSegments) {
  // 20 s at 1 m/s² then a 90° turn at 3°/s: 20 m/s heading 120°; the climb lifts the nose 5°.
  const Trajectory tr = generate_trajectory(moving_spec(50));
  const auto at = [&](double t) { return tr.truth[static_cast<std::size_t>(std::lround(t * 50))]; };
  EXPECT_NEAR(at(30).v_n.norm(), 20, 1e-12);
  EXPECT_NEAR(deg(at(90).euler.yaw_rad), 120, 1e-9);
  EXPECT_NEAR(deg(at(100).euler.pitch_rad), 5, 1e-9);
  EXPECT_NEAR(at(100).v_n.z(), 20 * std::sin(rad(5)), 1e-9);
  EXPECT_NEAR(deg(at(100).euler.roll_rad), 1, 1e-9);
  EXPECT_NEAR(at(240).v_n.norm(), 0, 1e-9);
  // Distance north over the 30 s cruise at heading 30°: 20·cos 30°·30 m.
  EXPECT_NEAR((at(60).lat_rad - at(30).lat_rad) * (earth_radii(kLat).R_M + 100), 20 * std::cos(rad(30)) * 30, 0.05);
}

// ---------------------------------------------------------------------------------------------
// The mechanization
// ---------------------------------------------------------------------------------------------

TEST(InsMechanization, IdealImuHeldStaticForAnHourStaysPut) {
  // pyins's bar (spec §4.7) at 10 Hz: the algorithm is exact for a static IMU (the body and the
  // n-frame turn together; the rotation and n-frame corrections cancel), so what is left is
  // rounding, amplified only by the vertical channel's e^{t/570 s}.
  const Trajectory tr = generate_trajectory(static_spec(3600, 10, {rad(1), rad(-2), rad(30)}));
  const std::vector<InsState> s = run_ins(state_of(tr.truth[0]), tr.imu);
  double worst_m = 0, worst_deg = 0, worst_v = 0;
  for (std::size_t k = 0; k < s.size(); k += 100) {
    const TruthSample& t = tr.truth[k];
    worst_m = std::max({worst_m, std::abs(north_error_m(t, s[k])), std::abs(east_error_m(t, s[k])),
                        std::abs(s[k].h_m - t.h_m)});
    worst_deg = std::max(worst_deg, deg(attitude_error_rad(t.C_bn, s[k])));
    worst_v = std::max(worst_v, s[k].v_n.norm());
  }
  EXPECT_LT(worst_m, 0.01);
  EXPECT_LT(worst_deg, 1e-6);
  EXPECT_LT(worst_v, 1e-6);
  std::printf("static hour: position %.3g m, attitude %.3g°, velocity %.3g m/s\n", worst_m, worst_deg, worst_v);
}

// pyins's integration tests (pyins/tests/test_strapdown.py, run_integration_test): the largest
// |difference| from the truth over every epoch, in pyins's columns and units.
struct PyinsDifference {
  double north_m = 0, east_m = 0, down_m = 0;
  double v_n = 0, v_e = 0, v_d = 0;  // m/s
  double roll_deg = 0, pitch_deg = 0, heading_deg = 0;
};

PyinsDifference pyins_difference(const Trajectory& tr, const std::vector<InsState>& s) {
  PyinsDifference d;
  const auto wrap_deg = [](double a) { return std::abs(deg(std::remainder(a, 2 * kPi))); };
  for (std::size_t k = 0; k < s.size(); ++k) {
    const TruthSample& t = tr.truth[k];
    const Euler e = euler_from_C_bn(s[k].C_bn());
    d.north_m = std::max(d.north_m, std::abs(north_error_m(t, s[k])));
    d.east_m = std::max(d.east_m, std::abs(east_error_m(t, s[k])));
    d.down_m = std::max(d.down_m, std::abs(s[k].h_m - t.h_m));
    d.v_n = std::max(d.v_n, std::abs(s[k].v_n.y() - t.v_n.y()));
    d.v_e = std::max(d.v_e, std::abs(s[k].v_n.x() - t.v_n.x()));
    d.v_d = std::max(d.v_d, std::abs(s[k].v_n.z() - t.v_n.z()));
    d.roll_deg = std::max(d.roll_deg, wrap_deg(e.roll_rad - t.euler.roll_rad));
    d.pitch_deg = std::max(d.pitch_deg, wrap_deg(e.pitch_rad - t.euler.pitch_rad));
    d.heading_deg = std::max(d.heading_deg, wrap_deg(e.yaw_rad - t.euler.yaw_rad));
  }
  std::printf("pyins's columns: north %.3g east %.3g down %.3g m; VN %.3g VE %.3g VD %.3g m/s; "
              "roll %.3g pitch %.3g heading %.3g deg\n", d.north_m, d.east_m, d.down_m, d.v_n, d.v_e, d.v_d,
              d.roll_deg, d.pitch_deg, d.heading_deg);
  return d;
}

void expect_within(const PyinsDifference& d, const PyinsDifference& bound) {
  EXPECT_LT(d.north_m, bound.north_m);
  EXPECT_LT(d.east_m, bound.east_m);
  EXPECT_LT(d.down_m, bound.down_m);
  EXPECT_LT(d.v_n, bound.v_n);
  EXPECT_LT(d.v_e, bound.v_e);
  EXPECT_LT(d.v_d, bound.v_d);
  EXPECT_LT(d.roll_deg, bound.roll_deg);
  EXPECT_LT(d.pitch_deg, bound.pitch_deg);
  EXPECT_LT(d.heading_deg, bound.heading_deg);
}

TEST(InsMechanization, PyinsStationaryScenarioWithItsThresholds) {
  // test_integrate_stationary: an hour at 10 Hz at 55° N 37° E, 150 m, roll −5°, pitch 10°, heading
  // 110°, the height integrated and held (pyins's with_altitude True/False); its thresholds.
  TrajectorySpec spec;
  spec.lat_rad = rad(55);
  spec.lon_rad = rad(37);
  spec.h_m = 150;
  spec.attitude = {rad(-5), rad(10), rad(110)};
  spec.imu_rate_hz = 10;
  spec.segments = {{SegmentKind::Static, 3600, 0}};
  const Trajectory tr = generate_trajectory(spec);
  const PyinsDifference pyins_bound{1e-3, 1e-3, 1e-2, 1e-6, 1e-6, 1e-5, 1e-8, 1e-8, 1e-8};
  for (const bool with_altitude : {true, false}) {
    SCOPED_TRACE(with_altitude ? "height integrated" : "height held");
    MechanizationOptions options;
    if (!with_altitude) options.hold_height_m = spec.h_m;
    expect_within(pyins_difference(tr, run_ins(state_of(tr.truth[0]), tr.imu, options)), pyins_bound);
  }
}

TEST(InsMechanization, PyinsSineVelocityScenarioWithItsIncrementThresholds) {
  // test_integrate_sine_velocity, sensor_type "increment" (polrig's IMU gives increments): an hour
  // at 100 Hz from 55° N 37° E, 1500 m, V_NED = (5, −3, 0.2) + 1·sin(2π t/60 s + (0°, 90°, 0°)) m/s,
  // the height integrated; its thresholds. In ENU: v_E phase 90°, v_U = −0.2 − sin(…) = −0.2 +
  // sin(… + 180°).
  SineVelocitySpec spec;
  spec.lat_rad = rad(55);
  spec.lon_rad = rad(37);
  spec.h_m = 1500;
  spec.v_mean_enu = {-3, 5, -0.2};
  spec.amplitude_enu = {1, 1, 1};
  spec.phase_rad = {rad(90), 0, kPi};
  spec.period_s = 60;
  spec.duration_s = 3600;
  spec.imu_rate_hz = 100;
  const Trajectory tr = generate_sine_velocity_trajectory(spec);
  // The generator itself: the truth's velocity is the formula's (NED (5, −3, 0.2) + … at t = 15 s:
  // sin(90°) = 1 for north and down, sin(180°) = 0 for east).
  const TruthSample& q = tr.truth[1500];
  EXPECT_NEAR(q.v_n.y(), 6, 1e-12);
  EXPECT_NEAR(q.v_n.x(), -3, 1e-12);
  EXPECT_NEAR(q.v_n.z(), -1.2, 1e-12);
  EXPECT_NEAR(q.euler.roll_rad, 0, 1e-12);
  EXPECT_NEAR(deg(q.euler.yaw_rad), 360 + deg(std::atan2(-3, 6)), 1e-9);
  const PyinsDifference pyins_bound{0.1, 0.1, 3, 1e-3, 1e-3, 1e-2, 1e-6, 1e-6, 1e-5};
  expect_within(pyins_difference(tr, run_ins(state_of(tr.truth[0]), tr.imu)), pyins_bound);
}

TEST(InsTrajectory, SineVelocityRefusesAnUndefinedHeadingAndOffGridDurations) {
  SineVelocitySpec spec;
  spec.v_mean_enu = {1, 0, 0};
  spec.amplitude_enu = {1, 0.5, 0};
  spec.duration_s = 10;
  EXPECT_THROW(generate_sine_velocity_trajectory(spec), std::invalid_argument);
  spec.amplitude_enu = {0.5, 0.5, 0};
  spec.duration_s = 10.005;
  EXPECT_THROW(generate_sine_velocity_trajectory(spec), std::invalid_argument);
  spec.duration_s = 10;
  EXPECT_EQ(generate_sine_velocity_trajectory(spec).imu.size(), 1000u);
}

TEST(InsMechanization, IdealImuOnAMovingTrajectoryReproducesTheTruth) {
  // 240 s of accelerating, turning and climbing at 100 Hz. The two-sample algorithm's residuals:
  // in the 3°/s turn at 20 m/s (f ≈ 1 m/s² rotating with the body at ω Δt = 5e-4) the sculling
  // error is ~(ωΔt)²·f·Δt ≈ 3e-9 m/s a step, ~1e-5 m/s over the turns' 6000 steps and ~1 mm of
  // position after them; at a segment boundary the coning term dθ₋ × dθ/12 pairs rates about
  // different axes once, ≈ (5e-4)(9e-5)/12 rad = 2e-7° each. Bounds: 2e-5 m/s, 5 mm, 1e-6°.
  const Trajectory tr = generate_trajectory(moving_spec(100));
  const std::vector<InsState> s = run_ins(state_of(tr.truth[0]), tr.imu);
  double worst_m = 0, worst_deg = 0, worst_v = 0;
  for (std::size_t k = 0; k < s.size(); ++k) {
    const TruthSample& t = tr.truth[k];
    worst_m = std::max({worst_m, std::abs(north_error_m(t, s[k])), std::abs(east_error_m(t, s[k])),
                        std::abs(s[k].h_m - t.h_m)});
    worst_deg = std::max(worst_deg, deg(attitude_error_rad(t.C_bn, s[k])));
    worst_v = std::max(worst_v, (s[k].v_n - t.v_n).norm());
  }
  std::printf("moving: position %.3g m, attitude %.3g°, velocity %.3g m/s\n", worst_m, worst_deg, worst_v);
  EXPECT_LT(worst_m, 5e-3);
  EXPECT_LT(worst_deg, 1e-6);
  EXPECT_LT(worst_v, 2e-5);
}

TEST(InsMechanization, AccelerometerBiasDrivesTheSchulerOscillation) {
  // Spec §4.7 (Titterton & Weston ch. 12): a north accelerometer bias ∇ (50 µg, yaw 0 so body y is
  // north), height held, gives δN = (R∇/g)(1 − cos ω_s t), ω_s = √(g/R), R = √(R_M R_N):
  // T_s = 84.4 min and a peak of 2R∇/g ≈ 637 m. The Earth's rate couples north and east (the
  // Foucault turn, 2π/(Ω sin L) = 37.3 h, rotates the swing by 13.6° per period), which shifts
  // the first return by < 0.5 % and lowers the peak by < 1.5 %: the tolerances.
  const double rate = 10, nabla = 50e-6 * kStandardG;
  const Trajectory tr = generate_trajectory(static_spec(6000, rate));
  ImuErrorSpec spec;
  spec.rate_hz = rate;
  spec.accel.bias = Eigen::Vector3d(0, nabla, 0);
  const CorruptedImu imu = corrupt_imu(tr.imu, spec, 1);
  MechanizationOptions hold;
  hold.hold_height_m = 50;
  const std::vector<InsState> s = run_ins(state_of(tr.truth[0]), imu.samples, hold);
  std::vector<double> dN(s.size());
  for (std::size_t k = 0; k < s.size(); ++k) dN[k] = north_error_m(tr.truth[k], s[k]);

  const EarthRadii r = earth_radii(kLat);
  const double R = std::sqrt(r.R_M * r.R_N), g = somigliana(kLat, 50);
  const double T_s = 2 * kPi * std::sqrt(R / g);
  EXPECT_NEAR(T_s / 60, 84.4, 0.06);  // the spec's 84.4 is R = 6371 km, g = 9.80665 (84.41); the site's R, g: 84.45
  // The first return: the minimum of δN between T_s/2 and 1.15 T_s.
  const auto lo = static_cast<std::size_t>(0.5 * T_s * rate), hi = static_cast<std::size_t>(1.15 * T_s * rate);
  const auto it = std::min_element(dN.begin() + lo, dN.begin() + hi);
  const double T_measured = static_cast<double>(it - dN.begin()) / rate;
  const double peak = *std::max_element(dN.begin(), dN.begin() + hi);
  std::printf("Schuler: period %.2f min (closed form %.2f), peak %.1f m (2R∇/g %.1f m)\n", T_measured / 60,
              T_s / 60, peak, 2 * R * nabla / g);
  EXPECT_NEAR(T_measured / T_s, 1.0, 0.005);
  EXPECT_NEAR(peak / (2 * R * nabla / g), 1.0, 0.015);
  EXPECT_NEAR(R * nabla / g, 319, 1.0);  // the spec's amplitude
  // Short times: ½∇t², to (ω_s t)²/12 = 0.05 % at 60 s; 0.2 %.
  EXPECT_NEAR(dN[static_cast<std::size_t>(60 * rate)] / (0.5 * nabla * 3600), 1.0, 0.002);
}

TEST(InsMechanization, EastGyroBiasDriftsTheLatitudeAsZ21sSins) {
  // Spec §4.7: ε_E = 5°/h alone, height held: δL = −ε_E (t − sin(ω_s t)/ω_s) = −0.551° at 1200 s at
  // 39.979° N (Z21's SINS: −0.568°), and −g ε t³/6 (in metres of north) at short times. The Earth's
  // rate couples in terms of relative size (Ω t)² ≈ 1 % at 1200 s: the tolerance 1.5 %; at 120 s the
  // series' next term (ω_s t)²/20 = 0.1 %: 0.5 %.
  const double rate = 20, eps = rad(5) / 3600;
  const Trajectory tr = generate_trajectory(static_spec(1200, rate));
  ImuErrorSpec spec;
  spec.rate_hz = rate;
  spec.gyro.bias = Eigen::Vector3d(eps, 0, 0);  // yaw 0: body x is east
  const CorruptedImu imu = corrupt_imu(tr.imu, spec, 1);
  MechanizationOptions hold;
  hold.hold_height_m = 50;
  const std::vector<InsState> s = run_ins(state_of(tr.truth[0]), imu.samples, hold);
  const EarthRadii r = earth_radii(kLat);
  const double w_s = std::sqrt(somigliana(kLat, 50) / std::sqrt(r.R_M * r.R_N));
  const double t = 1200;
  const double dL_closed = -eps * (t - std::sin(w_s * t) / w_s);
  const double dL = s.back().lat_rad - tr.truth.back().lat_rad;
  std::printf("latitude drift over 1200 s: %.4f° (closed form %.4f°, Z21 SINS −0.568°)\n", deg(dL), deg(dL_closed));
  EXPECT_NEAR(deg(dL_closed), -0.551, 0.001);  // the spec's rounding of R and g
  EXPECT_NEAR(dL / dL_closed, 1.0, 0.015);
  const std::size_t k120 = static_cast<std::size_t>(120 * rate);
  EXPECT_NEAR(north_error_m(tr.truth[k120], s[k120]) / (-somigliana(kLat, 50) * eps * std::pow(120.0, 3) / 6), 1.0, 0.005);
}

// ---------------------------------------------------------------------------------------------
// The error model
// ---------------------------------------------------------------------------------------------

InsState static_state(double yaw_deg = 0) {
  InsState s;
  s.q_bn = Eigen::Quaterniond(C_bn_from_euler({0, 0, rad(yaw_deg)}));
  s.lat_rad = kLat;
  s.lon_rad = kLon;
  s.h_m = 50;
  return s;
}

TEST(InsErrorModel, AlignmentEquilibriaAndTheHeadingFloor) {
  // Spec §4.7: at φ_E = −∇_N/g, φ_N = ∇_E/g, φ_U = −ε_E/(Ω cos L) + (∇_E/g) tan L the level
  // velocity errors and φ_E stand still (static, level, yaw 0 so body = ENU). A 5°/h east gyro
  // bias puts the heading 24.9° off.
  const InsState s = static_state();
  const double g = somigliana(kLat, 50);
  const Matrix15 F = error_dynamics(s, {0, 0, g});
  const Eigen::Vector3d eps(rad(5) / 3600, rad(1) / 3600, 0), nabla(40e-6 * g, -30e-6 * g, 0);
  Vector15 x = Vector15::Zero();
  x.segment<3>(kPhi) << -nabla.y() / g, nabla.x() / g,
      -eps.x() / (kEarthRate * std::cos(kLat)) + nabla.x() / g * std::tan(kLat);
  x.segment<3>(kGyroBias) = eps;
  x.segment<3>(kAccelBias) = nabla;
  const Vector15 dx = F * x;
  EXPECT_LT(std::abs(dx[kDV]), 1e-12 * g);
  EXPECT_LT(std::abs(dx[kDV + 1]), 1e-12 * g);
  EXPECT_LT(std::abs(dx[kPhi]), 1e-12 * kEarthRate);
  // Perturbing φ_U by 1e-3 rad moves φ̇_E by Ω cos L·1e-3: the equilibrium is not a zero of F.
  Vector15 y = x;
  y[kPhi + 2] += 1e-3;
  EXPECT_NEAR((F * y)[kPhi], -kEarthRate * std::cos(kLat) * 1e-3, 1e-15);
  // φ_U that cancels a 5°/h east bias in φ̇_E, from F alone: −F(φ_E, ε_x)·ε/F(φ_E, φ_U).
  const double phi_U = -F(kPhi, kGyroBias) * (rad(5) / 3600) / F(kPhi, kPhi + 2);
  EXPECT_NEAR(std::abs(deg(phi_U)), 24.9, 0.05);
}

TEST(InsErrorModel, FMatchesTheTermsSpec44OmitsAndThoseItPrints) {
  // A vehicle moving east and north: spot entries against spec §4.4's equations written out here.
  InsState s = static_state(30);
  s.v_n << 15, 8, 0.5;
  s.h_m = 300;
  const Eigen::Vector3d f_n(0.3, -0.2, 9.9);
  const Matrix15 F = error_dynamics(s, f_n);
  const EarthRadii r = earth_radii(kLat);
  const double RMh = r.R_M + 300, RNh = r.R_N + 300, tanL = std::tan(kLat), secL = 1 / std::cos(kLat);
  // δλ̇ = δV_E sec L/(R_N + h) + V_E sec L tan L δL/(R_N + h) − V_E sec L δh/(R_N + h)².
  EXPECT_DOUBLE_EQ(F(kDLon, kDV), secL / RNh);
  EXPECT_NEAR(F(kDLon, kDLat), 15 * secL * tanL / RNh, 1e-20);
  EXPECT_NEAR(F(kDLon, kDh), -15 * secL / (RNh * RNh), 1e-24);
  EXPECT_NEAR(F(kDLat, kDh), -8 / (RMh * RMh), 1e-24);
  // φ̇_U's δL term: Ω cos L + V_E sec²L/(R_N + h) (δω_ie and δω_en).
  EXPECT_NEAR(F(kPhi + 2, kDLat), kEarthRate * std::cos(kLat) + 15 * secL * secL / RNh, 1e-18);
  // δV̇ = f^n × φ: the E row's φ_N entry is −f_U.
  EXPECT_DOUBLE_EQ(F(kDV, kPhi + 1), -9.9);
  // The gravity gradient in the vertical channel: +3.086e-6 δh (PSINS etm.m), plus V×δω_en's part.
  const double V_cross = (Eigen::Vector3d(15, 8, 0.5).cross(Eigen::Vector3d(8 / (RMh * RMh), -15 / (RNh * RNh),
                                                                            -15 * tanL / (RNh * RNh))))
                             .z();
  EXPECT_NEAR(F(kDV + 2, kDh), 3.086e-6 + V_cross, 0.01e-6);
  // Biases enter through C_b^n.
  EXPECT_TRUE((F.block<3, 3>(kDV, kAccelBias).isApprox(s.C_bn(), 1e-15)));
  EXPECT_TRUE((F.block<3, 3>(kPhi, kGyroBias).isApprox(-s.C_bn(), 1e-15)));
}

TEST(InsErrorModel, LinearModelFollowsTheNonlinearMechanization) {
  // Spec §4.7 (pyins: within 12 %): small initial errors and biases on the moving trajectory,
  // the nonlinear INS against the truth, beside x propagated by Φ = I + FΔt with F along the
  // truth. Second-order terms (φ·φ g with φ ≤ 3′ = 9e-4 rad, F evaluated at the truth instead of
  // the INS) are ~1e-3 of the first: each error component agrees within 1 % of its largest value
  // over the run (measured: 0.3 % at most, in δV_N).
  const double rate = 100;
  const Trajectory tr = generate_trajectory(moving_spec(rate));
  Vector15 x0 = Vector15::Zero();
  x0.segment<3>(kPhi) << rad(20.0 / 3600), rad(-15.0 / 3600), rad(3.0 / 60);
  x0.segment<3>(kDV) << 0.02, -0.01, 0.005;
  x0.segment<3>(kGyroBias) << rad(0.5) / 3600, rad(-0.3) / 3600, rad(1.0) / 3600;
  x0.segment<3>(kAccelBias) << 100e-6 * kStandardG, -80e-6 * kStandardG, 50e-6 * kStandardG;

  ImuErrorSpec spec;
  spec.rate_hz = rate;
  spec.gyro.bias = x0.segment<3>(kGyroBias);
  spec.accel.bias = x0.segment<3>(kAccelBias);
  const CorruptedImu imu = corrupt_imu(tr.imu, spec, 1);
  InsState start = state_of(tr.truth[0]);
  start.q_bn = (quaternion_from_rotation_vector(-x0.segment<3>(kPhi)) * start.q_bn).normalized();
  start.v_n += x0.segment<3>(kDV);
  const std::vector<InsState> s = run_ins(start, imu.samples);

  Vector15 x = x0;
  std::vector<Eigen::Matrix<double, 9, 1>> lin, nl;
  for (std::size_t k = 0; k < tr.imu.size(); ++k) {
    const InsState truth = state_of(tr.truth[k]);
    const Eigen::Vector3d f_n = tr.truth[k].C_bn * tr.imu[k].dv * rate;
    x = discretize_first_order(error_dynamics(truth, f_n), Matrix15::Zero(), 1 / rate).Phi * x;
    if ((k + 1) % 100 != 0) continue;
    const TruthSample& t = tr.truth[k + 1];
    const Eigen::AngleAxisd aa(t.C_bn * s[k + 1].C_bn().transpose());
    Eigen::Matrix<double, 9, 1> e;
    e << aa.angle() * aa.axis(), s[k + 1].v_n - t.v_n, s[k + 1].lat_rad - t.lat_rad, s[k + 1].lon_rad - t.lon_rad,
        s[k + 1].h_m - t.h_m;
    nl.push_back(e);
    lin.push_back(x.head<9>());
  }
  for (int i = 0; i < 9; ++i) {
    double largest = 0, worst = 0;
    for (std::size_t k = 0; k < nl.size(); ++k) {
      largest = std::max(largest, std::abs(nl[k][i]));
      worst = std::max(worst, std::abs(nl[k][i] - lin[k][i]));
    }
    std::printf("error state %d: largest %.3g, linear − nonlinear %.3g (%.2g %%)\n", i, largest, worst, 100 * worst / largest);
    EXPECT_LT(worst, 0.01 * largest) << "state " << i;
  }
}

TEST(InsErrorModel, NoiseGrowthMatchesTheClosedForms) {
  // Spec §4.7, static and level, the covariance propagated from 0 with Z21's noise: heading
  // σ = N√t (0.29° over 1200 s at 0.5°/√h); north position σ from VRW alone VRW·t^{3/2}/√3 and
  // from ARW alone g·N·t^{5/2}/√20, at 60 s where the Schuler feedback's share is (ω_s t)²/~10
  // < 0.1 %. The heading's random walk is φ_U − sin L·δλ: φ_U also carries the turn of ENU
  // between the true and the computed longitude (the transport rate's tan L·δV_E/(R_N + h),
  // which alone makes σ(φ_U) 6 % larger at 1200 s). The Earth-rate coupling left is (Ω t)²/3
  // ≈ 0.15 % at 1200 s: 1 % and 0.5 % bounds.
  const InsState s = static_state();
  const double g = somigliana(kLat, 50), N = rad(0.5) / 60, VRW = 25e-6 * kStandardG;
  const Matrix15 F = error_dynamics(s, {0, 0, g});
  const auto covariance = [&](const ErrorModelNoise& noise, double t_end, double dt) {
    const Discretized d = discretize_van_loan(F, process_noise_density(s, noise), dt);
    Matrix15 P = Matrix15::Zero();
    for (int k = 0; k < static_cast<int>(std::lround(t_end / dt)); ++k) P = d.Phi * P * d.Phi.transpose() + d.Q;
    return P;
  };
  const auto sigma = [&](const ErrorModelNoise& noise, double t_end, double dt, int index) {
    return std::sqrt(covariance(noise, t_end, dt)(index, index));
  };
  ErrorModelNoise arw, vrw;
  arw.arw.setConstant(N);
  vrw.vrw.setConstant(VRW);
  Vector15 heading = Vector15::Zero();
  heading[kPhi + 2] = 1;
  heading[kDLon] = -std::sin(kLat);
  const Matrix15 P_arw = covariance(arw, 1200, 1);
  const double sigma_heading = std::sqrt(heading.dot(P_arw * heading));
  std::printf("heading σ over 1200 s: φ_U − sin L δλ %.4f°, φ_U %.4f°, N√t %.4f°\n", deg(sigma_heading),
              deg(std::sqrt(P_arw(kPhi + 2, kPhi + 2))), deg(N * std::sqrt(1200.0)));
  EXPECT_NEAR(sigma_heading / (N * std::sqrt(1200.0)), 1.0, 0.01);
  EXPECT_NEAR(deg(N * std::sqrt(1200.0)), 0.29, 0.005);
  const double R_M = earth_radii(kLat).R_M + 50;
  EXPECT_NEAR(sigma(vrw, 60, 0.1, kDLat) * R_M / (VRW * std::pow(60.0, 1.5) / std::sqrt(3.0)), 1.0, 0.005);
  EXPECT_NEAR(sigma(arw, 60, 0.1, kDLat) * R_M / (g * N * std::pow(60.0, 2.5) / std::sqrt(20.0)), 1.0, 0.005);
}

TEST(InsErrorModel, FirstOrderAndVanLoanDiscretizations) {
  InsState s = static_state(30);
  s.v_n << 15, 8, 0.5;
  const Matrix15 F = error_dynamics(s, {0.3, -0.2, 9.9});
  ErrorModelNoise noise;
  noise.arw.setConstant(rad(0.5) / 60);
  noise.vrw.setConstant(25e-6 * kStandardG);
  const Matrix15 Qc = process_noise_density(s, noise);
  const double dt = 0.01;
  const Discretized first = discretize_first_order(F, Qc, dt), exact = discretize_van_loan(F, Qc, dt);
  // Van Loan's Φ is e^{FΔt} (Eigen's matrix exponential of FΔt, a separate route).
  const Matrix15 expF = (F * dt).exp();
  EXPECT_LT((exact.Phi - expF).cwiseAbs().maxCoeff(), 1e-14);
  // I + FΔt misses Σ_{k≥2}(FΔt)^k/k!: bounded by ½‖FΔt‖²e^{‖FΔt‖} (∞-norm), and not zero.
  const double a = (F * dt).cwiseAbs().rowwise().sum().maxCoeff();
  const double miss = (first.Phi - expF).cwiseAbs().rowwise().sum().maxCoeff();
  EXPECT_LE(miss, 0.5 * a * a * std::exp(a));
  EXPECT_GT(miss, 0.0);
  std::printf("‖FΔt‖∞ = %.3g at 100 Hz; ‖I + FΔt − e^{FΔt}‖∞ = %.3g\n", a, miss);
  // Van Loan's Q against the closed form of a white acceleration q into δV_U → δh:
  // Q = q·[[Δt³/3, Δt²/2], [Δt²/2, Δt]] over Δt = 2 s.
  Matrix15 F2 = Matrix15::Zero(), Q2 = Matrix15::Zero();
  F2(kDh, kDV + 2) = 1;
  Q2(kDV + 2, kDV + 2) = 0.7;
  const Discretized d2 = discretize_van_loan(F2, Q2, 2.0);
  EXPECT_NEAR(d2.Q(kDh, kDh), 0.7 * 8 / 3, 1e-13);
  EXPECT_NEAR(d2.Q(kDh, kDV + 2), 0.7 * 2, 1e-13);
  EXPECT_NEAR(d2.Q(kDV + 2, kDV + 2), 0.7 * 2, 1e-13);
  EXPECT_NEAR(d2.Phi(kDh, kDV + 2), 2.0, 1e-14);
  // And at the IMU rate the first-order Q is within ‖FΔt‖ of van Loan's (relative, on the diagonal).
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(first.Q(i, i) / exact.Q(i, i), 1.0, 2 * a) << i;
}

TEST(InsErrorModel, VanLoanAgainstPadeOfTheBlockMatrix) {
  // discretize_van_loan sums Taylor series on a balanced F with scaling and squaring; the reference
  // is Van Loan's own statement, Eigen's Padé exponential of the 30 × 30 [[−F, Q_c], [0, Fᵀ]]Δt in
  // long double (64-bit mantissa). Cases: the filter's 1 s at Z21's noise with Gauss–Markov biases
  // on a moving vehicle, the IMU's 10 ms and a 60 s gap. Bound from rounding: each doubling can
  // double the relative error of the sums (~1e-16 of the scale each), so 64·2^s·ε with s the
  // doublings the unbalanced norm would need (balancing needs fewer); Φ_ij against 1 + |Φ_ij|, Q_ij
  // against √(Q_ii Q_jj) (its Cauchy–Schwarz scale).
  InsState s = static_state(30);
  s.v_n << 15, 8, 0.5;
  ErrorModelNoise noise;
  noise.arw.setConstant(rad(0.5) / 60);
  noise.vrw.setConstant(25e-6 * kStandardG);
  noise.gyro_tau_s.setConstant(300);
  noise.gyro_bias_sigma.setConstant(rad(1) / 3600);
  noise.accel_tau_s.setConstant(600);
  noise.accel_bias_sigma.setConstant(20e-6 * kStandardG);
  using MatrixL = Eigen::Matrix<long double, 30, 30>;
  for (const double dt : {1.0, 0.01, 60.0}) {
    const Matrix15 F = error_dynamics(s, {0.3, -0.2, 9.9}, noise), Qc = process_noise_density(s, noise);
    MatrixL A = MatrixL::Zero();
    A.block<15, 15>(0, 0) = (-F * dt).cast<long double>();
    A.block<15, 15>(0, 15) = (Qc * dt).cast<long double>();
    A.block<15, 15>(15, 15) = (F.transpose() * dt).cast<long double>();
    const MatrixL E = A.exp();
    const Eigen::Matrix<long double, 15, 15> Phi = E.block<15, 15>(15, 15).transpose();
    const Eigen::Matrix<long double, 15, 15> Q = Phi * E.block<15, 15>(0, 15);
    const Discretized d = discretize_van_loan(F, Qc, dt);
    double worst_phi = 0, worst_q = 0;
    for (int i = 0; i < 15; ++i)
      for (int j = 0; j < 15; ++j) {
        worst_phi = std::max(worst_phi, static_cast<double>(std::abs(d.Phi(i, j) - Phi(i, j)) / (1 + std::abs(Phi(i, j)))));
        worst_q = std::max(worst_q, static_cast<double>(std::abs(d.Q(i, j) - 0.5L * (Q(i, j) + Q(j, i))) /
                                                        std::sqrt(Q(i, i) * Q(j, j))));
      }
    const double norm = (F * dt).cwiseAbs().colwise().sum().maxCoeff();
    const double bound = 64 * std::exp2(std::max(0.0, std::ceil(std::log2(norm / 0.125)))) * 0x1p-52;
    std::printf("Δt %g s, ‖FΔt‖₁ %.3g: Φ within %.2g, Q within %.2g of its scale (bound %.2g)\n", dt, norm,
                worst_phi, worst_q, bound);
    EXPECT_LT(worst_phi, bound) << dt;
    EXPECT_LT(worst_q, bound) << dt;
  }
  // A stiff Gauss–Markov bias (τ = 0.02 s over 1 s, ‖FΔt‖ = 50), where the 30 × 30 exponential
  // loses Q to cancellation (its −F block grows as e^50): the bias states alone against their
  // closed forms, Φ = e^{−Δt/τ} and Q = σ²(1 − e^{−2Δt/τ}).
  noise.accel_tau_s.setConstant(0.02);
  const Discretized d = discretize_van_loan(error_dynamics(s, {0.3, -0.2, 9.9}, noise), process_noise_density(s, noise), 1.0);
  const double sigma2 = std::pow(noise.accel_bias_sigma.x(), 2);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(d.Phi(kAccelBias + i, kAccelBias + i), std::exp(-50.0), 1e-30);
    EXPECT_NEAR(d.Q(kAccelBias + i, kAccelBias + i) / (sigma2 * -std::expm1(-100.0)), 1.0, 1e-13);
  }
}

// ---------------------------------------------------------------------------------------------
// The filter
// ---------------------------------------------------------------------------------------------

// ---------------------------------------------------------------------------------------------
// The RTS smoother
// ---------------------------------------------------------------------------------------------

TEST(InsSmoother, TheClosedLoopRtsSmootherIsTheBatchLeastSquaresSolution) {
  // A linear Gaussian system, run as ins/'s filter runs: a nominal state propagated on its own and an
  // error state x = nominal − truth estimated at each measurement, fed back (nominal −= δ) and reset
  // to 0. Its smoothed states must be the minimum of the whole run's quadratic cost
  //   (x₀ − m₀)ᵀP₀⁻¹(x₀ − m₀) + Σ (x_k − Φx_{k−1})ᵀQ⁻¹(·) + Σ (z_k − Hx_k)²/r,
  // solved here directly by its normal equations A·X = b, and their covariances A⁻¹'s diagonal blocks.
  // Position and velocity, the position measured, 40 epochs.
  constexpr int N = 40;
  const double T = 1.0, q = 0.05, r = 0.3;
  Eigen::Matrix2d Phi, Q, P0;
  Phi << 1, T, 0, 1;
  Q << q * T * T * T / 3, q * T * T / 2, q * T * T / 2, q * T;
  P0 << 4, 0.5, 0.5, 1;
  const Eigen::RowVector2d H(1, 0);
  const Eigen::Vector2d m0(0, 1);
  std::mt19937_64 rng(20240601);
  std::normal_distribution<double> n01;
  const auto draw = [&](const Eigen::Matrix2d& C) {
    return Eigen::Vector2d(Eigen::LLT<Eigen::Matrix2d>(C).matrixL() * Eigen::Vector2d(n01(rng), n01(rng)));
  };
  std::vector<double> z(N);
  Eigen::Vector2d x = m0 + draw(P0);
  for (int k = 0; k < N; ++k) {
    if (k > 0) x = Phi * x + draw(Q);
    z[k] = H * x + std::sqrt(r) * n01(rng);
  }
  // The closed-loop filter, its record per epoch.
  std::vector<FilterRecord> records(N);
  std::vector<Eigen::Vector2d> filtered(N);
  Eigen::Vector2d nominal = m0;
  Eigen::Matrix2d P = P0;
  for (int k = 0; k < N; ++k) {
    if (k > 0) {
      nominal = Phi * nominal;
      P = Phi * P * Phi.transpose() + Q;
      records[k].Phi = Phi;
    }
    records[k].P_prior = P;
    const double S = H * P * H.transpose() + r;
    const Eigen::Vector2d K = P * H.transpose() / S;
    const Eigen::Vector2d delta = K * (H * nominal - z[k]);  // the measured error: model minus measurement
    nominal -= delta;
    P = (Eigen::Matrix2d::Identity() - K * H) * P;
    records[k].P_post = P;
    records[k].correction = delta;
    filtered[k] = nominal;
  }
  const std::vector<SmoothedEpoch> smoothed = rts_smooth(records);
  // The batch solution.
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(2 * N, 2 * N);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(2 * N);
  const Eigen::Matrix2d P0i = P0.inverse(), Qi = Q.inverse();
  A.block<2, 2>(0, 0) += P0i;
  b.segment<2>(0) += P0i * m0;
  for (int k = 1; k < N; ++k) {
    Eigen::Matrix<double, 2, 4> J;
    J << -Phi, Eigen::Matrix2d::Identity();
    A.block<4, 4>(2 * (k - 1), 2 * (k - 1)) += J.transpose() * Qi * J;
  }
  for (int k = 0; k < N; ++k) {
    A.block<2, 2>(2 * k, 2 * k) += H.transpose() * H / r;
    b.segment<2>(2 * k) += H.transpose() * z[k] / r;
  }
  const Eigen::MatrixXd Ainv = A.inverse();
  const Eigen::VectorXd X = Ainv * b;
  double worst_x = 0, worst_P = 0, first_shift = 0;
  for (int k = 0; k < N; ++k) {
    const Eigen::Vector2d xs = filtered[k] - smoothed[k].correction;  // as feed_back applies a correction
    worst_x = std::max(worst_x, (xs - X.segment<2>(2 * k)).cwiseAbs().maxCoeff());
    worst_P = std::max(worst_P, (smoothed[k].P - Ainv.block(2 * k, 2 * k, 2, 2)).cwiseAbs().maxCoeff());
  }
  first_shift = (smoothed[0].correction).norm();
  std::printf("RTS against the batch solution: states within %.2g, covariances within %.2g; the first epoch moved %.3g\n",
              worst_x, worst_P, first_shift);
  EXPECT_LT(worst_x, 1e-10);
  EXPECT_LT(worst_P, 1e-10);
  EXPECT_GT(first_shift, 0.05);  // the smoother changed something: the first epoch learns from the later ones
  EXPECT_EQ(smoothed[N - 1].correction.norm(), 0.0);
  EXPECT_LT(smoothed[0].P(0, 0), records[0].P_post(0, 0));
  records[3].P_prior.resize(3, 3);
  EXPECT_THROW(rts_smooth(records), std::invalid_argument);
}

TEST(InsFilter, SunElevationAtZ21sStartAndItsRowAgainstFiniteDifferences) {
  // Dec and GHA from the Astronomical Almanac's low-precision sun (tests/almanac_sun.h, not ERFA);
  // spec §4.3: H = 22.94° at the site at 16:14 Beijing time (geometric; the almanac is good to 0.01°).
  const test::AlmanacHourAngle sun = test::almanac_dec_gha(kZ21StartUnix);
  const SunElevationModel m = sun_elevation_model(kLat, kLon, sun.dec_rad, sun.gha_rad);
  EXPECT_NEAR(deg(std::asin(m.sin_H)), 22.94, 0.02);
  EXPECT_NEAR(deg(std::asin(m.sin_H)), 90 - test::almanac_sun(kZ21StartUnix, 39.979, 116.339).zenith_deg, 1e-9);
  // Central differences of sin H_c (Eq. 9) in L and λ; step 1e-5 rad: truncation ~1e-11.
  const auto sinH = [&](double L, double lon) {
    const double lha = sun.gha_rad + lon;
    return std::sin(L) * std::sin(sun.dec_rad) + std::cos(L) * std::cos(sun.dec_rad) * std::cos(lha);
  };
  const double h = 1e-5;
  EXPECT_NEAR(m.d_lat, (sinH(kLat + h, kLon) - sinH(kLat - h, kLon)) / (2 * h), 1e-9);
  EXPECT_NEAR(m.d_lon, (sinH(kLat, kLon + h) - sinH(kLat, kLon - h)) / (2 * h), 1e-9);
  // In the afternoon (LHA ∈ (0°, 180°)) going east makes it later local time and lowers the sun:
  // ∂sinH/∂λ < 0, the sign Z21's printed α lost (spec §4.3).
  EXPECT_LT(m.d_lon, 0.0);
}

TEST(InsFilter, SageHusaFollowsTheSpecRecursion) {
  // β₁ = 1, β_{k+1} = β_k/(β_k + b) → 1 − b; R₁ = the first sample; the sample raised to
  // 0.01·R0, the average capped at 100·R0 (spec §4.7).
  SageHusaR sh(1.0, 0.98);
  EXPECT_DOUBLE_EQ(sh.update(2.0, 0.5), 3.5);  // r² − HPHᵀ = 3.5, β = 1
  const double beta2 = 1 / 1.98, beta3 = beta2 / (beta2 + 0.98);
  EXPECT_NEAR(sh.beta(), beta2, 1e-15);
  const double R2 = (1 - beta2) * 3.5 + beta2 * 0.01;  // the sample −1 raised to R_min
  EXPECT_DOUBLE_EQ(sh.update(0.0, 1.0), R2);
  // A sample of 150 > R_max moves R by β only (PSINS would set R_max = 100).
  EXPECT_NEAR(sh.update(std::sqrt(150.0), 0.0), (1 - beta3) * R2 + beta3 * 150, 1e-12);
  EXPECT_DOUBLE_EQ(sh.update(100.0, 0.0), 100.0);  // an average above R_max: R_max
  for (int k = 0; k < 5000; ++k) sh.update(1.0, 0.0);
  EXPECT_NEAR(sh.beta(), 0.02, 1e-4);
  EXPECT_NEAR(sh.R(), 1.0, 1e-9);
}

// The linear system the filter assumes, at Z21's site: static, 1 Hz, Z21's IMU noise.
struct LinearZ21 {
  Matrix15 Phi, Q, Q_half, P0;
  double dt = 1;
  LinearZ21() {
    const InsState s = static_state(30);
    ErrorModelNoise noise;
    noise.arw.setConstant(rad(0.5) / 60);
    noise.vrw.setConstant(25e-6 * kStandardG);
    const Discretized d = discretize_van_loan(error_dynamics(s, {0, 0, somigliana(kLat, 50)}),
                                              process_noise_density(s, noise), dt);
    Phi = d.Phi;
    Q = d.Q;
    Eigen::SelfAdjointEigenSolver<Matrix15> es(Q);
    Q_half = es.eigenvectors() * es.eigenvalues().cwiseMax(0).cwiseSqrt().asDiagonal();
    const double R = earth_radii(kLat).R_M;
    Vector15 sd;
    sd << rad(0.05), rad(0.05), rad(0.5), 0.02, 0.02, 0.02, 200 / R, 200 / R, 1.0, Eigen::Vector3d::Constant(rad(5) / 3600),
        Eigen::Vector3d::Constant(50e-6 * kStandardG);
    P0 = sd.cwiseAbs2().asDiagonal();
  }
  RowVector15 H(double t) const {
    const test::AlmanacHourAngle sun = test::almanac_dec_gha(kZ21StartUnix + t);
    const SunElevationModel m = sun_elevation_model(kLat, kLon, sun.dec_rad, sun.gha_rad);
    RowVector15 row = RowVector15::Zero();
    row[kDLat] = m.d_lat;
    row[kDLon] = m.d_lon;
    return row;
  }
  double R(double t, double sigma_H) const {
    const test::AlmanacHourAngle sun = test::almanac_dec_gha(kZ21StartUnix + t);
    const double sin_H = sun_elevation_model(kLat, kLon, sun.dec_rad, sun.gha_rad).sin_H;
    return (1 - sin_H * sin_H) * sigma_H * sigma_H;  // (cos H·σ_H)²
  }
  Vector15 normal(std::uint64_t seed, std::uint64_t trial, std::uint64_t k) const {
    Vector15 n;
    for (int i = 0; i < 15; ++i) n[i] = standard_normal(seed, trial, k, static_cast<std::uint64_t>(i));
    return n;
  }
};

TEST(InsFilter, NeesAndNisInsideTheirChiSquareBands) {
  // 60 trials of 1200 s: x₀ ~ N(0, P0), x⁺ = Φx + w, z = Hx + v with the filter's own Φ, Q, H, R.
  // A consistent filter has Σ_trials NEES ~ χ²(15·60) at each checked time and Σ NIS ~ χ²(60·1200):
  // each inside its 99.9 % band (Wilson–Hilferty), four checks.
  const LinearZ21 sys;
  const int trials = 60, steps = 1200;
  const double sigma_H = rad(0.1);
  std::vector<double> nees(3, 0.0);
  const std::vector<int> checks{100, 600, 1200};
  double nis = 0;
  for (int trial = 0; trial < trials; ++trial) {
    Vector15 x = sys.P0.diagonal().cwiseSqrt().cwiseProduct(sys.normal(11, trial, 0));
    ErrorFilter f;
    f.P = sys.P0;
    for (int k = 1; k <= steps; ++k) {
      x = sys.Phi * x + sys.Q_half * sys.normal(12, trial, k);
      f.predict(sys.Phi, sys.Q);
      const RowVector15 H = sys.H(k);
      const double R = sys.R(k, sigma_H);
      const double z = H.dot(x) + std::sqrt(R) * standard_normal(13, trial, k, 0);
      nis += f.update(H, z, R).nis;
      for (std::size_t c = 0; c < checks.size(); ++c)
        if (k == checks[c]) {
          const Vector15 e = x - f.x;
          nees[c] += e.dot(f.P.ldlt().solve(e));
        }
    }
  }
  constexpr double z999 = 3.2905;
  for (std::size_t c = 0; c < checks.size(); ++c) {
    const double mean = nees[c] / (15.0 * trials);
    std::printf("NEES/15 at %d s: %.3f\n", checks[c], mean);
    EXPECT_GT(mean, chi2_mean_quantile(15.0 * trials, -z999));
    EXPECT_LT(mean, chi2_mean_quantile(15.0 * trials, z999));
  }
  const double mean_nis = nis / (double(trials) * steps);
  std::printf("mean NIS: %.4f\n", mean_nis);
  EXPECT_GT(mean_nis, chi2_mean_quantile(double(trials) * steps, -z999));
  EXPECT_LT(mean_nis, chi2_mean_quantile(double(trials) * steps, z999));
}

TEST(InsFilter, SageHusaRecoversAnUnderstatedR) {
  // The true measurement σ is twice the nominal (R_true = 4·R0). Non-adaptive, the mean NIS sits
  // near 4 (far outside χ²(1)'s mean band); Sage–Husa's R, averaged over the last 600 of 1200
  // updates and 10 trials, comes within 20 % of R_true (its EMA at β ≈ 0.02 has a relative sd of
  // √(2β/(2 − β)) ≈ 0.14 per update, ~0.03 over the ~200 effectively independent ones).
  const LinearZ21 sys;
  const double sigma_H = rad(0.1);
  double R_sum = 0, R_true_sum = 0, nis_fixed = 0;
  int n = 0, m = 0;
  for (int trial = 0; trial < 10; ++trial) {
    Vector15 x = sys.P0.diagonal().cwiseSqrt().cwiseProduct(sys.normal(21, trial, 0));
    ErrorFilter adaptive, fixed;
    adaptive.P = fixed.P = sys.P0;
    SageHusaR sh(sys.R(0, sigma_H));
    for (int k = 1; k <= 1200; ++k) {
      x = sys.Phi * x + sys.Q_half * sys.normal(22, trial, k);
      adaptive.predict(sys.Phi, sys.Q);
      fixed.predict(sys.Phi, sys.Q);
      const RowVector15 H = sys.H(k);
      const double R0 = sys.R(k, sigma_H), R_true = 4 * R0;
      const double z = H.dot(x) + std::sqrt(R_true) * standard_normal(23, trial, k, 0);
      const double R = sh.update(z - H.dot(adaptive.x), H.dot(adaptive.P * H.transpose()));
      adaptive.update(H, z, R);
      nis_fixed += fixed.update(H, z, R0).nis;
      ++m;
      if (k > 600) {
        R_sum += R;
        R_true_sum += R_true;
        ++n;
      }
    }
  }
  std::printf("Sage–Husa R / R_true = %.3f; fixed-R mean NIS %.2f\n", R_sum / R_true_sum, nis_fixed / m);
  EXPECT_NEAR(R_sum / R_true_sum, 1.0, 0.2);
  EXPECT_GT(nis_fixed / m, 3.0);
}

// Z21's static run in simulation: a 50 Hz IMU with Table 1's errors (seed 2021), yaw 30°, height
// held, and a sun elevation every second with noise σ_meas; the INS alone beside the filter.
struct Z21Run {
  InsState sins, filtered;
  TruthSample end;
  FilterSummary summary;
  double sigma_along_sun_m = 0;  // the filter's 1σ along the sun's azimuth at the end
  double along_sun_m = 0;        // its error there
};

Z21Run run_z21(double duration_s, double sigma_meas_deg, FilterSettings settings) {
  const double rate = 50;
  TrajectorySpec traj = static_spec(duration_s, rate, {0, 0, rad(30)});
  traj.substeps = 2;  // static: Simpson is exact for the constant rates
  const Trajectory tr = generate_trajectory(traj);
  ImuErrorSpec spec = z21_imu_errors();
  spec.rate_hz = rate;
  const CorruptedImu imu = corrupt_imu(tr.imu, spec, 2021);
  settings.mechanization.hold_height_m = 50;
  settings.noise = error_model_noise(spec);
  // The elevations below are the true ones plus noise, through no attitude: Z21's position-only H.
  settings.measurement = FilterSettings::SunMeasurement::ElevationZ21;
  Matrix15 P0 = LinearZ21().P0;
  P0(kDh, kDh) = 0;  // held
  const InsState start = state_of(tr.truth[0]);
  InsFilter filter(start, P0, settings);
  Z21Run run;
  run.sins = run_ins(start, imu.samples, settings.mechanization).back();
  for (std::size_t k = 0; k < imu.samples.size(); ++k) {
    filter.predict(imu.samples[k]);
    if ((k + 1) % static_cast<std::size_t>(rate) != 0) continue;
    const double t = imu.samples[k].t_s;
    const test::AlmanacHourAngle sun = test::almanac_dec_gha(kZ21StartUnix + t);
    const double H_true = std::asin(sun_elevation_model(kLat, kLon, sun.dec_rad, sun.gha_rad).sin_H);
    filter.update({t, H_true + rad(sigma_meas_deg) * standard_normal(99, 0, k, 0), sun.dec_rad, sun.gha_rad});
  }
  run.end = tr.truth.back();
  run.filtered = filter.state();
  run.summary = filter.summary();
  // Metres along the sun's azimuth A_s per radian of δL and δλ.
  const double A_s = rad(test::almanac_sun(kZ21StartUnix + duration_s, 39.979, 116.339).azimuth_deg);
  const EarthRadii r = earth_radii(kLat);
  const Eigen::Vector2d a((r.R_M + 50) * std::cos(A_s), (r.R_N + 50) * std::cos(kLat) * std::sin(A_s));
  run.sigma_along_sun_m = std::sqrt(a.dot(filter.P().block<2, 2>(kDLat, kDLat) * a));
  run.along_sun_m = north_error_m(run.end, run.filtered) * std::cos(A_s) + east_error_m(run.end, run.filtered) * std::sin(A_s);
  return run;
}

// Spec §4.6 item 3 [SIM-trend]: the SINS alone drifts tens of km in 1200 s, while the filter keeps
// the error along the sun's azimuth — the one direction an elevation sees (spec §4.3) — inside
// 4σ of its own covariance, that σ below the compass' 0.1° ≈ 11 km, and its summary consistent.
TEST(InsFilter, ClosedLoopOnZ21sStaticRunBoundsTheDrift) {
  const Z21Run run = run_z21(1200, 0.1, {});
  const double sins_km = std::hypot(north_error_m(run.end, run.sins), east_error_m(run.end, run.sins)) / 1000;
  std::printf("Z21 run: SINS %.1f km; integrated along the sun %.3f km (1σ %.3f km); %s\n", sins_km,
              run.along_sun_m / 1000, run.sigma_along_sun_m / 1000, run.summary.BriefReport().c_str());
  EXPECT_GT(sins_km, 5.0);
  EXPECT_LT(std::abs(run.along_sun_m), 4 * run.sigma_along_sun_m);
  EXPECT_LT(run.sigma_along_sun_m, 11e3);
  EXPECT_EQ(run.summary.updates, 1200);
  EXPECT_EQ(run.summary.predictions, 60000);
  EXPECT_EQ(run.summary.status, FilterStatus::Ok) << run.summary.BriefReport();
  EXPECT_LT(run.summary.nis_outside_95, 0.15);
}

// The compass four times noisier than σ_H says: with R fixed the summary reports the filter
// inconsistent (mean NIS ≈ 16 over 300 updates, far outside χ²(300)/300's 99.9 % band
// [0.75, 1.28]); Sage–Husa's R absorbs it and the summary is ok again.
TEST(InsFilter, SummaryFlagsAnUnderstatedCompassAndSageHusaAbsorbsIt) {
  FilterSettings fixed;
  fixed.adaptive = false;
  const Z21Run a = run_z21(300, 0.4, fixed), b = run_z21(300, 0.4, {});
  std::printf("fixed R: %s\nSage–Husa: %s\n", a.summary.BriefReport().c_str(), b.summary.BriefReport().c_str());
  EXPECT_EQ(a.summary.status, FilterStatus::Inconsistent);
  EXPECT_GT(a.summary.mean_nis, 8.0);
  EXPECT_EQ(b.summary.status, FilterStatus::Ok) << b.summary.BriefReport();
  // R settles near (cos H·0.4°)², 16 times the nominal (the EMA's sd at β ≈ 0.02 is ~15 %).
  EXPECT_NEAR(b.summary.final_R / std::pow(std::cos(rad(21.9)) * rad(0.4), 2), 1.0, 0.5);
}

// P propagated once per update by van Loan (FilterSettings::CovarianceStep::AtUpdates, what navigate
// uses) against PSINS's I + FΔt at every sample: two discretizations of one model, apart by the
// first-order form's O(‖FΔt‖) per step (test above: ‖FΔt‖∞ ~ 0.1 at 100 Hz through g, but the
// position σ it changes only through the accumulated Q): the along-sun σ within 2 % and the
// estimates within 5 % of it.
TEST(InsFilter, CovarianceAtUpdatesAgreesWithEverySample) {
  FilterSettings at_updates;
  at_updates.covariance_step = FilterSettings::CovarianceStep::AtUpdates;
  const Z21Run a = run_z21(300, 0.1, {}), b = run_z21(300, 0.1, at_updates);
  std::printf("along-sun σ: every sample %.1f m, at updates %.1f m; error %.1f m vs %.1f m\n", a.sigma_along_sun_m,
              b.sigma_along_sun_m, a.along_sun_m, b.along_sun_m);
  EXPECT_NEAR(b.sigma_along_sun_m / a.sigma_along_sun_m, 1.0, 0.02);
  EXPECT_NEAR(b.along_sun_m, a.along_sun_m, 0.05 * a.sigma_along_sun_m);
  EXPECT_EQ(b.summary.updates, a.summary.updates);
}

TEST(InsFilter, ANonFiniteMeasurementIsDataNotACrash) {
  InsFilter filter(static_state(), LinearZ21().P0);
  EXPECT_THROW(filter.update({1.0, 0.4, 0.03, 1.0}), std::invalid_argument);  // not the state's time
  EXPECT_EQ(filter.summary().status, FilterStatus::NoUpdates);
  filter.update({0, std::numeric_limits<double>::quiet_NaN(), 0.03, 1.0});
  const FilterSummary s = filter.summary();
  EXPECT_EQ(s.status, FilterStatus::NonFinite);
  EXPECT_EQ(s.skipped, 1);
  EXPECT_EQ(s.updates, 0);
  EXPECT_NE(s.BriefReport().find("non_finite"), std::string::npos);
}

// A zero-velocity update is three scalar Kalman updates on δv (z = v̂, H = e_i): with P's velocity
// block diagonal and uncorrelated with the rest, each is the textbook scalar one, v⁺ = v·R/(P + R),
// P⁺ = P·R/(P + R); a held height's v_U is pinned and gets none.
TEST(InsFilter, AZeroVelocityUpdateIsTheScalarKalmanUpdate) {
  Matrix15 P0 = Matrix15::Zero();
  for (int i = 0; i < 15; ++i) P0(i, i) = 1e-6;
  const double P_v = 0.1 * 0.1, R = 0.01 * 0.01;
  for (int i = 0; i < 3; ++i) P0(kDV + i, kDV + i) = P_v;
  for (const bool held : {false, true}) {
    InsState start = static_state();
    start.v_n = Eigen::Vector3d(0.05, -0.03, 0.02);
    FilterSettings settings;
    if (held) settings.mechanization.hold_height_m = start.h_m;
    InsFilter filter(start, P0, settings);
    const ZeroVelocityUpdate u = filter.update_zero_velocity(0.01);
    const int axes = held ? 2 : 3;
    for (int i = 0; i < axes; ++i) {
      EXPECT_NEAR(filter.state().v_n[i], start.v_n[i] * R / (P_v + R), 1e-15) << i;
      EXPECT_NEAR(filter.P()(kDV + i, kDV + i), P_v * R / (P_v + R), 1e-15) << i;
    }
    const ScalarUpdate& east = u.east;
    EXPECT_NEAR(east.nis, 0.05 * 0.05 / (P_v + R), 1e-12);
    EXPECT_EQ(std::isnan(u.up.nis), held);
    if (held) {
      EXPECT_EQ(filter.state().v_n.z(), 0.02);  // the mechanization's to hold: the update leaves it
    }
    const FilterSummary s = filter.summary();
    EXPECT_EQ(s.zero_velocity_updates, axes);
    EXPECT_EQ(s.updates, 0);  // the sun's statistics are apart
    EXPECT_NE(s.BriefReport().find("zero-velocity updates"), std::string::npos);
  }
  InsFilter filter(static_state(), P0);
  EXPECT_THROW(filter.update_zero_velocity(0), std::invalid_argument);
}

// A position fix with a correlated covariance (a PNS's, loosely coupled) is the textbook vector
// update with H = [e_δL; e_δλ] and R the fix's covariance in radians: the filter's two whitened scalar
// updates give K = P Hᵀ(H P Hᵀ + R)⁻¹, P⁺ = P − K H P and the fix's χ² zᵀ(HPHᵀ + R)⁻¹z, written here
// with Eigen's dense inverse (P0 correlates the position with a velocity, so K moves both).
TEST(InsFilter, APositionFixIsTheVectorKalmanUpdate) {
  InsState start = static_state();
  const EarthRadii r = earth_radii(start.lat_rad);
  const double m_lat = r.R_M + start.h_m, m_lon = (r.R_N + start.h_m) * std::cos(start.lat_rad);
  Matrix15 P0 = Matrix15::Identity() * 1e-8;
  P0(kDLat, kDLat) = std::pow(1000 / m_lat, 2);
  P0(kDLon, kDLon) = std::pow(800 / m_lon, 2);
  P0(kDV + 1, kDV + 1) = 0.01;
  P0(kDLat, kDV + 1) = P0(kDV + 1, kDLat) = 0.5 * std::sqrt(P0(kDLat, kDLat) * 0.01);
  FilterSettings settings;
  settings.adaptive = true;  // a fix's R is its own: never Sage–Husa's
  InsFilter filter(start, P0, settings);
  const double lat_fix = start.lat_rad - 600 / m_lat, lon_fix = start.lon_rad + 300 / m_lon;
  Eigen::Matrix2d cov_m2;
  cov_m2 << 400.0 * 400.0, -0.7 * 400.0 * 900.0, -0.7 * 400.0 * 900.0, 900.0 * 900.0;
  const PositionUpdate u = filter.update_position(lat_fix, lon_fix, cov_m2);

  Eigen::Matrix<double, 2, 15> H = Eigen::Matrix<double, 2, 15>::Zero();
  H(0, kDLat) = H(1, kDLon) = 1;
  const Eigen::Matrix2d R = Eigen::Vector2d(1 / m_lat, 1 / m_lon).asDiagonal() * cov_m2 *
                            Eigen::Vector2d(1 / m_lat, 1 / m_lon).asDiagonal();
  const Eigen::Matrix2d S = H * P0 * H.transpose() + R;
  const Eigen::Matrix<double, 15, 2> K = P0 * H.transpose() * S.inverse();
  const Eigen::Vector2d z(start.lat_rad - lat_fix, start.lon_rad - lon_fix);
  const Vector15 dx = K * z;
  const Matrix15 P1 = P0 - K * H * P0;
  EXPECT_NEAR(u.nis(), z.dot(S.inverse() * z), 1e-9 * z.dot(S.inverse() * z));
  EXPECT_NEAR((start.lat_rad - filter.state().lat_rad) * m_lat, dx[kDLat] * m_lat, 1e-6);  // metres
  EXPECT_NEAR((start.lon_rad - filter.state().lon_rad) * m_lon, dx[kDLon] * m_lon, 1e-6);
  EXPECT_NEAR(start.v_n.y() - filter.state().v_n.y(), dx[kDV + 1], 1e-12);
  for (int i = 0; i < 15; ++i)
    for (int j = 0; j < 15; ++j)
      EXPECT_NEAR(filter.P()(i, j), P1(i, j), 1e-9 * std::sqrt(P0(i, i) * P0(j, j))) << i << " " << j;
  EXPECT_EQ(filter.summary().updates, 2);
  Eigen::Matrix2d singular;
  singular << 1, 1, 1, 1;
  EXPECT_THROW(filter.update_position(lat_fix, lon_fix, singular), std::invalid_argument);
  filter.update_position(kNaNUpdate, lon_fix, cov_m2);  // data: skipped and counted
  EXPECT_EQ(filter.summary().skipped, 1);
}

// ---------------------------------------------------------------------------------------------
// Zero-velocity detection (Skog et al. 2010's SHOE)
// ---------------------------------------------------------------------------------------------

// At rest with Z21's IMU (its biases known to the test) each window's statistic is χ²(6W − 2)/
// (6W − 2) (the mean direction takes two of the 6W degrees of freedom): over 1000 windows of
// W = 100 its mean is 1 (sd of the mean √(2/598)/√1000 = 0.0018; 0.01 is 5.5 sd) and its sd
// √(2/598) = 0.0578 (sd of that ±2.2 %; 10 % allowed), and no window is missed (10⁻⁶ each).
TEST(InsZupt, AtRestTheStatisticIsChiSquareOverItsDegreesOfFreedom) {
  const double rate = 100;
  const Trajectory tr = generate_trajectory(static_spec(1000, rate, {rad(2), rad(-1), rad(30)}));
  ImuErrorSpec spec = z21_imu_errors();
  spec.rate_hz = rate;
  const CorruptedImu imu = corrupt_imu(tr.imu, spec, 77);
  const ZeroVelocityDetector detector{spec.gyro.white_noise, spec.accel.white_noise};
  RestModel rest;
  rest.g_mps2 = somigliana(kLat, 50);
  rest.omega_b = tr.truth[0].C_bn.transpose() * Eigen::Vector3d(0, kEarthRate * std::cos(kLat), kEarthRate * std::sin(kLat)) +
                 imu.drawn.gyro_bias;
  rest.accel_bias = imu.drawn.accel_bias;
  std::vector<double> T;
  int missed = 0;
  for (std::size_t k = 0; k + 100 <= imu.samples.size(); k += 100) {
    const ZeroVelocityTest t = detector.test(std::span(imu.samples).subspan(k, 100), k == 0 ? 0.0 : imu.samples[k - 1].t_s, rest);
    T.push_back(t.statistic);
    missed += t.at_rest ? 0 : 1;
    EXPECT_NEAR(t.threshold, chi2_mean_quantile(598, 4.753424308822899), 1e-12);
  }
  ASSERT_EQ(T.size(), 1000u);
  double mean = 0, var = 0;
  for (double x : T) mean += x / 1000;
  for (double x : T) var += (x - mean) * (x - mean) / 1000;
  std::printf("at rest: T mean %.4f, sd %.4f (χ²: 1, %.4f), %d missed\n", mean, std::sqrt(var), std::sqrt(2.0 / 598), missed);
  EXPECT_NEAR(mean, 1.0, 0.01);
  EXPECT_NEAR(std::sqrt(var) / std::sqrt(2.0 / 598), 1.0, 0.1);
  EXPECT_EQ(missed, 0);
  EXPECT_THROW(detector.test(std::span(imu.samples).subspan(0, 1), 0.0, rest), std::invalid_argument);
  EXPECT_THROW((ZeroVelocityDetector{}.test(std::span(imu.samples).subspan(0, 100), 0.0, rest)), std::invalid_argument);
}

// What the IMU sees in motion: an acceleration (‖f‖ ≠ g), a turn (ω ≠ ω_ie) and a vibrating cruise
// are not rest; a steady cruise without vibration is, to any IMU (f = g, ω = ω_ie up to the
// transport rate, 3e-6 rad/s at 20 m/s): why a simulated vehicle needs trajectory.vibration_mps2.
TEST(InsZupt, AccelerationTurnsAndVibrationAreNotRestASteadyCruiseIs) {
  const double rate = 100;
  ImuErrorSpec spec = z21_imu_errors();
  spec.rate_hz = rate;
  const ZeroVelocityDetector detector{spec.gyro.white_noise, spec.accel.white_noise};
  for (const double vibration : {0.0, 0.3}) {
    TrajectorySpec traj = moving_spec(rate);
    traj.vibration_mps2 = vibration;
    const Trajectory tr = generate_trajectory(traj);
    const CorruptedImu imu = corrupt_imu(tr.imu, spec, 78);
    // 1 s windows inside segments: the start's rest, the 1 m/s² acceleration, the cruise, the turn.
    const auto window = [&](double t0) {
      const std::size_t k = static_cast<std::size_t>(std::lround(t0 * rate));
      const TruthSample& at = tr.truth[k];
      RestModel rest;
      rest.g_mps2 = somigliana(at.lat_rad, at.h_m);
      rest.omega_b = at.C_bn.transpose() * Eigen::Vector3d(0, kEarthRate * std::cos(at.lat_rad), kEarthRate * std::sin(at.lat_rad)) +
                     imu.drawn.gyro_bias;
      rest.accel_bias = imu.drawn.accel_bias;
      return detector.test(std::span(imu.samples).subspan(k, 100), at.t_s, rest);
    };
    EXPECT_TRUE(window(4).at_rest) << window(4).statistic;
    EXPECT_FALSE(window(20).at_rest) << window(20).statistic;
    EXPECT_FALSE(window(75).at_rest) << window(75).statistic;
    EXPECT_EQ(window(45).at_rest, vibration == 0) << vibration << " " << window(45).statistic;
  }
}

// The vibration is in the IMU's Δv alone: the truth is the same bit for bit, at rest nothing
// changes, and while moving each axis's Δv/Δt carries the tone's increments, rms a·sin x/x with
// x = ωΔt/2 (the exact mean of √2·a·cos ωt over an interval), within 1 % over the 40 s cruise.
TEST(InsTrajectory, VibrationIsInTheImuAloneWithItsRms) {
  const double rate = 100, a = 0.3;
  TrajectorySpec smooth = moving_spec(rate), vibrating = smooth;
  vibrating.vibration_mps2 = a;
  const Trajectory t0 = generate_trajectory(smooth), t1 = generate_trajectory(vibrating);
  ASSERT_EQ(t0.imu.size(), t1.imu.size());
  for (std::size_t k = 0; k < t0.truth.size(); ++k) {
    ASSERT_EQ(t0.truth[k].lat_rad, t1.truth[k].lat_rad);
    ASSERT_EQ(t0.truth[k].v_n, t1.truth[k].v_n);
  }
  for (std::size_t k = 0; k < 1000; ++k) EXPECT_EQ(t0.imu[k].dv, t1.imu[k].dv) << k;  // the first 10 s: at rest
  // The cruise at 20 m/s, 30–60 s: each axis's rms against a·sin x/x.
  for (int i = 0; i < 3; ++i) {
    double sum2 = 0;
    int n = 0;
    for (std::size_t k = 3000; k < 6000; ++k, ++n) sum2 += std::pow((t1.imu[k].dv[i] - t0.imu[k].dv[i]) * rate, 2);
    const double x = kPi * kVibrationHz[i] / rate;
    EXPECT_NEAR(std::sqrt(sum2 / n) / (a * std::sin(x) / x), 1.0, 0.01) << i;
  }
  vibrating.vibration_mps2 = -1;
  EXPECT_THROW(generate_trajectory(vibrating), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// Allan deviation (IEEE 952)
// ---------------------------------------------------------------------------------------------

std::vector<double> gyro_x_rate(const CorruptedImu& c, double dt) {
  std::vector<double> y;
  y.reserve(c.samples.size());
  for (const ImuSample& s : c.samples) y.push_back(s.dtheta.x() / dt);
  return y;
}

// A loose Monte-Carlo bound on an overlapping Allan deviation's relative error at τ = mΔt:
// 1/√(2(N/m − 1)) is the non-overlapping estimator's; four of them.
double allan_tolerance(double n, double tau, double dt) { return 4 / std::sqrt(2 * (n * dt / tau - 1)); }

TEST(InsAllan, WhiteNoiseGivesArwOverRootTau) {
  const double dt = 0.01, N = rad(0.5) / 60;
  const std::size_t n = 1 << 17;
  ImuErrorSpec spec;
  spec.rate_hz = 1 / dt;
  spec.gyro.white_noise.setConstant(N);
  const std::vector<AllanPoint> a = allan_deviation(gyro_x_rate(corrupt_imu(zero_samples(n, dt), spec, 5), dt), dt);
  ASSERT_GE(a.size(), 10u);
  for (const AllanPoint& p : a)
    if (p.tau_s <= n * dt / 64) {
      EXPECT_NEAR(p.adev * std::sqrt(p.tau_s) / N, 1.0, allan_tolerance(n, p.tau_s, dt)) << p.tau_s;
    }
  EXPECT_NEAR(a.front().tau_s, dt, 1e-15);
  EXPECT_NEAR(a[1].tau_s, 2 * dt, 1e-15);
}

TEST(InsAllan, RateRandomWalkGivesKRootTauOverThree) {
  const double dt = 0.1, K = 1e-6;
  const std::size_t n = 1 << 17;
  ImuErrorSpec spec;
  spec.rate_hz = 1 / dt;
  spec.gyro.random_walk.setConstant(K);
  const std::vector<AllanPoint> a = allan_deviation(gyro_x_rate(corrupt_imu(zero_samples(n, dt), spec, 6), dt), dt);
  int checked = 0;
  // m ≥ 8: the discrete walk's Allan variance is K²τ/3·(1 + O(1/m²)). A random walk's estimates
  // correlate over the whole record, so the bound is doubled.
  for (const AllanPoint& p : a)
    if (p.tau_s >= 8 * dt && p.tau_s <= n * dt / 256) {
      EXPECT_NEAR(p.adev / (K * std::sqrt(p.tau_s / 3)), 1.0, 2 * allan_tolerance(n, p.tau_s, dt)) << p.tau_s;
      ++checked;
    }
  EXPECT_GE(checked, 5);
}

TEST(InsAllan, GaussMarkovBiasInstabilityFollowsItsClosedForm) {
  // σ_A²(τ) = (2σ²τ_c/τ)·[1 − (τ_c/2τ)(3 − 4e^{−τ/τ_c} + e^{−2τ/τ_c})] (IEEE 952 Annex C; El-Sheimy
  // et al. 2008): K√(τ/3) with K = σ√(2/τ_c) at short τ, a peak of 0.617σ at τ = 1.89τ_c — a
  // first-order Gauss–Markov bias has a peak, not the flat 0.664·B floor of flicker noise.
  const double dt = 0.1, sigma = 1e-4, tau_c = 10;
  const std::size_t n = 1 << 18;
  ImuErrorSpec spec;
  spec.rate_hz = 1 / dt;
  spec.gyro.bias_instability.setConstant(sigma);
  spec.gyro.correlation_time_s.setConstant(tau_c);
  const std::vector<AllanPoint> a = allan_deviation(gyro_x_rate(corrupt_imu(zero_samples(n, dt), spec, 8), dt), dt);
  const auto closed = [&](double tau) {
    const double r = tau / tau_c;
    return std::sqrt(2 * sigma * sigma / r * (1 - (3 - 4 * std::exp(-r) + std::exp(-2 * r)) / (2 * r)));
  };
  double peak = 0, peak_tau = 0;
  for (const AllanPoint& p : a) {
    // A GM's estimates decorrelate over ~τ_c: the white-noise bound with τ → max(τ, τ_c), doubled.
    if (p.tau_s >= dt * 4 && p.tau_s <= n * dt / 256) {
      EXPECT_NEAR(p.adev / closed(p.tau_s), 1.0, 2 * allan_tolerance(n, std::max(p.tau_s, tau_c), dt)) << p.tau_s;
    }
    if (p.adev > peak) peak = p.adev, peak_tau = p.tau_s;
  }
  std::printf("GM Allan peak %.4f σ at %.3g τ_c\n", peak / sigma, peak_tau / tau_c);
  EXPECT_NEAR(peak / sigma, 0.6174, 0.03);  // octaves straddle the peak: 12.8 s and 25.6 s
}

}  // namespace
