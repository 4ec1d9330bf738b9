// Berry's sky (sky/berry.h, sky/berry_fit.h) against what Berry, Dennis & Lee 2004 state of it
// and against independent references: single scattering's pattern when the neutral points meet at
// the sun (the Rayleigh formula, e ⊥ s × v, |w| = sin²γ), the singularities where it puts them
// with index +½ each (their §2: four +½ points, total +2 as the sphere requires), the mirror
// symmetry about the solar meridian, continuity as Babinet passes over the zenith; its fit to the
// vector-RT sky against the exact Natraj et al. 2009 tables.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "polrig/sky/berry.h"
#include "polrig/sky/berry_fit.h"
#include "polrig/sky/rayleigh.h"
#include "polrig/sky/sun_rows.h"
#include "polrig/units.h"
#include "rayleigh_tables.h"

namespace polrig {
namespace {

Vec3 from_el_az(double el_deg, double math_az_deg) {
  const double e = el_deg * kDeg, a = math_az_deg * kDeg;
  return {std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e)};
}

Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> n;
  Vec3 v{n(rng), n(rng), n(rng)};
  return vec3::mul(v, 1 / vec3::norm(v));
}

// δ = 0: single scattering. The E-vector ⊥ the scattering plane (|e·ŝ×v̂| = 1), |w| = sin²γ, and
// the DoP single scattering's P_max·sin²γ/(1 + cos²γ), at random suns above the horizon and views
// anywhere but within 1° of the nadir (where the plane's direction is undefined) or the sun.
TEST(BerrySky, IsSingleScatteringWhenTheNeutralPointsMeetAtTheSun) {
  std::mt19937_64 rng(3);
  int checked = 0;
  for (int t = 0; t < 2000; ++t) {
    Vec3 s = random_unit(rng);
    s[2] = std::abs(s[2]);
    const Vec3 v = random_unit(rng);
    const Vec3 c = vec3::cross(s, v);
    const double sin_gamma = vec3::norm(c), cos_gamma = vec3::dot(s, v);
    if (v[2] < -std::cos(1 * kDeg) || sin_gamma < 1e-3) continue;
    const BerryField berry(s, {0, 0});
    const BerryField::Polarization p = berry.at(v);
    EXPECT_NEAR(std::abs(vec3::dot(p.e_vector, vec3::mul(c, 1 / sin_gamma))), 1, 1e-9) << t;
    EXPECT_NEAR(p.w_abs, sin_gamma * sin_gamma, 1e-12) << t;
    EXPECT_NEAR(std::abs(berry.w(v)), sin_gamma * sin_gamma, 1e-9) << t;
    EXPECT_NEAR(berry_dop(p.w_abs, 0.7), 0.7 * sin_gamma * sin_gamma / (1 + cos_gamma * cos_gamma), 1e-12) << t;
    ++checked;
  }
  EXPECT_GT(checked, 1500);
}

// The same through the rig's sky (SunSky): a Berry model with both distances 0 reads as the
// single-scattering model, radiance models included.
TEST(BerrySky, ReadsAsTheSingleScatteringSkyWithBothDistancesZero) {
  SkyModel single;
  single.P_max.constant = 0.62, single.radiance = SkyRadiance::CieClear;
  SkyModel berry = single;
  berry.kind = SkyKind::Berry;
  berry.berry.babinet_deg = 0, berry.berry.brewster_deg = 0;
  const Vec3 s = from_el_az(31, 200);
  for (double el = 1; el < 90; el += 7)
    for (double az = 0; az < 360; az += 13) {
      const SkyLight a = sky_light(s, from_el_az(el, az), single), b = sky_light(s, from_el_az(el, az), berry);
      EXPECT_NEAR(b.dop, a.dop, 1e-12);
      EXPECT_DOUBLE_EQ(b.radiance, a.radiance);
      EXPECT_NEAR(std::remainder(b.aop_deg - a.aop_deg, 180.0), 0, 1e-7) << el << " " << az;
    }
}

// The angle of a line field's direction at v in the tangent frame (t1, t2) at the point p.
double line_angle(const Vec3& e, const Vec3& t1, const Vec3& t2) { return std::atan2(vec3::dot(e, t2), vec3::dot(e, t1)); }

// The index of Berry's field around a point p: the E-vector's turn over a small loop
// anticlockwise about p's outward normal, in units of a full turn.
double index_around(const BerryField& berry, const Vec3& p, double radius_deg) {
  Vec3 t1 = vec3::cross(Vec3{0, 0, 1}, p);
  if (vec3::norm(t1) < 1e-6) t1 = {1, 0, 0};
  t1 = vec3::mul(t1, 1 / vec3::norm(t1));
  const Vec3 t2 = vec3::cross(p, t1);
  const int n = 720;
  double turn = 0, prev = 0;
  for (int k = 0; k <= n; ++k) {
    const double a = 2 * M_PI * k / n, r = radius_deg * kDeg;
    const Vec3 v = vec3::add(vec3::mul(p, std::cos(r)),
                             vec3::add(vec3::mul(t1, std::sin(r) * std::cos(a)), vec3::mul(t2, std::sin(r) * std::sin(a))));
    const Vec3 e = berry.at(v).e_vector;
    const double ang = line_angle(e, t1, t2);
    if (k > 0) turn += std::remainder(ang - prev, M_PI);  // a line: directions modulo π
    prev = ang;
  }
  return turn / (2 * M_PI);
}

// Berry et al. §2: the zeros of w are Babinet δ_Ba above the sun and Brewster δ_Br below it on
// the solar meridian, Arago and the fourth point their antipodes, each of index +½. Checked with
// the zeros placed independently (the sun's meridian at zenith angles θ_s ∓ δ) and w itself.
TEST(BerrySky, PutsItsFourSingularitiesWhereThePaperDoesEachOfIndexOneHalf) {
  for (const auto& [h, az, d_Ba, d_Br] : {std::array{36.87, 120.0, 15.9, 20.3}, std::array{10.0, -40.0, 18.0, 9.5},
                                          std::array{70.0, 10.0, 25.0, 12.0}, std::array{60.0, 75.0, 0.0, 30.0}}) {
    const Vec3 s = from_el_az(h, az);
    const BerryField berry(s, {d_Ba, d_Br});
    const Vec3 Ba = from_el_az(h + d_Ba, az), Br = from_el_az(h - d_Br, az);
    const std::array<Vec3, 4> expected{Ba, Br, vec3::mul(Br, -1), vec3::mul(Ba, -1)};
    for (int i = 0; i < 4; ++i) {
      EXPECT_NEAR(vec3::norm(vec3::sub(berry.neutral_points()[i], expected[i])), 0, 1e-12) << h << " " << i;
      if (expected[i][2] > -0.9) {
        EXPECT_LT(std::abs(berry.w(expected[i])), 1e-12) << h << " point " << i;
        if (d_Ba > 0 && d_Br > 0) {
          EXPECT_NEAR(index_around(berry, expected[i], 1.0), 0.5, 1e-9) << h << " point " << i;
        }
      }
    }
    // Away from the points the field is polarized: |w| = sin α sin β > 0.
    EXPECT_GT(berry.at(from_el_az(h + 90, az)).w_abs, 0.1);
  }
}

// Mirror symmetry about the solar meridian (the paper's pattern, as the sky's): χ at relative
// azimuth +Δ is −χ at −Δ in each view's meridian frame; and the DoP is the same.
TEST(BerrySky, IsMirrorSymmetricAboutTheSolarMeridian) {
  SkyModel m;
  m.kind = SkyKind::Berry;
  m.berry.babinet_deg = 17, m.berry.brewster_deg = 11;
  const double az_sun = 35;  // math azimuth
  const Vec3 s = from_el_az(28, az_sun);
  for (double el = 2; el < 90; el += 4)
    for (double d = 3; d < 180; d += 11) {
      const SkyLight a = sky_light(s, from_el_az(el, az_sun + d), m), b = sky_light(s, from_el_az(el, az_sun - d), m);
      EXPECT_NEAR(std::remainder(a.aop_deg + b.aop_deg, 180.0), 0, 1e-9) << el << " " << d;
      EXPECT_NEAR(a.dop, b.dop, 1e-12);
    }
}

// The literal formula's (ζ + 1/ζ_Ba*)/|ζ_Ba + 1/ζ_Ba*| changes sign as Babinet crosses the zenith
// (a sun above 90° − δ_Ba) and would turn the whole pattern by 90°; polrig's form is continuous
// there: a 0.02° rise of the sun across that elevation turns no E-vector more than 10° from a
// neutral point by more than 0.1° (the points themselves move 0.02°).
TEST(BerrySky, StaysContinuousAsBabinetPassesOverTheZenith) {
  const double d_Ba = 15, h0 = 90 - d_Ba;
  const BerryField below(from_el_az(h0 - 0.01, 0), {d_Ba, 20}), above(from_el_az(h0 + 0.01, 0), {d_Ba, 20});
  for (double el = 5; el < 85; el += 10)
    for (double az = 5; az < 360; az += 20) {
      const Vec3 v = from_el_az(el, az);
      bool near_point = false;
      for (const Vec3& p : below.neutral_points()) near_point |= vec3::dot(p, v) > std::cos(10 * kDeg);
      if (near_point) continue;
      const double c = std::abs(vec3::dot(below.at(v).e_vector, above.at(v).e_vector));
      EXPECT_GT(c, std::cos(0.1 * kDeg)) << el << " " << az;
    }
}

TEST(BerrySky, RefusesDistancesOutsideTheirRange) {
  const Vec3 s = from_el_az(30, 0);
  EXPECT_THROW(BerryField(s, {-1, 10}), std::invalid_argument);
  EXPECT_THROW(BerryField(s, {10, 90}), std::invalid_argument);
  EXPECT_THROW(BerryField(s, {std::nan(""), 10}), std::invalid_argument);
  EXPECT_THROW(BerryField(from_el_az(-60, 0), {10, 80}), std::invalid_argument);  // Brewster past the nadir
}

// The fit to the vector-RT sky against the exact tables (τ 0.25 and 0.1, black ground, ρ = 0, the
// sun at each tabulated μ₀ down to 0.2): at every table view with DoP ≥ 0.02 Berry's AoP, with
// the distances fitted to polrig's sky at that sun, against the table's. The spec (skies.md §3)
// reads 0.1–0.3° rms for separately fitted distances; measured here 0.005–0.03° (τ 0.1) and
// 0.01–0.09° (τ 0.25), against single scattering's 0.7–29°: the bound 0.15° holds every sun, and
// Berry beats single scattering tenfold wherever single scattering errs by more than 0.5°.
TEST(BerrySky, FittedDistancesFollowTheExactTablesAop) {
  for (const char* tau_text : {"0.1", "0.25"}) {
    const std::string tau_s = tau_text;
    const auto I = test::read_rayleigh_table("I_DN_TAU_" + tau_s), Q = test::read_rayleigh_table("Q_DN_TAU_" + tau_s),
               U = test::read_rayleigh_table("U_DN_TAU_" + tau_s);
    VectorRtSettings rt;
    rt.tau_rayleigh = std::stod(tau_s), rt.depolarization = 0;
    const std::shared_ptr<const VectorRtSky> sky = vector_rt_sky(rt);
    for (double mu0 : {0.2, 0.4, 0.6, 0.8, 0.92}) {
      const double h = std::asin(mu0) / kDeg;
      const BerryFitResult fit = fit_berry(sky->for_sun(h), h);
      ASSERT_TRUE(fit.summary.usable()) << fit.summary.status;
      SkyModel berry;
      berry.kind = SkyKind::Berry;
      berry.berry.babinet_deg = fit.distances.babinet_deg, berry.berry.brewster_deg = fit.distances.brewster_deg;
      std::vector<SkyQuery> queries;
      std::vector<double> table_aop;
      for (std::size_t r = 0; r < I[0].size(); ++r) {
        if (std::abs(I[0][r].mu0 - mu0) > 1e-9) continue;
        for (int p = 0; p < 7; ++p) {
          const double Qp = -Q[0][r].v[p], Up = -U[0][r].v[p];  // polrig's sense (test_vector_rt_sky)
          if (std::hypot(Qp, Up) < 0.02 * I[0][r].v[p]) continue;
          SkyQuery q;
          q.sun = fixed_sun(150, h);
          q.view_az_deg = 150 - 30.0 * p, q.view_el_deg = std::asin(I[0][r].mu) / kDeg;
          queries.push_back(q);
          table_aop.push_back(0.5 * std::atan2(Up, Qp) / kDeg);
        }
      }
      const std::vector<SkySample> got = sky_along(queries, berry);
      SkyModel single;
      const std::vector<SkySample> ss = sky_along(queries, single);
      double e2 = 0, s2 = 0;
      for (std::size_t k = 0; k < got.size(); ++k) {
        const double d = std::remainder(got[k].light.aop_deg - table_aop[k], 180.0);
        const double ds = std::remainder(ss[k].light.aop_deg - table_aop[k], 180.0);
        e2 += d * d, s2 += ds * ds;
      }
      const double rms = std::sqrt(e2 / got.size()), rms_single = std::sqrt(s2 / got.size());
      EXPECT_LT(rms, 0.15) << "tau " << tau_s << " mu0 " << mu0;
      if (rms_single > 0.5) {
        EXPECT_LT(rms, rms_single / 10) << "tau " << tau_s << " mu0 " << mu0;
      }
      // The fit's own report, over its grid, is of the same size.
      EXPECT_LT(fit.summary.aop_rms_deg, 0.2) << "tau " << tau_s << " mu0 " << mu0;
      EXPECT_GT(got.size(), 100u);
    }
  }
}

}  // namespace
}  // namespace polrig

namespace polrig {
namespace {

// A fitted distance below the vector-RT sky's low-sun limit is refused as Berry's sky's, with the
// way out (distances given as numbers), not as the vector-RT sky's own error.
TEST(BerryFit, RefusesASunBelowTheFitsLimitSayingWhatToGive) {
  const std::shared_ptr<const BerryFit> fit = berry_fit(VectorRtSettings{});
  try {
    (void)fit->distances(1.0);
    FAIL() << "a sun at 1° was fitted";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("Berry's sky with fitted distances"), std::string::npos) << what;
    EXPECT_NE(what.find("the sun's elevation 1° is outside [2°, 90°]"), std::string::npos) << what;
    EXPECT_NE(what.find("sky.berry.babinet_deg"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace polrig
