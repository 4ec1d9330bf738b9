// The vector-RT sky as the rigs, `sky table` and every instrument read it (sky/vector_rt_sky.h,
// SunSky): its interpolation against exact solves, the whole chain (geographic azimuths, view
// frames, absolute radiance) against the exact Natraj et al. 2009 tables, the low-sun refusal,
// thread-count independence, and the rig keys.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <tbb/global_control.h>

#include "polrig/io/rig_yaml.h"
#include "polrig/rig/error.h"
#include "polrig/rig/rig.h"
#include "polrig/sky/neutral_points.h"
#include "polrig/sky/sun_rows.h"
#include "polrig/sky/vector_rt_sky.h"
#include "polrig/units.h"
#include "rayleigh_tables.h"
#include "support.h"

namespace polrig {
namespace {

double aop_deg(double Q, double U) { return 0.5 * std::atan2(U, Q) / kDeg; }

SkyModel vector_rt_model(const VectorRtSettings& s) {
  SkyModel m;
  m.kind = SkyKind::VectorRt;
  m.vector_rt = vector_rt_sky(s);
  return m;
}

// The interpolation (4-point in the sun's elevation every 1°, in s with θ = (π/2)(1 − s²) at 48
// view nodes) against exact solves at random suns and views, the horizon's views included. The
// bounds are the measured errors (I 9e-4, DoP 5e-5, AoP 0.016°) with a margin below 2×.
TEST(SlowVectorRtSky, InterpolatesExactSolvesWithinItsStatedError) {
  for (double tau : {0.05, 0.25, 1.0})
    for (double A : {0.0, 0.8}) {
      VectorRtSettings s;
      s.tau_rayleigh = tau, s.ground_albedo = A;
      const VectorRtSky sky(s);
      std::mt19937_64 rng(7);
      std::uniform_real_distribution<double> U(0, 1);
      double e_I = 0, e_dop = 0, e_aop = 0;
      for (int t = 0; t < 8; ++t) {
        const double h = 2 + 88 * U(rng);
        std::vector<double> mu;
        for (int k = 0; k < 16; ++k) mu.push_back(k < 4 ? std::pow(U(rng), 4) + 1e-5 : U(rng));
        const DiffuseField exact = solve_vector_rt(s, std::sin(h * kDeg), mu);
        const SunField field = sky.for_sun(h);
        for (std::size_t k = 0; k < mu.size(); ++k)
          for (int p = 0; p < 8; ++p) {
            const double phi = p * 0.8;
            const Eigen::Vector4d x = exact.down_at(k, phi);
            const Eigen::Vector3d y = field.stokes(mu[k], phi);
            e_I = std::max(e_I, std::abs(y(0) / x(0) - 1));
            const double dx = std::hypot(x(1), x(2)) / x(0), dy = std::hypot(y(1), y(2)) / y(0);
            e_dop = std::max(e_dop, std::abs(dx - dy));
            if (dx >= 0.02) e_aop = std::max(e_aop, std::abs(std::remainder(aop_deg(y(1), y(2)) - aop_deg(x(1), x(2)), 180.0)));
          }
      }
      EXPECT_LT(e_I, 2e-3) << tau << " " << A;
      EXPECT_LT(e_dop, 1e-4) << tau << " " << A;
      EXPECT_LT(e_aop, 0.03) << tau << " " << A;
    }
}

// Every row of the τ = 0.25 DN tables at μ₀ = 0.6 (the sun at 36.87°), black ground and albedo
// 0.25, through sky_along's fixed suns: the views' geographic azimuths (A_view = A_sun − φ), their
// meridian frames and the absolute L/E₀ (a tabulated I is π·L/E₀; (Q, U)_polrig = −(Q, U)_table).
using Row = test::TableRow;
const auto read_blocks = test::read_rayleigh_table;

TEST(VectorRtSky, SkyTableMatchesTheExactTablesThroughTheWholeChain) {
  const auto I = read_blocks("I_DN_TAU_0.25"), Q = read_blocks("Q_DN_TAU_0.25"), U = read_blocks("U_DN_TAU_0.25");
  ASSERT_EQ(I.size(), 3u);
  const double albedos[2] = {0, 0.25};
  const double sun_az = 150;
  for (int b = 0; b < 2; ++b) {
    VectorRtSettings s;
    s.tau_rayleigh = 0.25, s.depolarization = 0, s.ground_albedo = albedos[b];
    const SkyModel model = vector_rt_model(s);
    std::vector<SkyQuery> queries;
    std::vector<std::array<double, 3>> expected;  // I/π, Q/π, U/π in polrig's sense
    for (std::size_t r = 0; r < I[b].size(); ++r) {
      if (std::abs(I[b][r].mu0 - 0.6) > 1e-9) continue;
      for (int p = 0; p < 7; ++p) {
        SkyQuery q;
        q.sun = fixed_sun(sun_az, std::asin(0.6) / kDeg);
        q.view_az_deg = sun_az - 30.0 * p;
        q.view_el_deg = std::asin(I[b][r].mu) / kDeg;
        queries.push_back(q);
        expected.push_back({I[b][r].v[p] / M_PI, -Q[b][r].v[p] / M_PI, -U[b][r].v[p] / M_PI});
      }
    }
    ASSERT_EQ(queries.size(), 16u * 7u);
    const std::vector<SkySample> got = sky_along(queries, model);
    for (std::size_t k = 0; k < got.size(); ++k) {
      const auto& [It, Qt, Ut] = expected[k];
      ASSERT_TRUE(got[k].absolute.has_value());
      const Stokes& x = *got[k].absolute;
      EXPECT_NEAR(x(0) / It, 1, 2e-3) << k;
      const double dop_t = std::hypot(Qt, Ut) / It;
      EXPECT_NEAR(got[k].light.dop, dop_t, 1e-4) << k;
      EXPECT_NEAR(std::hypot(x(1), x(2)) / x(0), dop_t, 1e-4) << k;
      if (dop_t >= 0.02) {
        EXPECT_NEAR(std::remainder(got[k].light.aop_deg - aop_deg(Qt, Ut), 180.0), 0, 0.03) << k;
      }
    }
  }
}

TEST(VectorRtSky, RefusesASunBelowItsLimitNamingTheRow) {
  const SkyModel model = vector_rt_model({});
  std::vector<SkyQuery> q(3);
  q[0].sun = fixed_sun(100, 30), q[1].sun = fixed_sun(100, 1.5), q[2].sun = fixed_sun(100, -5);
  try {
    (void)sky_along(q, model);
    FAIL() << "a sun at 1.5° was accepted";
  } catch (const SunRowError& e) {
    EXPECT_EQ(e.row, 1u);
    EXPECT_PRED_FORMAT2(test::HasText, e.what(), "the sun's elevation 1.5° is outside [2°, 90°]");
  }
}

TEST(VectorRtSky, SameBitsForAnyThreadCount) {
  const SkyModel model = vector_rt_model({});
  std::vector<SkyQuery> q(4000);
  for (std::size_t i = 0; i < q.size(); ++i) {
    q[i].sun = fixed_sun(200, 20 + (i % 7) * 3.3);
    q[i].view_az_deg = (i * 37) % 360, q[i].view_el_deg = (i % 89) + 0.5;
  }
  std::vector<SkySample> one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = sky_along(q, model);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = sky_along(q, model);
  }
  for (std::size_t i = 0; i < q.size(); ++i) {
    ASSERT_EQ(one[i].light.dop, two[i].light.dop) << i;
    ASSERT_EQ(one[i].light.aop_deg, two[i].light.aop_deg) << i;
    ASSERT_EQ(*one[i].absolute, *two[i].absolute) << i;
  }
}

// The zeros of one table column Q(μ) (polrig's sign), as view elevations: each sign change between
// grid points, located on the 4-point Lagrange interpolant in μ by bisection.
std::vector<double> table_zeros_deg(const std::vector<Row>& rows, std::size_t first, int column) {
  std::vector<double> mu, q, zeros;
  for (std::size_t k = 0; k < 16; ++k) mu.push_back(rows[first + k].mu), q.push_back(-rows[first + k].v[column]);
  const auto interp = [&](std::size_t j0, double x) {
    double sum = 0;
    for (std::size_t i = j0; i < j0 + 4; ++i) {
      double w = 1;
      for (std::size_t j = j0; j < j0 + 4; ++j)
        if (j != i) w *= (x - mu[j]) / (mu[i] - mu[j]);
      sum += w * q[i];
    }
    return sum;
  };
  for (std::size_t k = 0; k + 1 < mu.size(); ++k) {
    if ((q[k] > 0) == (q[k + 1] > 0)) continue;
    const std::size_t j0 = std::min<std::size_t>(k > 0 ? k - 1 : 0, mu.size() - 4);
    double a = mu[k], b = mu[k + 1];
    const bool a_positive = q[k] > 0;
    for (int it = 0; it < 60; ++it) {
      const double m = 0.5 * (a + b);
      ((interp(j0, m) > 0) == a_positive ? a : b) = m;
    }
    zeros.push_back(std::asin(0.5 * (a + b)) / kDeg);
  }
  return zeros;
}

// The neutral points against the exact tables (τ = 0.25 DN, black ground, every μ₀): each point
// polrig finds is a sign change of the table's Q in the principal plane at the same place, to the
// interpolation of the table's μ grid (0.5°), and every sign change of the tables is one of them.
TEST(VectorRtSky, NeutralPointsAreWhereTheExactTablesChangeSign) {
  const auto Q = read_blocks("Q_DN_TAU_0.25");
  VectorRtSettings s;
  s.tau_rayleigh = 0.25, s.depolarization = 0;
  int checked = 0;
  for (std::size_t r0 = 0; r0 < Q[0].size(); r0 += 16) {
    const double h = std::asin(Q[0][r0].mu0) / kDeg;
    if (h < VectorRtSky::kMinSunElevationDeg || h > 85) continue;
    const NeutralPoints p = vector_rt_neutral_points(s, h);
    std::vector<double> sun_side = table_zeros_deg(Q[0], r0, 0), anti_side = table_zeros_deg(Q[0], r0, 6);
    const auto claim = [&](std::vector<double>& zeros, double elevation, const char* what) {
      if (elevation < std::asin(Q[0][r0].mu) / kDeg) return;  // below the tables' lowest view (μ = 0.02)
      ASSERT_FALSE(zeros.empty()) << what << " at sun " << h << "°: no sign change in the table";
      std::size_t best = 0;
      for (std::size_t k = 1; k < zeros.size(); ++k)
        if (std::abs(zeros[k] - elevation) < std::abs(zeros[best] - elevation)) best = k;
      EXPECT_NEAR(zeros[best], elevation, 0.5) << what << " at sun " << h << "°";
      zeros.erase(zeros.begin() + static_cast<long>(best));
      ++checked;
    };
    if (p.babinet_deg) {
      const double e = h + *p.babinet_deg;
      e <= 90 ? claim(sun_side, e, "Babinet") : claim(anti_side, 180 - e, "Babinet");
    }
    if (p.brewster_deg) claim(sun_side, h - *p.brewster_deg, "Brewster");
    if (p.arago_deg) claim(anti_side, *p.arago_deg - h, "Arago");
    EXPECT_TRUE(sun_side.empty() && anti_side.empty()) << "sun " << h << "°: a sign change polrig did not find";
  }
  EXPECT_GE(checked, 10);
  // The spec's reading of the tables (skies.md §1): Babinet ~15.5° above and Brewster ~20.3° below
  // a sun at 36.9° (τ 0.25); Arago ~19–25° above the antisun at low sun (τ 0.1–0.25).
  const NeutralPoints p = vector_rt_neutral_points(s, 36.87);
  EXPECT_NEAR(*p.babinet_deg, 15.5, 0.6);
  EXPECT_NEAR(*p.brewster_deg, 20.3, 0.3);
  for (double tau : {0.1, 0.25}) {
    s.tau_rayleigh = tau;
    const NeutralPoints low = vector_rt_neutral_points(s, 10);
    ASSERT_TRUE(low.arago_deg);
    EXPECT_GE(*low.arago_deg, 18);
    EXPECT_LE(*low.arago_deg, 26);
  }
}

const char* kSkyRig = "source:\n  model: sky\nsky:\n  model: vector-rt\n";

TEST(VectorRtSky, RigKeysChooseTheSkyAndRefuseTheOthersKeys) {
  const LoadedRig r = parse_rig(std::string(kSkyRig) + "  rt:\n    tau_rayleigh: bodhaine\n    wavelength_nm: 450\n"
                                "    ground_albedo: 0.2\n", "vrt.yaml");
  const std::optional<Sky> sky = rig_sky(r.rig);
  ASSERT_TRUE(sky);
  EXPECT_EQ(sky->model.kind, SkyKind::VectorRt);
  ASSERT_TRUE(sky->model.vector_rt);
  EXPECT_NEAR(sky->model.vector_rt->settings().tau_rayleigh, 0.2203, 5e-4);  // Bodhaine at 450 nm
  EXPECT_EQ(sky->model.vector_rt->settings().ground_albedo, 0.2);
  const auto refused = [](const std::string& text, const std::string& message) {
    try {
      (void)parse_rig(text, "bad.yaml");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const RigError& e) {
      EXPECT_PRED_FORMAT2(test::HasText, e.what(), message);
    }
  };
  refused(std::string(kSkyRig) + "  p_max: 0.6\n",
          "key 'sky.p_max': expected no value with sky.model vector-rt (only sky.model single-scattering or berry reads it)");
  refused("source:\n  model: sky\nsky:\n  rt:\n    streams: 16\n",
          "key 'sky.rt.streams': expected no value with sky.model single-scattering");
  refused(std::string(kSkyRig) + "  rt:\n    tau_rayleigh: -0.1\n", "key 'sky.rt.tau_rayleigh'");
  refused(std::string(kSkyRig) + "  rt:\n    streams: 15\n", "key 'sky.rt.streams'");
  refused(std::string(kSkyRig) + "  rt:\n    ground_albedo: 1.5\n", "key 'sky.rt.ground_albedo'");
  refused("source:\n  model: sky\nsky:\n  model: berry-ish\n", "key 'sky.model'");
  // An override of sky.model sets aside the file's keys of the other sky, not an override's.
  const std::string shipped = "source:\n  model: sky\nsky:\n  p_max: 0.66\n  radiance: uniform\n";
  const LoadedRig switched = parse_rig(shipped, "shipped.yaml", {RigOverride::parse("sky.model=vector-rt")});
  EXPECT_EQ(rig_sky(switched.rig)->model.kind, SkyKind::VectorRt);
  EXPECT_EQ(rig_to_yaml(switched.rig).find("p_max"), std::string::npos);
  EXPECT_THROW((void)parse_rig(shipped, "shipped.yaml",
                               {RigOverride::parse("sky.model=vector-rt"), RigOverride::parse("sky.p_max=0.5")}),
               RigError);
}

}  // namespace
}  // namespace polrig

namespace polrig {
namespace {

namespace fs = std::filesystem;

class VectorRtSkyCli : public test::PolrigTest {
 protected:
  VectorRtSkyCli() : PolrigTest("polrig_vrt_", "") {}
  const std::string kSky = " --set source.model=sky --set sky.model=vector-rt --set sky.rt.tau_rayleigh=0.25 "
                           "--set sky.rt.depolarization=0";
};

// `sky table` with fixed suns: I_sr, Q_sr, U_sr beside dop and aop_deg, consistent with each other,
// the zenith's DoP the tables' 0.412 (τ 0.25, sun 36.87°, black ground; spec skies.md §1); a sun
// below the limit refused naming its line, nothing written.
TEST_F(VectorRtSkyCli, SkyTableWritesTheAbsoluteStokesVector) {
  test::write_file(tmp / "in.csv", "id,sun_az_deg,sun_el_deg,view_az_deg,view_el_deg\na,150,36.8699,0,90\nb,150,36.8699,330,20\n");
  ok("sky table " + test::shell_quote(tmp / "in.csv") + " -o " + test::shell_quote(tmp / "out") + kSky);
  const test::Csv csv = test::read_csv(tmp / "out" / "sky.csv");
  ASSERT_EQ(csv.rows.size(), 2u);
  const std::string head = "id,sun_az_deg,sun_el_deg,view_az_deg,view_el_deg,dop,aop_deg,I_sr,Q_sr,U_sr\n"
                           "a,150,36.8699,0,90,0.41";
  EXPECT_EQ(test::read_file(tmp / "out" / "sky.csv").substr(0, head.size()), head);
  for (const auto& row : csv.rows) {
    const double I = std::stod(row[csv.col("I_sr")]), Q = std::stod(row[csv.col("Q_sr")]), U = std::stod(row[csv.col("U_sr")]);
    EXPECT_NEAR(std::hypot(Q, U) / I, std::stod(row[csv.col("dop")]), 1e-12);
    EXPECT_NEAR(std::remainder(aop_deg(Q, U) - std::stod(row[csv.col("aop_deg")]), 180.0), 0, 1e-9);
  }
  EXPECT_NEAR(std::stod(csv.rows[0][csv.col("dop")]), 0.412, 1e-3);
  test::write_file(tmp / "low.csv", "sun_az_deg,sun_el_deg,view_az_deg,view_el_deg\n150,30,0,90\n150,1,0,90\n");
  const Result r = polrig("sky table " + test::shell_quote(tmp / "low.csv") + " -o " + test::shell_quote(tmp / "low") + kSky);
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, "low.csv:3: column 'sun_el_deg': vector-rt sky: the sun's elevation 1° is outside [2°, 90°]");
  EXPECT_FALSE(fs::exists(tmp / "low"));
}

TEST_F(VectorRtSkyCli, NeutralPointsCsvAndTheSingleScatteringSkysNone) {
  ok("sky neutral-points --sun-el-deg 20:40:3 --no-plots -o " + test::shell_quote(tmp / "np") + kSky);
  const test::Csv csv = test::read_csv(tmp / "np" / "neutral_points.csv");
  ASSERT_EQ(csv.rows.size(), 3u);
  EXPECT_EQ(csv.rows[2][csv.col("sun_el_deg")], "40");
  EXPECT_EQ(csv.rows[0][csv.col("brewster_deg")], "nan");  // 20° up: Brewster below the horizon
  EXPECT_NEAR(std::stod(csv.rows[1][csv.col("babinet_deg")]), 17.6, 0.5);
  ok("sky neutral-points --set source.model=sky --sun-el-deg 30 --no-plots -o " + test::shell_quote(tmp / "ss"));
  EXPECT_EQ(test::read_file(tmp / "ss" / "neutral_points.csv"), "sun_el_deg,babinet_deg,brewster_deg,arago_deg\n30,nan,nan,nan\n");
  const Result r = polrig("sky neutral-points --sun-el-deg 1:60:5 -o " + test::shell_quote(tmp / "bad") + kSky);
  EXPECT_EQ(r.status, 2);
  EXPECT_HAS(r.err, "--sun-el-deg 1:60:5: the sun's elevation 1° is outside [2°, 90°]");
}

TEST_F(VectorRtSkyCli, MapShowsTheDifferenceFromSingleScattering) {
  const std::string plots = test::gnuplot_present() ? "" : " --no-plots";
  ok("sky --size 64 -o " + test::shell_quote(tmp / "map") + kSky + " --set sky.first_stop_utc=2018-11-16T04:00:00Z" + plots);
  EXPECT_TRUE(fs::exists(tmp / "map" / "sky.exr"));
  if (plots.empty()) {
    EXPECT_TRUE(fs::exists(tmp / "map" / "aop_difference.png"));
    EXPECT_TRUE(fs::exists(tmp / "map" / "dop_ratio.png"));
  }
}

}  // namespace
}  // namespace polrig
