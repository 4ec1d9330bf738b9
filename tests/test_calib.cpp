// Angles from voltages (Eq. 2, Eqs. 16–19) and the section algorithm.
#include <gtest/gtest.h>

#include <cmath>

#include "polrig/calib/angles.h"
#include "polrig/calib/fit.h"
#include "polrig/calib/model.h"
#include "polrig/device/sensor.h"
#include "polrig/units.h"

namespace polrig {
namespace {

const std::array<double, 6> kUniform{1, 1, 1, 1, 1, 1};
// Noise-free inversion loses only rounding: a few ulps of 180°.
constexpr double kAngleTol = 1e-9;

std::array<double, 3> voltages(const CalibrationParams& p, double theta, double d) {
  return pair_voltages(p, Electronics{}, kUniform, theta, d);
}

TEST(PairAngle, BothInversionsAgreeAndRecoverTheAngle) {
  const CalibrationParams t = CalibrationParams::theory(kWang2019FilmAxesDeg);
  const Electronics e;
  for (double d : {0.05, 0.55, 0.88}) {
    // 0.1° steps include θ = 45° and 135°, where d·cos2θ = 0 and arctan(Y/X) is ±90°.
    for (int k = 0; k < 1800; ++k) {
      const double theta = 0.1 * k;
      const auto V = voltages(t, theta, d);
      for (auto [a, b] : {std::pair{0, 1}, std::pair{0, 2}, std::pair{1, 2}}) {
        const PairAngle x = pair_angle(t, e, V, a, b, PairInversion::Atan2);
        const PairAngle y = pair_angle(t, e, V, a, b, PairInversion::ArctanSignExtension);
        EXPECT_NEAR(axis_difference_deg(x.theta_deg, y.theta_deg), 0.0, kAngleTol) << theta;
        EXPECT_NEAR(x.d, y.d, 1e-12);
        EXPECT_NEAR(axis_difference_deg(x.theta_deg, theta), 0.0, kAngleTol) << theta;
        EXPECT_NEAR(x.d, d, 1e-12);
        EXPECT_GE(x.theta_deg, 0.0);
        EXPECT_LT(x.theta_deg, 180.0);
      }
    }
  }
}

TEST(PairAngle, SignExtensionAddsNinetyDegreesWhereDWouldBeNegative) {
  // θ = 100°: arctan alone gives 10° with a negative d; the sign rule turns it into 100°.
  const CalibrationParams t = CalibrationParams::theory(kWang2019FilmAxesDeg);
  const PairAngle a =
      pair_angle(t, Electronics{}, voltages(t, 100.0, 0.5), 0, 1, PairInversion::ArctanSignExtension);
  EXPECT_NEAR(a.theta_deg, 100.0, kAngleTol);
  EXPECT_NEAR(a.d, 0.5, 1e-12);
}

TEST(PairAngle, CalibratedParametersInvertEquation15) {
  // Eqs. 16–19 with the true parameters invert a device made with the same parameters.
  const CalibrationParams p = CalibrationParams::wang2019_indoor();
  for (double theta = 0.0; theta < 180.0; theta += 3.7) {
    const auto V = voltages(p, theta, 0.55);
    const SensorAngles s = sensor_angles(p, Electronics{}, V);
    EXPECT_NEAR(axis_difference_deg(s.theta12.theta_deg, theta), 0, kAngleTol);
    EXPECT_NEAR(axis_difference_deg(s.theta13.theta_deg, theta), 0, kAngleTol);
    EXPECT_NEAR(axis_difference_deg(s.theta23.theta_deg, theta), 0, kAngleTol);
    EXPECT_NEAR(axis_difference_deg(s.theta_sec_deg, theta), 0, kAngleTol);
    EXPECT_NEAR(s.theta12.d, 0.55, 1e-12);
  }
}

TEST(Section, EdgesBelongToTheSectionAbove) {
  // Sections [−15, 15), [15, 45), …, [135, 165), [165, 195) ≡ [−15, 15).
  EXPECT_EQ(section_of(0.0), 0);
  EXPECT_EQ(section_of(14.999999), 0);
  EXPECT_EQ(section_of(15.0), 1);
  EXPECT_EQ(section_of(44.999999), 1);
  EXPECT_EQ(section_of(45.0), 2);
  EXPECT_EQ(section_of(75.0), 3);
  EXPECT_EQ(section_of(105.0), 4);
  EXPECT_EQ(section_of(135.0), 5);
  EXPECT_EQ(section_of(164.999999), 5);
  EXPECT_EQ(section_of(165.0), 0);
  EXPECT_EQ(section_of(179.999999), 0);
  EXPECT_EQ(section_of(-0.000001), 0);
  EXPECT_EQ(section_of(180.0), 0);
}

TEST(Section, BadVoltageHasZeroSlopeAtTheSectionCentre) {
  // dV_i/dθ ∝ sin(2θ − φ_i) vanishes at the centre of the section it is excluded from.
  for (int s = 0; s < 6; ++s) {
    const int bad = bad_voltage_of(s);
    const double phi = 120.0 * bad;
    EXPECT_NEAR(std::sin(deg2rad(2 * 30.0 * s - phi)), 0.0, 1e-12) << "section " << s;
  }
  EXPECT_EQ(bad_voltage_of(0), 0);  // V1 at 0°
  EXPECT_EQ(bad_voltage_of(1), 2);  // V3 at 30°
  EXPECT_EQ(bad_voltage_of(2), 1);  // V2 at 60°
  EXPECT_EQ(bad_voltage_of(3), 0);  // V1 at 90°
  EXPECT_EQ(bad_voltage_of(4), 2);  // V3 at 120°
  EXPECT_EQ(bad_voltage_of(5), 1);  // V2 at 150°
}

TEST(Section, ThetaSecIsThePairWithoutTheBadVoltage) {
  // Spec's example: θ12 = 60° lies in [45, 75), whose bad voltage is V2, so θ_sec = θ13.
  // Perturb V2 slightly: θ12 and θ23 move, θ13 (and so θ_sec) does not.
  const CalibrationParams t = CalibrationParams::theory(kWang2019FilmAxesDeg);
  for (double theta : {46.0, 60.0, 74.0}) {
    auto V = voltages(t, theta, 0.5);
    V[1] += 1e-4;
    const SensorAngles s = sensor_angles(t, Electronics{}, V);
    EXPECT_EQ(s.section, 2);
    EXPECT_EQ(s.theta_sec_deg, s.theta13.theta_deg);
    EXPECT_NEAR(s.theta_sec_deg, theta, kAngleTol);
    EXPECT_GT(std::abs(axis_difference_deg(s.theta12.theta_deg, theta)), 1e-4);
  }
  // Around the 45° edge: just below it θ_sec = θ12 (section [15, 45), bad V3).
  const SensorAngles below = sensor_angles(t, Electronics{}, voltages(t, 44.9, 0.5));
  EXPECT_EQ(below.section, 1);
  EXPECT_EQ(below.theta_sec_deg, below.theta12.theta_deg);
  const SensorAngles above = sensor_angles(t, Electronics{}, voltages(t, 45.1, 0.5));
  EXPECT_EQ(above.section, 2);
  EXPECT_EQ(above.theta_sec_deg, above.theta13.theta_deg);
}

// ---- Eq. 15 and its fit --------------------------------------------------------------------

std::vector<Observation> table2_observations(const std::vector<double>& thetas, double d) {
  const FitParams truth = FitParams::coupled(CalibrationParams::wang2019_indoor(), d);
  std::vector<Observation> obs;
  for (double t : thetas)
    for (int i = 0; i < 3; ++i) obs.push_back({t, i, eq15_voltage(truth, 0.5, i, t)});
  return obs;
}

std::vector<double> cs_angles() {  // the paper's 19 CS points, 0°..180° every 10°
  std::vector<double> t;
  for (int k = 0; k <= 18; ++k) t.push_back(10.0 * k);
  return t;
}

FitParams nominal_start(double d) {
  return FitParams::coupled(CalibrationParams::theory(kWang2019FilmAxesDeg), d);
}

TEST(Eq15Model, AgreesWithTheDeviceModel) {
  const CalibrationParams p = CalibrationParams::wang2019_indoor();
  const FitParams f = FitParams::coupled(p, 0.55);
  for (double theta = 0; theta < 180; theta += 11) {
    const auto V = voltages(p, theta, 0.55);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(eq15_voltage(f, 0.5, i, theta), V[i], 1e-15);
  }
}

TEST(Eq15Model, DecouplingRoundTripsAndDaChangesOnlyD) {
  const CalibrationParams p = CalibrationParams::wang2019_indoor();
  const CalibrationParams q = FitParams::coupled(p, 0.55).decoupled(0.55);
  for (int m = 0; m < 6; ++m) EXPECT_NEAR(q.kd[m], p.kd[m], 1e-15);
  // Another d_a rescales kd but leaves every angle unchanged (§3.5).
  const CalibrationParams r = FitParams::coupled(p, 0.55).decoupled(0.6);
  for (double theta = 0; theta < 180; theta += 13) {
    const auto V = voltages(p, theta, 0.55);
    EXPECT_NEAR(sensor_angles(r, Electronics{}, V).theta_sec_deg,
                sensor_angles(p, Electronics{}, V).theta_sec_deg, 1e-9);
    EXPECT_NEAR(sensor_angles(r, Electronics{}, V).theta12.d, 0.6, 1e-12);
  }
}

TEST(Eq15Model, JacobianMatchesCentralDifferences) {
  // Central differences: truncation ~h²·f'''/6, rounding ~1e-16·|V|/h; with h = 1e-5 (relative)
  // both stay below 1e-9 V + 1e-7 of the derivative.
  const FitParams p = FitParams::coupled(CalibrationParams::wang2019_indoor(), 0.55);
  const FitParams::Vector x = p.vector();
  for (double theta : {0.0, 17.0, 45.0, 100.0, 163.0}) {
    for (int i = 0; i < 3; ++i) {
      const FitParams::Vector g = eq15_gradient(p, 0.5, i, theta);
      for (int c = 0; c < FitParams::kCount; ++c) {
        const double h = 1e-5 * std::max(1.0, std::abs(x(c)));
        FitParams::Vector xp = x, xm = x;
        xp(c) += h;
        xm(c) -= h;
        const double fd = (eq15_voltage(FitParams::from_vector(xp), 0.5, i, theta) -
                           eq15_voltage(FitParams::from_vector(xm), 0.5, i, theta)) / (2 * h);
        EXPECT_NEAR(g(c), fd, 1e-9 + 1e-7 * std::abs(fd))
            << "theta=" << theta << " V" << i + 1 << " x" << c;
      }
    }
  }
}

TEST(Eq15Fit, RecoversTable2FromNoiseFreeData) {
  // Spec: noise-free data from Table 2's indoor parameters are recovered to 1e-6 (angles in
  // degrees, k in mV), starting from the nominal values.
  const FitResult r = fit_eq15(table2_observations(cs_angles(), 0.55), nominal_start(0.55), 0.5);
  const CalibrationParams got = r.params.decoupled(0.55);
  const CalibrationParams want = CalibrationParams::wang2019_indoor();
  for (int m = 0; m < 6; ++m) {
    EXPECT_NEAR(got.alpha_deg[m], want.alpha_deg[m], 1e-6) << m;
    EXPECT_NEAR(got.kd[m], want.kd[m], 1e-6) << m;
  }
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(got.k_mV[i], want.k_mV[i], 1e-6) << i;
    EXPECT_NEAR(got.kv[i], want.kv[i], 1e-6) << i;
  }
  EXPECT_LT(r.residual_rms_V, 1e-12);
  EXPECT_EQ(r.observations, 57);
  EXPECT_GT(r.iterations, 0);
}

TEST(Eq15Fit, StandardErrorsMatchTheScatterOfRepeatedFits) {
  // Gaussian noise σ on every voltage: the reported standard errors must match the spread of
  // the estimates over repeated fits. With 200 fits the sample SD has ~5% relative error;
  // allow 25% (5 standard errors).
  const double sigma = 1e-4;
  const std::vector<Observation> clean = table2_observations(cs_angles(), 0.55);
  std::vector<FitParams::Vector> est;
  FitParams::Vector mean_se = FitParams::Vector::Zero();
  const int trials = 200;
  for (int t = 0; t < trials; ++t) {
    std::vector<Observation> obs = clean;
    for (std::size_t n = 0; n < obs.size(); ++n)
      obs[n].volts += sigma * standard_normal(99, static_cast<std::uint64_t>(t), n, 0);
    const FitResult r = fit_eq15(obs, nominal_start(0.55), 0.5);
    est.push_back(r.params.vector());
    mean_se += r.standard_error.vector() / trials;
  }
  for (int c : {FitParams::alpha_index(0), FitParams::alpha_index(3), FitParams::k_index(1),
                FitParams::kv_index(2), FitParams::c_index(4)}) {
    double m = 0, s = 0;
    for (const auto& e : est) m += e(c) / trials;
    for (const auto& e : est) s += (e(c) - m) * (e(c) - m) / (trials - 1);
    EXPECT_NEAR(std::sqrt(s) / mean_se(c), 1.0, 0.25) << "x" << c;
  }
}

TEST(Eq15Fit, TooFewObservationsIsAnError) {
  try {
    fit_eq15(table2_observations({0, 30, 60, 90, 120}, 0.55), nominal_start(0.55), 0.5);
    FAIL() << "expected CalibrationError";
  } catch (const CalibrationError& e) {
    EXPECT_NE(std::string(e.what()).find("V1 has 5 observation(s)"), std::string::npos) << e.what();
  }
}

TEST(Eq15Fit, AnglesThatCannotSeparateTheParametersAreAnError) {
  // Six stops but only two distinct polarization angles (mod 180°): rank deficient.
  try {
    fit_eq15(table2_observations({0, 180, 360, 90, 270, 450}, 0.55), nominal_start(0.55), 0.5);
    FAIL() << "expected CalibrationError";
  } catch (const CalibrationError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot determine"), std::string::npos) << e.what();
  }
}

TEST(Eq15Fit, UnpolarizedLightIsAnError) {
  // d = 0: no voltage depends on α or on the angle; nothing can be calibrated.
  EXPECT_THROW(fit_eq15(table2_observations(cs_angles(), 0.0), nominal_start(0.0), 0.5),
               CalibrationError);
}

}  // namespace
}  // namespace polrig
