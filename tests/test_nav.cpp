// compass/heading: the closed-form heading from one E-vector (W19 Eqs. 22–25, spec §1.5), checked
// against a forward model written here with Eigen's AngleAxis (independent of the solver's own
// rotation helpers), and the sign conventions of spec §0.
#include <cmath>
#include <numbers>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "polrig/compass/heading.h"
#include "polrig/random.h"
#include "polrig/units.h"

namespace {
using namespace polrig;
using Eigen::AngleAxisd;
using Eigen::Matrix3d;
using Eigen::Vector3d;

double rad(double deg) { return deg * std::numbers::pi / 180.0; }
double deg(double r) { return r * 180.0 / std::numbers::pi; }

// C_b^n of the spec: Rz(−H)·Rx(pitch)·Ry(roll), active right-hand rotations.
Matrix3d body_to_n(double H, double roll, double pitch) {
  return (AngleAxisd(-rad(H), Vector3d::UnitZ()) * AngleAxisd(rad(pitch), Vector3d::UnitX()) *
          AngleAxisd(rad(roll), Vector3d::UnitY()))
      .toRotationMatrix();
}

Vector3d sun_enu(double A, double h) {  // spec §0: A from north towards east
  return {std::cos(rad(h)) * std::sin(rad(A)), std::cos(rad(h)) * std::cos(rad(A)), std::sin(rad(h))};
}

// θ_b seen by a sensor looking along Z_b of C (body → n): e = s × v / |s × v| (spec §1.2),
// e_b = Cᵀ·e, θ_b = atan2(e_b,y, e_b,x), anticlockwise from X_b seen from above.
double theta_b(const Matrix3d& C, const Vector3d& s) {
  const Vector3d v = C * Vector3d::UnitZ();
  const Vector3d e_b = C.transpose() * s.cross(v).normalized();
  return deg(std::atan2(e_b.y(), e_b.x()));
}

Vec3 to_vec3(const Vector3d& v) { return {v.x(), v.y(), v.z()}; }

double circ(double a, double b) { return std::abs(heading_difference_deg(a, b)); }

struct Pose {
  double H, roll, pitch, A, h;
};
Pose random_pose(std::uint64_t k) {
  const auto u = [&](std::uint64_t c) { return uniform_unit(20260522, k, 9, c); };
  return {360.0 * u(0), -15.0 + 30.0 * u(1), -15.0 + 30.0 * u(2), 360.0 * u(3), 1.0 + 69.0 * u(4)};
}

TEST(Heading, RecoversRandomTiltedPosesTo1e9Degrees) {
  double worst = 0, worst_prior = 0;
  int front_checked = 0;
  for (std::uint64_t k = 0; k < 2000; ++k) {
    const Pose p = random_pose(k);
    const Vector3d s = sun_enu(p.A, p.h);
    const Matrix3d C = body_to_n(p.H, p.roll, p.pitch);
    const double th = theta_b(C, s);
    const Tilt tilt{p.roll, p.pitch};
    const HeadingSolution r = solve_heading(to_vec3(s), th, tilt);
    ASSERT_EQ(r.status, HeadingStatus::Ok) << k;
    // One of the two roots is the truth.
    const double e = std::min(circ(r.heading_deg, p.H), circ(r.heading_alt_deg, p.H));
    worst = std::max(worst, e);
    // Without a prior the chosen root has the sun in front (forward body component larger).
    const double fwd_true = (C.transpose() * s).y();
    if (fwd_true > 0.05 && circ(r.heading_deg, r.heading_alt_deg) > 10.0) {
      EXPECT_LT(circ(r.heading_deg, p.H), 1e-9) << k;
      ++front_checked;
    }
    // With a prior 5° off the truth, the chosen root is the truth (when the roots are apart).
    if (circ(r.heading_deg, r.heading_alt_deg) > 20.0) {
      const HeadingSolution q = solve_heading(to_vec3(s), th, tilt, p.H + 5.0);
      EXPECT_TRUE(q.from_prior);
      worst_prior = std::max(worst_prior, circ(q.heading_deg, p.H));
    }
  }
  EXPECT_LT(worst, 1e-9);
  EXPECT_LT(worst_prior, 1e-9);
  EXPECT_GT(front_checked, 800);
  std::printf("worst heading error over 2000 tilted poses: %.3g deg (prior: %.3g deg); "
              "sun-in-front choice checked on %d\n", worst, worst_prior, front_checked);
}

// Spec §0: turn the device +10° anticlockwise seen from above (a right-hand rotation about the
// up axis of n): the heading, clockwise from north, falls by 10°.
TEST(Heading, TurningAnticlockwiseLowersTheHeading) {
  for (std::uint64_t k = 0; k < 200; ++k) {
    const Pose p = random_pose(k + 5000);
    const Vector3d s = sun_enu(p.A, p.h);
    const Matrix3d C0 = body_to_n(p.H, p.roll, p.pitch);
    const Matrix3d C1 = AngleAxisd(rad(10.0), Vector3d::UnitZ()).toRotationMatrix() * C0;
    const HeadingSolution r0 = solve_heading(to_vec3(s), theta_b(C0, s), {p.roll, p.pitch}, p.H);
    // The turned body's roll and pitch are unchanged (the turn is about the vertical). The
    // prior is the unturned heading, not the answer: of the roots H − 10 and H + 170 it picks
    // the one 10° away.
    const HeadingSolution r1 = solve_heading(to_vec3(s), theta_b(C1, s), {p.roll, p.pitch}, p.H);
    EXPECT_NEAR(heading_difference_deg(r1.heading_deg, r0.heading_deg), -10.0, 1e-9) << k;
  }
}

// Level: H = A_s + θ_b (mod 180°), both roots.
TEST(Heading, LevelCaseIsSunAzimuthPlusAngle) {
  for (std::uint64_t k = 0; k < 200; ++k) {
    const Pose p = random_pose(k + 9000);
    const Vector3d s = sun_enu(p.A, p.h);
    const double th = theta_b(body_to_n(p.H, 0, 0), s);
    const HeadingSolution r = solve_heading(to_vec3(s), th, {});
    EXPECT_NEAR(axis_difference_deg(r.heading_deg, p.A + th), 0.0, 1e-9);
    EXPECT_NEAR(axis_difference_deg(r.heading_alt_deg, p.A + th), 0.0, 1e-9);
    EXPECT_NEAR(circ(r.heading_deg, r.heading_alt_deg), 180.0, 1e-9);
    // The level sun in front: s_b,y = cos h·cos(A − H) > 0 at the chosen root.
    EXPECT_GT(std::cos(rad(p.A - r.heading_deg)), 0.0);
  }
}

// The level check printed in spec §1.5: s_b = cos h·(sin(A − H), cos(A − H), tan h).
TEST(Heading, LevelSunInBodyFrame) {
  for (std::uint64_t k = 0; k < 100; ++k) {
    const Pose p = random_pose(k + 12000);
    const Vec3 s = to_vec3(sun_enu(p.A, p.h));
    const Vec3 sb = enu_to_body(s, p.H, {});
    const double ch = std::cos(rad(p.h));
    EXPECT_NEAR(sb[0], ch * std::sin(rad(p.A - p.H)), 1e-15);
    EXPECT_NEAR(sb[1], ch * std::cos(rad(p.A - p.H)), 1e-15);
    EXPECT_NEAR(sb[2], ch * std::tan(rad(p.h)), 1e-15);
  }
}

// The solver's own rotations agree with the spec's C_b^n (Eigen, above) for tilted poses.
TEST(Heading, BodyToEnuIsTheSpecsRotation) {
  for (std::uint64_t k = 0; k < 100; ++k) {
    const Pose p = random_pose(k + 13000);
    const Matrix3d C = body_to_n(p.H, p.roll, p.pitch);
    const Vector3d w(0.3, -0.5, 0.8);
    const Vec3 n = body_to_enu(to_vec3(w), p.H, {p.roll, p.pitch});
    const Vec3 b = enu_to_body(to_vec3(w), p.H, {p.roll, p.pitch});
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(n[i], (C * w)(i), 1e-15);
      EXPECT_NEAR(b[i], (C.transpose() * w)(i), 1e-15);
    }
  }
  // Senses: pitch up lifts the nose, roll positive lowers the right side.
  EXPECT_GT(body_to_enu({0, 1, 0}, 0, {0, 10})[2], 0.0);
  EXPECT_LT(body_to_enu({1, 0, 0}, 0, {10, 0})[2], 0.0);
  // Heading 90°: forward points east.
  EXPECT_NEAR(body_to_enu({0, 1, 0}, 90, {})[0], 1.0, 1e-15);
}

TEST(Heading, NoSolutionWithTheSunAtTheZenith) {
  const HeadingSolution r = solve_heading({0, 0, 1}, 30.0, {3, -2});
  EXPECT_EQ(r.status, HeadingStatus::SunNearZenithOrVerticalE);
  EXPECT_EQ(heading_status_name(r.status), "sun-near-zenith-or-vertical-e");
  EXPECT_FALSE(has_heading(r.status));
  EXPECT_TRUE(std::isnan(r.heading_deg));
  // Just inside the default threshold (horizontal part sin 1°): 89.5° elevation, level.
  EXPECT_EQ(solve_heading(to_vec3(sun_enu(40, 89.5)), 30.0, {}).status,
            HeadingStatus::SunNearZenithOrVerticalE);
  EXPECT_EQ(solve_heading(to_vec3(sun_enu(40, 88.5)), 30.0, {}).status, HeadingStatus::Ok);
}

// A sun vector that is not of unit length is refused, not solved into a wrong heading or NaN.
TEST(Heading, NonUnitSunIsRefused) {
  for (const Vec3& s : {Vec3{2, 0, 0}, Vec3{0, 0, 0}, Vec3{0.6, 0.8 + 1e-8, 0}}) {
    EXPECT_THROW(solve_heading(s, 30.0, {}), std::invalid_argument);
    EXPECT_THROW(sky_view_body(s, 10.0, {}), std::invalid_argument);
  }
  try {
    solve_heading({2, 0, 0}, 30.0, {});
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("sun_enu (2, 0, 0) has length 2"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(solve_heading({0.6, 0.8, 1e-10}, 30.0, {}));
}

// The same test fires with a low sun when the E-vector is nearly vertical: pitch 89.5°,
// θ_b = 90° (e_b forward) gives u = Rx(89.5°)·Y = (0, cos 89.5°, sin 89.5°), so
// √(a²+b²) = cos 89.5°·cos h_s < sin 1° for any sun.
TEST(Heading, NoSolutionWithTheEVectorNearlyVertical) {
  for (const double el : {0.0, 20.0, 45.0}) {
    EXPECT_EQ(solve_heading(to_vec3(sun_enu(40, el)), 90.0, {0, 89.5}).status,
              HeadingStatus::SunNearZenithOrVerticalE) << el;
    // Pitch 80°: √(a²+b²) = cos 80°·cos h_s is above sin 1° (the tangent test then decides).
    EXPECT_NE(solve_heading(to_vec3(sun_enu(40, el)), 90.0, {0, 80}).status,
              HeadingStatus::SunNearZenithOrVerticalE) << el;
  }
}

// Pitch 15°, θ_b = 90° (e_b forward): q = c/√(a² + b²) = −tan 15°·tan h_s, so |q| = 1 at
// h_s = 75°: just past it is noise (clamped, one double root), further on no heading fits.
TEST(Heading, TangentIsClampedWithinTheToleranceElseInconsistent) {
  const double t15 = std::tan(rad(15));
  const double h_clamp = deg(std::atan((1 + 5e-7) / t15));
  const double h_bad = deg(std::atan((1 + 2e-6) / t15));
  const double h_ok = deg(std::atan((1 - 1e-3) / t15));
  const Tilt tilt{0, 15};
  const HeadingSolution c = solve_heading(to_vec3(sun_enu(123, h_clamp)), 90.0, tilt);
  EXPECT_EQ(c.status, HeadingStatus::Clamped);
  EXPECT_TRUE(has_heading(c.status));
  EXPECT_EQ(c.heading_deg, c.heading_alt_deg);
  EXPECT_EQ(solve_heading(to_vec3(sun_enu(123, h_bad)), 90.0, tilt).status,
            HeadingStatus::Inconsistent);
  EXPECT_EQ(solve_heading(to_vec3(sun_enu(123, h_ok)), 90.0, tilt).status, HeadingStatus::Ok);
  // The clamped root: at the tangent, H = atan2(b, a) ∓ 0 = A_s (+180°: q = −1 gives acos = 180°).
  EXPECT_NEAR(circ(c.heading_deg, 123 + 180), 0.0, 1e-6);
}

// The forward model through the sky (sky_light) agrees with the one written here, and with the
// solver closes the loop.
TEST(Heading, SkyViewMatchesTheIndependentForwardModel) {
  SkyModel sky;
  sky.P_max.constant = 0.61;
  for (std::uint64_t k = 0; k < 300; ++k) {
    const Pose p = random_pose(k + 20000);
    const Vector3d s = sun_enu(p.A, p.h);
    const Matrix3d C = body_to_n(p.H, p.roll, p.pitch);
    const BodySkyView view = sky_view_body(to_vec3(s), p.H, {p.roll, p.pitch}, sky);
    EXPECT_NEAR(axis_difference_deg(view.aop_body_deg, theta_b(C, s)), 0.0, 1e-10);
    const double cg = s.dot(C.col(2));
    EXPECT_NEAR(view.dop, 0.61 * (1 - cg * cg) / (1 + cg * cg), 1e-14);
    const HeadingSolution r = solve_heading(to_vec3(s), view.aop_body_deg, {p.roll, p.pitch}, p.H + 1);
    EXPECT_LT(circ(r.heading_deg, p.H), 1e-9);
  }
}

}  // namespace
