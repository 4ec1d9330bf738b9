// Optics: the sheet polarizer's Mueller matrix (Malus's law with τM and τm) and the traced
// plano-convex lens (its focus against the lensmaker's equation).
#include <gtest/gtest.h>

#include <cmath>

#include "polrig/optics/lens.h"
#include "polrig/optics/polarizer.h"

namespace polrig {
namespace {

constexpr double kExact = 1e-14;

TEST(Polarizer, UnpolarizedLightPassesTheMeanTransmittance) {
  const Stokes out = linear_polarizer(0.62, 0.18, 37.0) * unpolarized(1.0);
  EXPECT_NEAR(out(0), 0.5 * (0.62 + 0.18), kExact);
  // …and leaves polarized along the axis with d = (τM − τm)/(τM + τm).
  EXPECT_NEAR(std::hypot(out(1), out(2)) / out(0), 0.44 / 0.80, kExact);
  EXPECT_NEAR(0.5 * std::atan2(out(2), out(1)) * 180 / M_PI, 37.0, 1e-12);
}

TEST(Polarizer, MalusLawWithTauMAndTaum) {
  // Fully polarized light at Δ from the axis: T = τM·cos²Δ + τm·sin²Δ.
  for (double delta = 0; delta <= 180; delta += 15) {
    const Stokes out = linear_polarizer(0.62, 0.18, 10.0) * linearly_polarized(1.0, 1.0, 10.0 + delta);
    const double c = std::cos(delta * M_PI / 180), s = std::sin(delta * M_PI / 180);
    EXPECT_NEAR(out(0), 0.62 * c * c + 0.18 * s * s, kExact) << delta;
  }
}

TEST(Polarizer, CrossedAndRotatedFilms) {
  // Two films at Δ on unpolarized light: ½[(τM² + τm²)cos²Δ + 2τMτm·sin²Δ]; crossed (Δ = 90°):
  // τM·τm.
  const double M = 0.62, m = 0.18;
  for (double delta : {0.0, 30.0, 45.0, 60.0, 90.0}) {
    const Stokes out = linear_polarizer(M, m, 20.0 + delta) * (linear_polarizer(M, m, 20.0) * unpolarized(1.0));
    const double c = std::cos(delta * M_PI / 180), s = std::sin(delta * M_PI / 180);
    EXPECT_NEAR(out(0), 0.5 * ((M * M + m * m) * c * c + 2 * M * m * s * s), kExact) << delta;
  }
  const Stokes crossed = linear_polarizer(M, m, 90.0) * (linear_polarizer(M, m, 0.0) * unpolarized(1.0));
  EXPECT_NEAR(crossed(0), M * m, kExact);
}

TEST(Polarizer, FrameRotationTurnsTheAngle) {
  const Stokes s = frame_rotation(25.0) * linearly_polarized(1.0, 0.5, 40.0);
  EXPECT_NEAR(0.5 * std::atan2(s(2), s(1)) * 180 / M_PI, 15.0, 1e-12);
}

TEST(Lens, FresnelTransmittanceAtNormalIncidence) {
  // 1 − ((n − 1)/(n + 1))² at normal incidence, both ways.
  const double n = 1.5168, r = (n - 1) / (n + 1);
  EXPECT_NEAR(fresnel_transmittance(1.0, n, 1.0), 1 - r * r, kExact);
  EXPECT_NEAR(fresnel_transmittance(n, 1.0, 1.0), 1 - r * r, kExact);
  EXPECT_EQ(fresnel_transmittance(n, 1.0, std::cos(60 * M_PI / 180)), 0.0);  // beyond critical
}

TEST(Lens, TracedFocusMatchesTheLensmakersEquation) {
  // The seed lens: f = 50 mm, Ø 12.7 mm, t = 3.5 mm, N-BK7. Rays parallel to the axis from the
  // port side at height h cross the axis behind the plane face at BFL = f − t/n (thick lens,
  // one flat side). Spherical aberration moves the crossing by −k·h² (k ≈ n²/(2f(n − 1)²)·…); at
  // h = 0.05 mm it is below 1e-4 mm, so the paraxial rays must land within 1e-3 mm. The
  // marginal ray (h = 6 mm) must fall short, as a spherical lens does.
  const PlanoConvexLens lens = PlanoConvexLens::from_focal_length(50.0, 3.5, 12.7, 1.5168);
  const auto crossing = [&](double h) {
    const auto out = trace_through(lens, LensRay{{h, 0, 10}, {0, 0, -1}, 1});
    EXPECT_TRUE(out.has_value());
    return out->origin[2] + out->origin[0] / -out->direction[0] * out->direction[2];
  };
  EXPECT_NEAR(-crossing(0.05), lens.back_focal_length(), 1e-3);
  EXPECT_NEAR(lens.back_focal_length(), 50.0 - 3.5 / 1.5168, kExact);
  EXPECT_LT(-crossing(6.0), lens.back_focal_length() - 0.1);
  // Reversibility: a ray traced up and then down returns to itself.
  const LensRay up{{0.3, -0.2, -40}, {0.01, 0.02, 1}, 1};
  LensRay u = up;
  const double norm = std::sqrt(1 + 0.01 * 0.01 + 0.02 * 0.02);
  for (double& c : u.direction) c /= norm;
  const auto through = trace_through(lens, u);
  ASSERT_TRUE(through.has_value());
  LensRay back{through->origin, {-through->direction[0], -through->direction[1], -through->direction[2]}, 1};
  back.origin[2] += 1e-9;  // just outside the convex face
  for (int k = 0; k < 3; ++k) back.origin[k] -= back.direction[k] * 1e-6;
  const auto again = trace_through(lens, back);
  ASSERT_TRUE(again.has_value());
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(again->direction[k], -u.direction[k], 1e-9);
  EXPECT_NEAR(again->transmittance, through->transmittance, 1e-12);
}

TEST(Lens, RaysOutsideTheApertureAreBlocked) {
  const PlanoConvexLens lens = PlanoConvexLens::from_focal_length(50.0, 3.5, 12.7, 1.5168);
  EXPECT_FALSE(trace_through(lens, LensRay{{7.0, 0, 10}, {0, 0, -1}, 1}).has_value());
}

}  // namespace
}  // namespace polrig
