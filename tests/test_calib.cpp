// Angles from voltages (Eq. 2, Eqs. 16–19) and the section algorithm.
#include <gtest/gtest.h>

#include <cmath>

#include "polrig/calib/angles.h"
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

}  // namespace
}  // namespace polrig
