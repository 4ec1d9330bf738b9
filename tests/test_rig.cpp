// Rig kinematics: positions, the rotation sign convention, schedules.
#include <gtest/gtest.h>

#include <cmath>

#include "polrig/geometry/geometry.h"
#include "polrig/rig/rig.h"
#include "polrig/geometry/schedule.h"

namespace polrig {
namespace {

constexpr double kTight = 1e-12;  // mm: rounding of a few trigonometric evaluations

TEST(Geometry, CentredSensorPutsPhotodiodeOneOnTheXAxis) {
  const PhotodiodeRing ring;
  const Eccentricity centred{0, 0, 0, 0};
  const auto p = photodiode_positions(ring, centred, 0.0);
  EXPECT_NEAR(p[0].x(), 14.0, kTight);
  EXPECT_NEAR(p[0].y(), 0.0, kTight);
  // β_m = −60°·(m−1): photodiode 2 at −60°.
  EXPECT_NEAR(p[1].x(), 14.0 * 0.5, kTight);
  EXPECT_NEAR(p[1].y(), -14.0 * std::sqrt(3.0) / 2.0, kTight);
}

TEST(Geometry, TableTurnsTheSensorAnticlockwise) {
  // P(θ_R) = Rot(θ_R)·P(0): a quarter turn takes photodiode 1 from +x to +y.
  const PhotodiodeRing ring;
  const auto p = photodiode_positions(ring, Eccentricity{0, 0, 0, 0}, 90.0);
  EXPECT_NEAR(p[0].x(), 0.0, kTight);
  EXPECT_NEAR(p[0].y(), 14.0, kTight);
}

TEST(Geometry, SensorOffsetTurnsWithTheTable) {
  const Eccentricity e{0.0, 0.0, 0.5, 30.0};
  const Point2 at0 = sensor_centre(e, 0.0);
  EXPECT_NEAR(at0.x(), 0.5 * std::cos(M_PI / 6), kTight);
  EXPECT_NEAR(at0.y(), 0.5 * std::sin(M_PI / 6), kTight);
  const Point2 at60 = sensor_centre(e, 60.0);  // now at 90°
  EXPECT_NEAR(at60.x(), 0.0, kTight);
  EXPECT_NEAR(at60.y(), 0.5, kTight);
  // Distances from O_R stay fixed during the turn (the L_Rm of Eq. 6).
  const PhotodiodeRing ring;
  const auto p0 = photodiode_positions(ring, e, 0.0);
  const auto p1 = photodiode_positions(ring, e, 123.0);
  for (int m = 0; m < 6; ++m) EXPECT_NEAR(p0[m].norm(), p1[m].norm(), kTight);
}

TEST(Geometry, PortCentreIsFixed) {
  const Point2 port = port_centre(Eccentricity{0.05, 90.0, 0.0, 0.0});
  EXPECT_NEAR(port.x(), 0.0, kTight);
  EXPECT_NEAR(port.y(), 0.05, kTight);
}

TEST(Geometry, PolarizationAngleFollowsTheTableAngle) {
  // θ = θ_R − ψ_P in the sensor's top-view frame (docs/physics.md, "Sign conventions").
  EXPECT_DOUBLE_EQ(sensor_polarization_angle_deg(30.0, 0.0), 30.0);
  EXPECT_DOUBLE_EQ(sensor_polarization_angle_deg(30.0, 10.0), 20.0);
  EXPECT_DOUBLE_EQ(sensor_polarization_angle_deg(190.0, 0.0), 10.0);
  EXPECT_DOUBLE_EQ(sensor_polarization_angle_deg(0.0, 10.0), 170.0);
  EXPECT_DOUBLE_EQ(sensor_polarization_angle_deg(360.0, 0.0), 0.0);
}

TEST(Schedule, PaperIndoorScheduleHas37StopsWithBothEnds) {
  const Schedule s;  // 0°:10°:360°
  const auto a = s.table_angles_deg();
  ASSERT_EQ(a.size(), 37u);
  EXPECT_EQ(a.front(), 0.0);
  EXPECT_EQ(a.back(), 360.0);
  EXPECT_EQ(a[18], 180.0);
}

TEST(Schedule, StopIsIncludedOnlyWhenReachedByWholeSteps) {
  Schedule s;
  s.start_deg = 0;
  s.step_deg = 0.1;
  s.stop_deg = 1.0;  // 0.1 is inexact in binary; the end point must still be found
  EXPECT_EQ(s.table_angles_deg().size(), 11u);
  s.stop_deg = 1.05;
  EXPECT_EQ(s.table_angles_deg().size(), 11u);
}

TEST(Schedule, ExplicitAnglesReplaceStartStepStop) {
  Schedule s;
  s.angles_deg = {5, 185, 17};
  EXPECT_EQ(s.table_angles_deg(), (std::vector<double>{5, 185, 17}));
}

// Spec sky-and-compasses.md §1.4: the paper's 10° steps at 5°/s with 1 s of dwell are 3 s per
// stop, so the 37 stops of 0:10:360 span 108 s.
TEST(Schedule, StopTimesOfThePapersTurnAreThreeSecondsApart) {
  const Schedule s;  // 0:10:360, 5°/s, 1 s dwell
  const std::vector<double> t = s.stop_times_s();
  ASSERT_EQ(t.size(), 37u);
  for (std::size_t k = 0; k < t.size(); ++k) EXPECT_NEAR(t[k], 3.0 * static_cast<double>(k), 1e-12) << k;
}

// An explicit list turns by |Δθ| whatever the direction: 5 → 185 → 17 is 180° then 168°.
TEST(Schedule, StopTimesFollowTheAnglesTurned) {
  Schedule s;
  s.angles_deg = {5, 185, 17};
  s.speed_deg_s = 10;
  s.dwell_s = 2;
  EXPECT_EQ(s.stop_times_s(), (std::vector<double>{0, 18 + 2, 18 + 16.8 + 4}));
}

}  // namespace
}  // namespace polrig
