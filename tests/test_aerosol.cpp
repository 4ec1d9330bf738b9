// The aerosol layer of the vector-RT sky (spec skies.md §2 "Aerosols") against independent
// references: the phase-matrix file's own stated properties, Wigner's d-functions by their explicit
// sum, Rayleigh's and Henyey–Greenstein's closed-form expansions, the exact Rayleigh tables reached
// through the aerosol's path (reader → expansion → δ-M → four Stokes components → single-scattering
// correction), the thin-layer limit against the file's numbers, and flux conservation.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "polrig/io/rig_yaml.h"
#include "polrig/rig/error.h"
#include "polrig/rig/rig.h"
#include "polrig/sky/aerosol.h"
#include "polrig/sky/vector_rt.h"
#include "polrig/sky/vector_rt_sky.h"
#include "polrig/units.h"
#include "rayleigh_tables.h"
#include "support.h"

namespace polrig {
namespace {

const std::string kA4 = std::string(POLRIG_SOURCE_DIR) + "/data/aerosol-phase-matrix/iprt-a4-spheroids-350nm.txt";
constexpr double kA4Ssa = 0.787581;  // the file's header (IPRT case A4)

std::shared_ptr<const PhaseMatrixTable> a4() {
  static const auto t = std::make_shared<const PhaseMatrixTable>(read_phase_matrix(kA4));
  return t;
}

// A phase matrix tabulated every `step_deg` from a closed form (the tests' own, not the file reader's).
template <class F>
PhaseMatrixTable tabulated(F elements, double step_deg) {
  PhaseMatrixTable t;
  t.source = "closed form";
  const int n = static_cast<int>(std::lround(180 / step_deg));
  for (int i = 0; i <= n; ++i) {
    t.theta_deg.push_back(i * step_deg);
    t.elements.push_back(elements(std::cos(i * step_deg * kDeg)));
  }
  return t;
}

TEST(Aerosol, ReadsTheIprtFileWithItsStatedNormalizationAndAsymmetry) {
  const PhaseMatrixTable& t = *a4();
  EXPECT_EQ(t.theta_deg.size(), 1801u);
  // The file's README: ½∫P1 sinΘ dΘ = 0.99989 as printed; its header: g = 0.83835.
  EXPECT_NEAR(t.normalization_as_read, 0.99989, 1e-5);
  const PhaseExpansion e = expand(t, 2);
  EXPECT_NEAR(e.alpha1[0], 1, 1e-12);
  EXPECT_NEAR(e.alpha1[1] / 3, 0.83835, 1e-4);
  // The layout P = [[P1, P2], [P2, P5]] ⊕ [[P3, P4], [−P4, P6]]: the first row's numbers.
  EXPECT_NEAR(t.elements[0].a1 * t.normalization_as_read, 557.186, 1e-9);
  EXPECT_NEAR(t.elements[0].a2 * t.normalization_as_read, 557.013, 1e-9);
  EXPECT_NEAR(t.elements[0].a4 * t.normalization_as_read, 556.843, 1e-9);
}

// Wigner's d^j_{m'm}(β) by its explicit sum (Wigner 1931; Edmonds 1957 Eq. 4.1.15).
double wigner_sum(int j, int mp, int m, double beta) {
  const auto f = [](int n) { return std::tgamma(n + 1.0); };
  double d = 0;
  for (int k = 0; k <= 2 * j; ++k) {
    const int a = j + m - k, b = j - k - mp, c = k - m + mp;
    if (a < 0 || b < 0 || c < 0) continue;
    d += std::pow(-1.0, c) * std::sqrt(f(j + m) * f(j - m) * f(j + mp) * f(j - mp)) / (f(a) * f(k) * f(b) * f(c)) *
         std::pow(std::cos(beta / 2), 2 * j - 2 * k + m - mp) * std::pow(std::sin(beta / 2), 2 * k - m + mp);
  }
  return d;
}

TEST(Aerosol, WignerFunctionsFollowTheirExplicitSum) {
  for (double beta_deg : {0.0, 17.0, 63.0, 90.0, 141.0, 180.0}) {
    const double x = std::cos(beta_deg * kDeg);
    for (auto [m, n] : {std::pair{0, 0}, std::pair{0, 2}, std::pair{2, 2}, std::pair{2, -2}}) {
      const std::vector<double> d = wigner_d(12, m, n, x);
      for (int l = 0; l <= 12; ++l) {
        const double expected = l < std::max(std::abs(m), std::abs(n)) ? 0 : wigner_sum(l, m, n, beta_deg * kDeg);
        EXPECT_NEAR(d[static_cast<std::size_t>(l)], expected, 1e-12) << "l " << l << " (" << m << ", " << n << ") at " << beta_deg;
      }
    }
    EXPECT_NEAR(wigner_d(30, 0, 0, x)[30], std::legendre(30, x), 1e-12);
  }
}

// Rayleigh's expansion in closed form (Hovenier, van der Mee & Domke 2004 §2.8, in polrig's
// Q = I_l − I_r, where β1 takes the sign of b1 = −¾Δ sin²Θ): α1 = (1, 0, Δ/2), α2_2 = 3Δ,
// α3 = 0, α4_1 = (3/2)ΔΔ', β1_2 = −(√6/2)Δ, nothing else.
TEST(Aerosol, RayleighsExpansionIsItsClosedForm) {
  const double rho = 0.0279, Delta = (1 - rho) / (1 + rho / 2), Delta_p = (1 - 2 * rho) / (1 - rho);
  const PhaseExpansion e = expand(tabulated([&](double x) { return rayleigh_elements(x, rho); }, 0.01), 6);
  const double tol = 1e-6;  // the trapezoid rule at 0.01°
  for (int l = 0; l <= 6; ++l) {
    const auto L = static_cast<std::size_t>(l);
    EXPECT_NEAR(e.alpha1[L], l == 0 ? 1 : l == 2 ? Delta / 2 : 0, tol) << l;
    EXPECT_NEAR(e.alpha2[L], l == 2 ? 3 * Delta : 0, tol) << l;
    EXPECT_NEAR(e.alpha3[L], 0, tol) << l;
    EXPECT_NEAR(e.alpha4[L], l == 1 ? 1.5 * Delta * Delta_p : 0, tol) << l;
    EXPECT_NEAR(e.beta1[L], l == 2 ? -std::sqrt(6.0) / 2 * Delta : 0, tol) << l;
    EXPECT_NEAR(e.beta2[L], 0, tol) << l;
  }
}

// Henyey–Greenstein's α_l = (2l + 1)g^l, so δ-M's f is g^{L+1} (Wiscombe 1977) and the
// truncated α'_l = (2l + 1)(g^l − g^{L+1})/(1 − g^{L+1}).
TEST(Aerosol, DeltaMOfHenyeyGreensteinIsWiscombes) {
  const double g = 0.7;
  const auto hg = [g](double x) {
    ScatteringElements e;
    e.a1 = e.a2 = e.a3 = e.a4 = (1 - g * g) / std::pow(1 + g * g - 2 * g * x, 1.5);
    return e;
  };
  const int L = 15;
  const DeltaM dm = delta_m(expand(tabulated(hg, 0.01), L + 1), L);
  EXPECT_NEAR(dm.f, std::pow(g, L + 1), 1e-6);
  for (int l = 0; l <= L; ++l) {
    const double expected = (2 * l + 1) * (std::pow(g, l) - std::pow(g, L + 1)) / (1 - std::pow(g, L + 1));
    EXPECT_NEAR(dm.truncated.alpha1[static_cast<std::size_t>(l)], expected, 2e-5 * (2 * l + 1)) << l;
  }
}

// The Rayleigh tables through the aerosol's path: the air given as an "aerosol" whose phase matrix
// is Rayleigh's (ρ = 0) tabulated every 0.01°, alone (τ_R = 0) and half and half with the air.
double table_error_through_the_aerosol_path(const std::string& tau, double rayleigh_share) {
  using test::read_rayleigh_table;
  const test::TableBlocks I = read_rayleigh_table("I_DN_TAU_" + tau), Q = read_rayleigh_table("Q_DN_TAU_" + tau),
                          U = read_rayleigh_table("U_DN_TAU_" + tau);
  VectorRtSettings s;
  s.depolarization = 0;
  s.tau_rayleigh = rayleigh_share * std::stod(tau);
  s.aerosol.tau = std::stod(tau) - s.tau_rayleigh;
  s.aerosol.ssa = 1;
  s.aerosol.phase = std::make_shared<const PhaseMatrixTable>(tabulated([](double x) { return rayleigh_elements(x, 0); }, 0.01));
  double worst = 0;
  const double albedos[3] = {0, 0.25, 0.8};
  for (std::size_t b = 0; b < I.size(); b += 2) {  // A = 0 and 0.8
    s.ground_albedo = albedos[b];
    for (std::size_t r0 = 0; r0 < I[b].size(); r0 += 32) {  // every other sun
      std::vector<double> mu;
      for (std::size_t k = 0; k < 16; ++k) mu.push_back(I[b][r0 + k].mu);
      const DiffuseField f = solve_vector_rt(s, I[b][r0].mu0, mu);
      for (std::size_t k = 0; k < 16; ++k)
        for (int p = 0; p < 7; ++p) {
          const Eigen::Vector4d x = f.down_at(k, p * 30 * kDeg) * M_PI;  // the tables' I is π·L/E₀
          const double It = I[b][r0 + k].v[p], Qt = -Q[b][r0 + k].v[p], Ut = -U[b][r0 + k].v[p];
          worst = std::max({worst, std::abs(x(0) / It - 1), std::abs(x(1) - Qt) / It, std::abs(x(2) - Ut) / It});
        }
    }
  }
  return worst;
}

TEST(Aerosol, ARayleighPhaseMatrixFileGivesTheExactTables) {
  // The spec's table accuracy (skies.md §4: I ≲ 1e-5 relative); Q and U relative to I.
  EXPECT_LT(table_error_through_the_aerosol_path("0.1", 0), 1e-5);
  EXPECT_LT(table_error_through_the_aerosol_path("0.25", 0.5), 1e-5);
}

// A layer so thin that it scatters once: I = ϖτ·P1(Θ)/(4πμ) to first order in τ, DoP = −b1/a1
// across the scattering plane, from the file's own numbers at a row's angle.
TEST(Aerosol, AThinLayerScattersOnceAsTheFileSays) {
  VectorRtSettings s;
  s.tau_rayleigh = 0, s.aerosol.tau = 1e-5, s.aerosol.ssa = kA4Ssa, s.aerosol.phase = a4();
  const double mu0 = std::cos(40 * kDeg);
  const std::vector<double> mu = {std::cos(20 * kDeg), std::cos(60 * kDeg)};
  const DiffuseField f = solve_vector_rt(s, mu0, mu);
  for (std::size_t u = 0; u < mu.size(); ++u)
    for (double phi_deg : {0.0, 45.0, 90.0, 135.0, 180.0}) {
      const double phi = phi_deg * kDeg;
      const double x = mu0 * mu[u] + std::sqrt((1 - mu0 * mu0) * (1 - mu[u] * mu[u])) * std::cos(phi);
      // In the solar meridian Θ is a whole degree: the file's own row there, not an interpolation.
      const double theta_deg = std::acos(x) / kDeg;
      const bool on_a_row = phi_deg == 0 || phi_deg == 180;
      const ScatteringElements p =
          on_a_row ? a4()->elements[static_cast<std::size_t>(std::lround(theta_deg * 10))] : a4()->at(x);
      const Eigen::Vector4d v = f.down_at(u, phi);
      const double expected_I = kA4Ssa * s.aerosol.tau * p.a1 / (4 * M_PI * mu[u]);
      EXPECT_NEAR(v(0) / expected_I, 1, 1e-4) << u << " " << phi_deg;
      EXPECT_NEAR(std::hypot(v(1), v(2)) / v(0), std::abs(p.b1) / p.a1, 1e-5) << u << " " << phi_deg;
    }
}

TEST(Aerosol, ConservesTheSunsFluxWithoutAbsorptionAndLosesItWith) {
  VectorRtSettings s;
  s.tau_rayleigh = 0.1, s.aerosol.tau = 0.2, s.aerosol.ssa = 1, s.aerosol.phase = a4();
  for (double mu0 : {1.0, 0.5, 0.2}) {
    const DiffuseFluxes f = vector_rt_fluxes(s, mu0);
    EXPECT_NEAR(f.up_top + f.down_diffuse_bottom + f.down_direct_bottom, mu0, 1e-7 * mu0) << mu0;
  }
  s.aerosol.ssa = kA4Ssa;
  const DiffuseFluxes f = vector_rt_fluxes(s, 0.5);
  EXPECT_LT(f.up_top + f.down_diffuse_bottom + f.down_direct_bottom, 0.5 * 0.97);
}

TEST(Aerosol, RefusesBadFilesNamingTheLineAndColumn) {
  const auto refused = [](const std::string& text, const std::string& message) {
    try {
      (void)parse_phase_matrix(text, "pm.txt");
      ADD_FAILURE() << "accepted: " << text;
    } catch (const PhaseMatrixError& e) {
      EXPECT_HAS(e.what(), message);
    }
  };
  const std::string head = "# theta_deg P1 P2 P3 P4 P5 P6\n";
  refused(head + "0 1 0 1 0 1 1\n90 1 0 1\n", "pm.txt:3: expected 7 columns");
  refused(head + "0 1 zero 1 0 1 1\n", "pm.txt:2: column 3 (P2): 'zero' is not a number");
  refused(head + "0 1 0 1 0 1 1\n0 1 0 1 0 1 1\n180 1 0 1 0 1 1\n", "pm.txt:3: column 1 (theta_deg): 0 does not rise");
  refused(head + "1 1 0 1 0 1 1\n", "pm.txt:2: column 1 (theta_deg): the table must start at 0 degrees");
  refused(head + "0 1 0 1 0 1 1\n90 1 0 1 0 1 1\n170 1 0 1 0 1 1\n", "pm.txt:4: column 1 (theta_deg): the table must end at 180");
  refused(head + "0 1 0 1 0 1 1\n90 1 -1.5 1 0 1 1\n180 1 0 1 0 1 1\n", "pm.txt:3: column 3 (P2): |-1.5| exceeds P1");
  refused(head + "0 1 0 1 0 1 1\n90 0 0 0 0 0 0\n180 1 0 1 0 1 1\n", "pm.txt:3: column 2 (P1): P1 = 0 is not positive");
  refused(head + "0 2 0 2 0 2 2\n90 2 0 0 0 2 0\n180 2 0 -2 0 2 -2\n", "pm.txt:2-4: column 2 (P1): half the integral");
  refused(head + "0 1 0 1 0 1 inf\n", "pm.txt:2: column 7 (P6)");
}

TEST(Aerosol, RefusesStreamsTooFewForTheForwardPeak) {
  VectorRtSettings s;
  s.aerosol.tau = 0.2, s.aerosol.ssa = kA4Ssa, s.aerosol.phase = a4(), s.streams = 16;
  try {
    check_vector_rt(s);
    ADD_FAILURE() << "16 streams accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_HAS(e.what(), "streams 16 are too few for the aerosol's phase matrix");
  }
  s.streams = 32;
  EXPECT_NO_THROW(check_vector_rt(s));
  s.aerosol.phase = nullptr;
  EXPECT_THROW(check_vector_rt(s), std::invalid_argument);
}

const char* kAerosolRig = "source:\n  model: sky\nsky:\n  model: vector-rt\n  rt:\n    aerosol:\n      tau: 0.2\n";

TEST(Aerosol, RigKeysReadTheFileBesideTheRigAndNameTheKeyWhenWrong) {
  test::TempDir dir("aerosol_rig");
  std::filesystem::copy_file(kA4, dir.path() / "a4.txt");
  {
    std::ofstream(dir.path() / "bad.txt") << "# theta_deg P1 P2 P3 P4 P5 P6\n0 1 x 1 0 1 1\n";
  }
  const std::string rig_path = (dir.path() / "rig.yaml").string();
  const LoadedRig r = parse_rig(std::string(kAerosolRig) + "      ssa: 0.787581\n      phase_matrix: a4.txt\n", rig_path);
  const std::optional<Sky> sky = rig_sky(r.rig);
  ASSERT_TRUE(sky && sky->model.vector_rt);
  const AerosolSettings& a = sky->model.vector_rt->settings().aerosol;
  EXPECT_EQ(a.tau, 0.2);
  EXPECT_EQ(a.ssa, 0.787581);
  ASSERT_TRUE(a.phase);
  EXPECT_EQ(a.phase->theta_deg.size(), 1801u);
  EXPECT_EQ(r.rig.source.sky.aerosol_phase_matrix, (dir.path() / "a4.txt").lexically_normal().string());
  const auto refused = [&](const std::string& text, const std::string& message) {
    try {
      (void)parse_rig(text, rig_path);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const RigError& e) {
      EXPECT_HAS(e.what(), message);
    }
  };
  refused(kAerosolRig, "key 'sky.rt.aerosol.phase_matrix'");
  refused(std::string(kAerosolRig) + "      phase_matrix: bad.txt\n", "bad.txt:2: column 3 (P2): 'x' is not a number");
  refused(std::string(kAerosolRig) + "      phase_matrix: none.txt\n", "none.txt: cannot open");
  refused(std::string(kAerosolRig) + "      phase_matrix: a4.txt\n    streams: 16\n", "key 'sky.rt.streams'");
  refused(std::string(kAerosolRig) + "      ssa: 0\n", "key 'sky.rt.aerosol.ssa'");
  refused("source:\n  model: sky\nsky:\n  model: vector-rt\n  rt:\n    aerosol:\n      tau: -1\n", "key 'sky.rt.aerosol.tau'");
  refused("source:\n  model: sky\nsky:\n  model: vector-rt\n  rt:\n    tau_rayleigh: 0\n", "key 'sky.rt.tau_rayleigh'");
}

}  // namespace
}  // namespace polrig

namespace polrig {
namespace {

// Chapman's function for x = R/H = 796.4 against its independent forms: 1/μ₀ overhead; the
// large-x form √(πx/2)·e^{x cos²θ/2}·erfc(√(x/2)·cos θ) (exact to O(1/x)); and at the horizon the
// series √(πx/2)(1 + 3/(8x) − 15/(128x²)) (Chapman 1931; Smith & Smith 1972).
TEST(PseudoSpherical, AirMassIsChapmansFunction) {
  const double x = 6371.0 / 8.0;
  EXPECT_NEAR(chapman_air_mass(1), 1, 1e-9);
  EXPECT_NEAR(chapman_air_mass(0) / (std::sqrt(M_PI * x / 2) * (1 + 3 / (8 * x) - 15 / (128 * x * x))), 1, 1e-6);
  for (double zenith_deg : {30.0, 60.0, 80.0, 85.0, 88.0, 89.0}) {
    const double c = std::cos(zenith_deg * kDeg);
    const double large_x = std::sqrt(M_PI * x / 2) * std::exp(x * c * c / 2) * std::erfc(std::sqrt(x / 2) * c);
    EXPECT_NEAR(chapman_air_mass(c) / large_x, 1, 2e-3) << zenith_deg;
  }
}

TEST(PseudoSpherical, TakesALowerSunAndAgreesWithPlaneParallelOverhead) {
  VectorRtSettings plane, sphere;
  sphere.pseudo_spherical = true;
  EXPECT_THROW((void)VectorRtSky(plane).for_sun(1.5), std::invalid_argument);
  EXPECT_NO_THROW((void)VectorRtSky(sphere).for_sun(1.5));
  EXPECT_THROW((void)VectorRtSky(sphere).for_sun(0.9), std::invalid_argument);
  // A high sun's beam is the same (air mass 1.1547 against 1.1545 at 30° zenith).
  const double mu0 = std::cos(30 * kDeg);
  const Eigen::Vector4d a = solve_vector_rt(plane, mu0, {1.0}).down_at(0, 0);
  const Eigen::Vector4d b = solve_vector_rt(sphere, mu0, {1.0}).down_at(0, 0);
  EXPECT_NEAR(b(0) / a(0), 1, 1e-4);
  // A low sun's beam crosses less air than 1/μ₀: the sky under it is brighter at the zenith.
  const double low = std::sin(3 * kDeg);
  EXPECT_GT(solve_vector_rt(sphere, low, {1.0}).down_at(0, 0)(0), solve_vector_rt(plane, low, {1.0}).down_at(0, 0)(0));
}

}  // namespace
}  // namespace polrig
