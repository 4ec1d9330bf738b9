// Optics: the sheet polarizer's Mueller matrix (Malus's law with τM and τm), the traced
// plano-convex lens (its focus against the lensmaker's equation) and polarization ray tracing
// (sheet polarizers at oblique incidence, Fresnel refraction, frames), each against a closed form.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <utility>

#include "polrig/optics/lens.h"
#include "polrig/optics/polarized_ray.h"
#include "polrig/optics/polarizer.h"
#include "polrig/random.h"

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

// A meridional ray parallel to the axis at height h, from the port side, through the seed lens
// traced in the test by Snell's law in angles: where it crosses the axis, below the plane face.
double snell_axis_crossing(double h, double R, double t, double n) {
  const double z1 = t - R + std::sqrt(R * R - h * h);  // on the convex face
  const double i1 = std::asin(h / R), r1 = std::asin(std::sin(i1) / n);
  const double g = i1 - r1;                             // the ray's angle to the axis in the glass
  const double x2 = h - z1 * std::tan(g);               // height on the plane face
  const double g2 = std::asin(n * std::sin(g));         // and in air below it
  return -x2 / std::tan(g2);
}

TEST(Lens, TracedFocusMatchesTheLensmakersEquation) {
  // The seed lens: f = 50 mm, Ø 12.7 mm, t = 3.5 mm, N-BK7; R = f(n − 1) (lensmaker, one flat
  // side). The traced axis crossing must equal the test's own Snell trace at every height, and
  // the paraxial one the thick-lens focus from ray-transfer matrices: refraction by the convex
  // face (power (n − 1)/R), a reduced thickness t/n, the plane face (power 0).
  const double f = 50.0, t = 3.5, n = 1.5168, R = f * (n - 1);
  const PlanoConvexLens lens = PlanoConvexLens::from_focal_length(f, t, 12.7, n);
  const auto crossing = [&](double h) {
    const auto out = trace_through(lens, LensRay{{h, 0, 10}, {0, 0, -1}, 1});
    EXPECT_TRUE(out.has_value());
    return out->origin[2] + out->origin[0] / -out->direction[0] * out->direction[2];
  };
  for (double h : {0.05, 1.0, 3.0, 6.0}) EXPECT_NEAR(crossing(h), snell_axis_crossing(h, R, t, n), 1e-9) << h;
  Eigen::Matrix2d refraction, transfer;
  refraction << 1, 0, -(n - 1) / R, 1;
  transfer << 1, t / n, 0, 1;
  const Eigen::Vector2d out = transfer * refraction * Eigen::Vector2d(1, 0);  // height, reduced angle
  const double bfl = -out(0) / out(1);
  // Spherical aberration moves the crossing by O(h²/f) · (a few): below 1e-4 mm at h = 0.05 mm.
  EXPECT_NEAR(-crossing(0.05), bfl, 1e-4);
  EXPECT_NEAR(lens.back_focal_length(), bfl, 1e-12);
  EXPECT_LT(-crossing(6.0), bfl - 0.1);  // the marginal ray falls short, as a spherical lens does
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


// ---- Polarization ray tracing ----

constexpr double kTight = 1e-12;

double dot3(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec3 cross3(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
Vec3 unit3(const Vec3& a) {
  const double n = std::sqrt(dot3(a, a));
  return {a[0] / n, a[1] / n, a[2] / n};
}
double rad(double deg) { return deg * M_PI / 180; }
// (sinθ cosφ, sinθ sinφ, cosθ).
Vec3 direction(double theta_deg, double phi_deg) {
  const double t = rad(theta_deg), p = rad(phi_deg);
  return {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
}
Vec3 random_direction(std::uint64_t i) {
  const double z = 2 * uniform_unit(11, i, 0, 0) - 1, az = 2 * M_PI * uniform_unit(11, i, 1, 0);
  const double r = std::sqrt(1 - z * z);
  return {r * std::cos(az), r * std::sin(az), z};
}
// A physical Stokes vector: S0 in (0.5, 1.5], degree of polarization in (0.2, 1].
Stokes random_stokes(std::uint64_t i) {
  const double S0 = 0.5 + uniform_unit(7, i, 0, 0), p = 0.2 + 0.8 * uniform_unit(7, i, 1, 0);
  const Vec3 d = random_direction(1000 + i);
  return Stokes(S0, S0 * p * d[0], S0 * p * d[1], S0 * p * d[2]);
}
// The 3-D direction of the polarization ellipse's major axis (up to sign).
Vec3 major_axis(const PolarizedRay& r) {
  const double psi = 0.5 * std::atan2(r.S(2), r.S(1));
  const Vec3 y = cross3(r.k, r.x_hat);
  return {std::cos(psi) * r.x_hat[0] + std::sin(psi) * y[0], std::cos(psi) * r.x_hat[1] + std::sin(psi) * y[1],
          std::cos(psi) * r.x_hat[2] + std::sin(psi) * y[2]};
}
void expect_stokes_near(const Stokes& a, const Stokes& b, double tol) {
  for (int c = 0; c < 4; ++c) EXPECT_NEAR(a(c), b(c), tol) << "component " << c;
}

TEST(PolarizedRay, SheetPolarizerAtNormalIncidenceIsTheLinearPolarizer) {
  // A ray along ±z with x_hat = lab x (what unpolarized_ray picks): going up its frame is the lab
  // frame; going down y_hat = −y, so S_ray = diag(1, 1, −1, −1)·S_lab. Either way, through a film
  // in the z = const plane (either normal) and back in the frame x_hat = x, S must be
  // linear_polarizer(τM, τm, ψ)·S_lab in the lab frame.
  EXPECT_EQ(unpolarized_ray({0, 0, -1}, 1.0).x_hat, (Vec3{1, 0, 0}));
  EXPECT_EQ(unpolarized_ray({0, 0, 1}, 1.0).x_hat, (Vec3{1, 0, 0}));
  const MuellerMatrix mirror = Eigen::Vector4d(1, 1, -1, -1).asDiagonal();
  const double M = 0.62, m = 0.18;
  for (double psi : {0.0, 25.0, 90.0, 137.0})
    for (double kz : {-1.0, 1.0})
      for (double nz : {1.0, -1.0})
        for (std::uint64_t i = 0; i < 8; ++i) {
          const Stokes S_lab = random_stokes(i);
          const MuellerMatrix to_ray = kz < 0 ? mirror : MuellerMatrix::Identity();
          PolarizedRay ray{{0, 0, kz}, {1, 0, 0}, to_ray * S_lab};
          pass_sheet_polarizer(ray, {0, 0, nz}, {std::cos(rad(psi)), std::sin(rad(psi)), 0}, M, m);
          set_frame(ray, {1, 0, 0});
          expect_stokes_near(ray.S, to_ray * (linear_polarizer(M, m, psi) * S_lab), kTight);
        }
}

TEST(PolarizedRay, CrossedIdealPolarizersLeakOffAxis) {
  // Absorption axes m1 = x, m2 = y (films in z = const): unpolarized light leaves the first film
  // polarized along e1 = k × x with τM/2, the second passes cos²χ of it along e2 = k × y.
  const double M = 0.9;
  const auto leak = [&](double theta, double phi, double sign) {
    const Vec3 d = direction(theta, phi);
    PolarizedRay ray = unpolarized_ray({sign * d[0], sign * d[1], sign * d[2]}, 1.0);
    pass_sheet_polarizer(ray, {0, 0, 1}, {0, -1, 0}, M, 0.0);  // m1 = z × (−y) = x
    pass_sheet_polarizer(ray, {0, 0, 1}, {1, 0, 0}, M, 0.0);   // m2 = z × x = y
    return ray.S(0);
  };
  for (double sign : {1.0, -1.0})
    for (double theta : {0.0, 20.0, 45.0, 70.0})
      for (double phi : {0.0, 30.0, 45.0, 60.0, 90.0, 135.0, 200.0}) {
        const double st = std::sin(rad(theta)), ct = std::cos(rad(theta));
        const double sp = std::sin(rad(phi)), cp = std::cos(rad(phi));
        const double cos_chi =
            -st * st * sp * cp / (std::sqrt(ct * ct + st * st * sp * sp) * std::sqrt(ct * ct + st * st * cp * cp));
        EXPECT_NEAR(leak(theta, phi, sign), 0.5 * M * M * cos_chi * cos_chi, 1e-14) << theta << " " << phi;
      }
  EXPECT_NEAR(leak(45, 0, -1), 0.0, 1e-15);
  EXPECT_NEAR(leak(45, 90, -1), 0.0, 1e-15);
  EXPECT_NEAR(leak(45, 45, -1), 0.5 * M * M / 9, 1e-14);  // cos χ = −1/3
  EXPECT_GT(leak(45, 45, -1), leak(45, 30, -1));
  EXPECT_GT(leak(45, 45, -1), leak(45, 60, -1));
}

TEST(PolarizedRay, ObliqueSheetPolarizerPassesTheOrdinaryWave) {
  // Linear light along v (⊥ k) through a film of normal z, axis a, at oblique k: the field splits
  // onto e_t = unit(k × m), m = z × a, and e_a = k × e_t, so S0 = τM(v·e_t)² + τm(v·e_a)² and
  // the light leaves linear along √τM(v·e_t)·e_t + √τm(v·e_a)·e_a. (Crossed films cannot tell this
  // from "the axis projected ⊥ k"; a single film can.)
  const double M = 0.62, m = 0.18;
  for (std::uint64_t i = 0; i < 24; ++i) {
    const double psi = 180 * uniform_unit(13, i, 0, 0);
    const Vec3 a{std::cos(rad(psi)), std::sin(rad(psi)), 0};
    const Vec3 d = direction(15 + 60 * uniform_unit(13, i, 1, 0), 360 * uniform_unit(13, i, 2, 0));
    const Vec3 k{d[0], d[1], -d[2]};
    const Vec3 v = unit3(cross3(k, random_direction(200 + i)));  // a random direction ⊥ k
    PolarizedRay ray{k, v, Stokes(1, 1, 0, 0)};
    pass_sheet_polarizer(ray, {0, 0, 1}, a, M, m);
    const Vec3 e_t = unit3(cross3(k, cross3({0, 0, 1}, a))), e_a = cross3(k, e_t);
    const double vt = dot3(v, e_t), va = dot3(v, e_a);
    EXPECT_NEAR(ray.S(0), M * vt * vt + m * va * va, kTight);
    EXPECT_NEAR(ray.S.tail<3>().norm(), ray.S(0), kTight);  // still fully polarized
    const Vec3 field = unit3({std::sqrt(M) * vt * e_t[0] + std::sqrt(m) * va * e_a[0],
                              std::sqrt(M) * vt * e_t[1] + std::sqrt(m) * va * e_a[1],
                              std::sqrt(M) * vt * e_t[2] + std::sqrt(m) * va * e_a[2]});
    EXPECT_NEAR(std::abs(dot3(major_axis(ray), field)), 1.0, kTight);
    EXPECT_NEAR(std::abs(dot3(ray.x_hat, e_t)), 1.0, kTight);
  }
}

TEST(PolarizedRay, ParallelFilmsFollowMalusWithBothTaus) {
  // Two films at Δ, normal incidence, unpolarized light: ½[(τM² + τm²)cos²Δ + 2τMτm·sin²Δ].
  const double M = 0.62, m = 0.18;
  const auto axis = [](double deg) { return Vec3{std::cos(rad(deg)), std::sin(rad(deg)), 0}; };
  for (double delta : {0.0, 30.0, 45.0, 60.0, 90.0, 150.0}) {
    PolarizedRay ray = unpolarized_ray({0, 0, -1}, 1.0);
    pass_sheet_polarizer(ray, {0, 0, 1}, axis(20), M, m);
    pass_sheet_polarizer(ray, {0, 0, 1}, axis(20 + delta), M, m);
    const double c = std::cos(rad(delta)), s = std::sin(rad(delta));
    EXPECT_NEAR(ray.S(0), 0.5 * ((M * M + m * m) * c * c + 2 * M * m * s * s), kTight) << delta;
  }
}

TEST(PolarizedRay, SheetPairClosedFormIsTheMuellerChain) {
  // The closed form a1·a2 + b1·b2·cos 2χ against the two frame rotations and diattenuators of
  // pass_sheet_polarizer, at oblique incidence up to 75°, any axes, partial polarizers.
  const auto axis = [](double deg) { return Vec3{std::cos(rad(deg)), std::sin(rad(deg)), 0}; };
  for (std::uint64_t i = 0; i < 200; ++i) {
    const double psi = 180 * uniform_unit(17, i, 0, 0), beta = 360 * uniform_unit(17, i, 1, 0);
    const double M1 = 0.5 + 0.5 * uniform_unit(17, i, 2, 0), m1 = 0.3 * uniform_unit(17, i, 3, 0);
    const double M2 = 1.0, m2 = 0.5 * uniform_unit(17, i, 4, 0);
    const Vec3 d = direction(75 * uniform_unit(17, i, 5, 0), 360 * uniform_unit(17, i, 6, 0));
    const Vec3 k{d[0], d[1], -d[2]};
    PolarizedRay ray = unpolarized_ray(k, 1.0);
    pass_sheet_polarizer(ray, {0, 0, 1}, axis(psi), M1, m1);
    pass_sheet_polarizer(ray, {0, 0, 1}, axis(beta), M2, m2);
    const SheetPolarizerPair pair({0, 0, 1}, axis(psi), M1, m1, axis(beta), M2, m2);
    EXPECT_NEAR(pair.transmittance(k), ray.S(0), kTight) << i;
  }
}

TEST(PolarizedRay, RefractionOfUnpolarizedLightIsFresnelAndSnell) {
  for (const auto& [n1, n2] : {std::pair{1.0, 1.5168}, std::pair{1.5168, 1.0}})
    for (double theta : {0.0, 10.0, 30.0, 40.0})  // below the critical 41.25° for glass → air
      for (double nz : {1.0, -1.0}) {
        const Vec3 d = direction(theta, 30);
        const Vec3 k_in{d[0], d[1], -d[2]};
        PolarizedRay ray = unpolarized_ray(k_in, 1.0);
        ASSERT_TRUE(refract(ray, {0, 0, nz}, n1, n2));
        const double cos_i = std::cos(rad(theta));
        EXPECT_NEAR(ray.S(0), fresnel_transmittance(n1, n2, cos_i), 1e-14);
        // Snell: n1 sin θi = n2 sin θt, in the plane of incidence, on through the interface.
        const double sin_t = std::hypot(ray.k[0], ray.k[1]);
        EXPECT_NEAR(n1 * std::sin(rad(theta)), n2 * sin_t, 1e-14);
        EXPECT_NEAR(dot3(ray.k, cross3(k_in, {0, 0, 1})), 0.0, 1e-15);
        EXPECT_LT(ray.k[2], 0);
        if (theta > 0) {
          EXPECT_GT(ray.k[0] * k_in[0] + ray.k[1] * k_in[1], 0);
        }
        EXPECT_NEAR(dot3(ray.k, ray.k), 1.0, 1e-15);
        EXPECT_NEAR(dot3(ray.x_hat, ray.k), 0.0, 1e-15);
      }
}

TEST(PolarizedRay, RefractionMatchesTheTextbookAmplitudes) {
  // T = (n2 cos θt)/(n1 cos θi)·t² with t_s = 2n1 cos θi/(n1 cos θi + n2 cos θt),
  // t_p = 2n1 cos θi/(n2 cos θi + n1 cos θt); 45° light keeps S2 = √(T_s T_p) (no retardance).
  const double n1 = 1.0, n2 = 1.5168, ti = rad(35);
  const double ci = std::cos(ti), ct = std::cos(std::asin(n1 * std::sin(ti) / n2));
  const double ts = 2 * n1 * ci / (n1 * ci + n2 * ct), tp = 2 * n1 * ci / (n2 * ci + n1 * ct);
  const double Ts = n2 * ct / (n1 * ci) * ts * ts, Tp = n2 * ct / (n1 * ci) * tp * tp;
  const Vec3 k{std::sin(ti), 0, -ci};  // plane of incidence x–z: s = ±y
  const auto through = [&](const Stokes& S) {
    PolarizedRay ray{k, {0, 1, 0}, S};
    EXPECT_TRUE(refract(ray, {0, 0, 1}, n1, n2));
    return ray.S;
  };
  EXPECT_NEAR(through(Stokes(1, 1, 0, 0))(0), Ts, kTight);
  EXPECT_NEAR(through(Stokes(1, -1, 0, 0))(0), Tp, kTight);
  EXPECT_NEAR(through(Stokes(1, 0, 1, 0))(2), std::sqrt(Ts * Tp), kTight);
  EXPECT_LT(Ts, Tp);
}

TEST(PolarizedRay, BrewsterAnglePassesPAndReflectsPartOfS) {
  // tan θB = n2/n1: T_p = 1, and r_s = (n1² − n2²)/(n1² + n2²), both ways through the surface.
  for (const auto& [n1, n2] : {std::pair{1.0, 1.5168}, std::pair{1.5168, 1.0}}) {
    const double tb = std::atan(n2 / n1);
    const Vec3 k{std::sin(tb), 0, -std::cos(tb)}, p{std::cos(tb), 0, std::sin(tb)};
    PolarizedRay p_ray{k, p, Stokes(1, 1, 0, 0)}, s_ray{k, p, Stokes(1, -1, 0, 0)};
    ASSERT_TRUE(refract(p_ray, {0, 0, 1}, n1, n2));
    ASSERT_TRUE(refract(s_ray, {0, 0, 1}, n1, n2));
    EXPECT_NEAR(p_ray.S(0), 1.0, 1e-14);
    EXPECT_NEAR(p_ray.S(1), -1.0, 1e-14);  // still p: x_hat is now s
    const double rs = (n1 * n1 - n2 * n2) / (n1 * n1 + n2 * n2);
    EXPECT_NEAR(s_ray.S(0), 1 - rs * rs, 1e-14);
    EXPECT_NEAR(s_ray.S(1), 1 - rs * rs, 1e-14);
  }
}

TEST(PolarizedRay, TotalInternalReflectionLeavesTheRay) {
  const double n = 1.5168, critical = std::asin(1 / n) * 180 / M_PI;
  for (double theta : {critical + 0.01, 60.0, 89.0}) {
    const Vec3 d = direction(theta, 70);
    PolarizedRay ray{{d[0], d[1], -d[2]}, unit3(cross3({d[0], d[1], -d[2]}, {0, 0, 1})), Stokes(1, 0.3, -0.2, 0.1)};
    const PolarizedRay before = ray;
    EXPECT_FALSE(refract(ray, {0, 0, 1}, n, 1.0));
    EXPECT_EQ(ray.k, before.k);
    EXPECT_EQ(ray.x_hat, before.x_hat);
    EXPECT_EQ(ray.S, before.S);
  }
}

TEST(PolarizedRay, SetFrameKeepsThePolarizationIn3D) {
  // Sign: a downward ray (y_hat = −y) polarized along lab 30° is at −30° in its frame; in the
  // frame x_hat = lab y (so y_hat = x) the same light is at 60°.
  PolarizedRay down{{0, 0, -1}, {1, 0, 0}, linearly_polarized(1.0, 1.0, -30)};
  set_frame(down, {0, 1, 0});
  expect_stokes_near(down.S, linearly_polarized(1.0, 1.0, 60), 1e-15);

  for (std::uint64_t i = 0; i < 32; ++i) {
    const Vec3 k = random_direction(i), u = random_direction(100 + i);
    const PolarizedRay start{k, unpolarized_ray(k, 1.0).x_hat, random_stokes(i)};
    PolarizedRay ray = start;
    set_frame(ray, u);
    // x_hat is u's unit projection ⊥ k.
    const double uk = dot3(u, k);
    const Vec3 u_perp = unit3({u[0] - uk * k[0], u[1] - uk * k[1], u[2] - uk * k[2]});
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(ray.x_hat[c], u_perp[c], 1e-14);
    // S0, degree of polarization, ellipticity and the ellipse's axis in space are unchanged.
    EXPECT_NEAR(ray.S(0), start.S(0), 1e-15);
    EXPECT_NEAR(ray.S.tail<3>().norm(), start.S.tail<3>().norm(), 1e-14);
    EXPECT_NEAR(ray.S(3), start.S(3), 1e-15);
    EXPECT_NEAR(std::abs(dot3(major_axis(ray), major_axis(start))), 1.0, 1e-12);
    set_frame(ray, start.x_hat);
    expect_stokes_near(ray.S, start.S, 1e-14);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(ray.x_hat[c], start.x_hat[c], 1e-15);
  }
  PolarizedRay ray = unpolarized_ray({0, 0, 1}, 1.0);
  EXPECT_THROW(set_frame(ray, {0, 0, 2}), std::invalid_argument);
}

TEST(Lens, PolarizedTraceFollowsTheSamePath) {
  const PlanoConvexLens lens = PlanoConvexLens::from_focal_length(50.0, 3.5, 12.7, 1.5168);
  const auto ray = [](Vec3 o, Vec3 d) { return LensRay{o, unit3(d), 1}; };
  for (const LensRay& in : {ray({0, 0, 10}, {0, 0, -1}), ray({4, 0, 10}, {0, 0, -1}),
                            ray({1.5, -2, 10}, {0.05, 0.03, -1}), ray({0.3, -0.2, -40}, {0.01, 0.02, 1})}) {
    const auto plain = trace_through(lens, in);
    PolarizedRay pol = unpolarized_ray(in.direction, 1.0);
    const auto traced = trace_through(lens, in, &pol);
    ASSERT_TRUE(plain && traced);
    EXPECT_EQ(traced->origin, plain->origin);
    EXPECT_EQ(traced->direction, plain->direction);
    EXPECT_EQ(traced->transmittance, plain->transmittance);
    EXPECT_EQ(pol.k, plain->direction);
    EXPECT_NEAR(dot3(pol.x_hat, pol.k), 0.0, 1e-15);
    const auto no_pol = trace_through(lens, in, nullptr);
    EXPECT_EQ(no_pol->direction, plain->direction);
    EXPECT_EQ(no_pol->transmittance, plain->transmittance);
  }
  // On axis both faces are at normal incidence: no partial polarization, S0 = transmittance.
  PolarizedRay axial = unpolarized_ray({0, 0, -1}, 1.0);
  const auto out = trace_through(lens, LensRay{{0, 0, 10}, {0, 0, -1}, 1}, &axial);
  EXPECT_NEAR(axial.S(0), out->transmittance, kTight);
  // A miss leaves the polarization alone; a polarization along another direction is refused.
  PolarizedRay kept{{0, 0, -1}, {1, 0, 0}, Stokes(1, 0.5, 0, 0)};
  EXPECT_FALSE(trace_through(lens, LensRay{{7.0, 0, 10}, {0, 0, -1}, 1}, &kept));
  EXPECT_EQ(kept.S, Stokes(1, 0.5, 0, 0));
  PolarizedRay tilted = unpolarized_ray(unit3({0.1, 0, -1}), 1.0);
  EXPECT_THROW(trace_through(lens, LensRay{{0, 0, 10}, {0, 0, -1}, 1}, &tilted), std::invalid_argument);
}

TEST(Lens, MeridionalRayTransmitsPMoreThanS) {
  // A ray parallel to the axis at height h in the x–z plane meets the convex face at θ1 with
  // sin θ1 = h/R, bends to θt1, and meets the plane face at θ2 = θ1 − θt1. s = ±y at both faces,
  // so x-polarized light is p throughout: S0 = T_p1·T_p2 (T_s1·T_s2 for y), textbook amplitudes.
  const PlanoConvexLens lens = PlanoConvexLens::from_focal_length(50.0, 3.5, 12.7, 1.5168);
  const double n = lens.index, h = 4.0;
  const auto T = [](double n1, double n2, double theta_i) {
    const double ci = std::cos(theta_i), ct = std::cos(std::asin(n1 * std::sin(theta_i) / n2));
    const double ts = 2 * n1 * ci / (n1 * ci + n2 * ct), tp = 2 * n1 * ci / (n2 * ci + n1 * ct);
    return std::pair{n2 * ct / (n1 * ci) * ts * ts, n2 * ct / (n1 * ci) * tp * tp};
  };
  const double t1 = std::asin(h / lens.radius_of_curvature), t2 = t1 - std::asin(std::sin(t1) / n);
  const auto [Ts1, Tp1] = T(1.0, n, t1);
  const auto [Ts2, Tp2] = T(n, 1.0, t2);
  const LensRay in{{h, 0, 10}, {0, 0, -1}, 1};
  const auto through = [&](const Stokes& S) {
    PolarizedRay pol{{0, 0, -1}, {1, 0, 0}, S};
    EXPECT_TRUE(trace_through(lens, in, &pol));
    return pol.S;
  };
  const Stokes p = through(Stokes(1, 1, 0, 0)), s = through(Stokes(1, -1, 0, 0));
  EXPECT_NEAR(p(0), Tp1 * Tp2, kTight);
  EXPECT_NEAR(p(1), -p(0), kTight);  // still p (x_hat is s on the way out)
  EXPECT_NEAR(s(0), Ts1 * Ts2, kTight);
  EXPECT_GT(p(0), s(0));
  // Unpolarized light: the existing `transmittance` depolarizes between the faces,
  // ¼(T_s1 + T_p1)(T_s2 + T_p2); the polarized trace keeps the first face's partial
  // polarization and gains ¼(T_p1 − T_s1)(T_p2 − T_s2).
  const double T_unpolarized = trace_through(lens, in)->transmittance;
  EXPECT_NEAR(T_unpolarized, 0.25 * (Ts1 + Tp1) * (Ts2 + Tp2), kTight);
  EXPECT_NEAR(through(unpolarized(1.0))(0), T_unpolarized + 0.25 * (Tp1 - Ts1) * (Tp2 - Ts2), kTight);
  EXPECT_GT(0.25 * (Tp1 - Ts1) * (Tp2 - Ts2), 1e-7);  // the difference is real, not rounding
}

}  // namespace
}  // namespace polrig
