// The traced source: scene files, the Embree sphere solve, the port's irradiance below it.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "polrig/io/rig_yaml.h"
#include "polrig/io/scene_yaml.h"
#include "polrig/sim/simulate.h"
#include "polrig/study/cs.h"
#include "polrig/study/sweep.h"
#include "polrig/source/sphere_tracer.h"
#include "polrig/source/traced_port.h"
#include "support.h"

namespace polrig {
namespace {

constexpr double kPi = std::numbers::pi;

// A point lamp at the centre and no baffles: every quantity of sphere theory is exact.
SceneSpec theory_sphere(long long photons) {
  SceneSpec s;
  s.lamps = {LampSpec{{0, 0, 0}, 0.0, 100.0, 0.0}};
  s.baffles.clear();
  s.trace.photons = photons;
  s.trace.batches = 16;
  s.trace.wall_bins_theta = 20;
  s.trace.wall_bins_phi = 20;
  return s;
}

// Port fraction of the sphere: cap area 2πRh over 4πR², h = R − √(R² − a²). From the centre the
// cap subtends the same fraction of directions.
double port_fraction(const SceneSpec& s) {
  const double R = s.sphere.radius(), a = s.port.radius();
  return (R - std::sqrt(R * R - a * a)) / (2 * R);
}

TEST(SphereSolve, EnergyBookkeepingClosesAndNothingLeaks) {
  SceneSpec s;  // the default scene: lamp, baffle
  s.trace.photons = 200000;
  const SphereSolution sol = SphereTracer(s).solve();
  const EnergyLedger& L = sol.ledger;
  EXPECT_EQ(L.launched, 200000);
  EXPECT_EQ(L.ended(), L.launched);  // exact: every photon ends once
  EXPECT_EQ(L.leaked, 0);
  EXPECT_GT(L.escaped, 0);
  EXPECT_GT(L.absorbed_baffles, 0);
  EXPECT_GT(L.absorbed_lamps, 0);
  EXPECT_GT(L.rays, L.launched);
}

TEST(SphereSolve, EscapeFractionMatchesSphereTheory) {
  // A photon from the centre leaves directly with probability f, else after each diffuse
  // reflection (probability ρ) with probability f: P = f + (1 − f)·ρf/(1 − ρ(1 − f)).
  // Binomial standard error √(P(1 − P)/N); allow 5.
  const SceneSpec s = theory_sphere(400000);
  const SphereSolution sol = SphereTracer(s).solve();
  const double f = port_fraction(s), rho = s.sphere.reflectance;
  const double P = f + (1 - f) * rho * f / (1 - rho * (1 - f));
  const double N = static_cast<double>(sol.ledger.launched);
  EXPECT_NEAR(sol.ledger.escaped / N, P, 5 * std::sqrt(P * (1 - P) / N));
}

TEST(SphereSolve, MeanWallIrradianceMatchesSphereTheory) {
  // Design: E = Φ·ρ/(A_s·(1 − ρ(1 − f))), first strike excluded, where Φ is the flux that first
  // strikes the wall: Φ(1 − f) for a lamp at the centre. Batch standard error; allow 5.
  const SceneSpec s = theory_sphere(400000);
  const SphereSolution sol = SphereTracer(s).solve();
  const double R = s.sphere.radius(), f = port_fraction(s), rho = s.sphere.reflectance;
  const double A_s = 4 * kPi * R * R * 1e-6, A_wall = A_s * (1 - f);
  const double theory = 100.0 * (1 - f) * rho / (A_s * (1 - rho * (1 - f)));
  double m = 0, m2 = 0;
  const auto& b = sol.batch_indirect_W;
  for (double w : b) m += w / A_wall / static_cast<double>(b.size());
  for (double w : b) m2 += (w / A_wall - m) * (w / A_wall - m);
  const double se = std::sqrt(m2 / static_cast<double>(b.size() - 1) / static_cast<double>(b.size()));
  EXPECT_NEAR(m, theory, 5 * se);
  EXPECT_LT(se, 0.01 * theory);  // the test has teeth: 1% resolution or better
  // The indirect irradiance is uniform (the integrating sphere's defining property): every bin
  // agrees with the mean within its own errors.
  int outliers = 0;
  for (std::size_t i = 0; i < sol.wall.E.size(); ++i) {
    if (sol.wall.wall_area_mm2[i] < 0.5 * sol.wall.wall_area_mm2[0]) continue;  // port-cut bins
    const double e = sol.wall.E[i] - sol.wall.E_first[i];
    const double e_se = std::hypot(sol.wall.E_se[i], sol.wall.E_first_se[i]);
    outliers += std::abs(e - theory) > 5 * e_se;
  }
  EXPECT_EQ(outliers, 0);
}

TEST(SphereSolve, DirectIrradianceMatchesTheTalliedFirstStrike) {
  // The first strike is computed, not sampled: Φ/(4π)·cos θ/D². For a lamp at the centre it is
  // Φ/(4πR²) everywhere; the tallied first-strike map must agree bin by bin within 5 standard
  // errors.
  const SceneSpec s = theory_sphere(400000);
  const SphereTracer tracer(s);
  const SphereSolution sol = tracer.solve();
  const double R = s.sphere.radius(), expected = 100.0 / (4 * kPi * R * R) * 1e6;
  EXPECT_NEAR(tracer.direct_irradiance({0, 0, R}), expected, 1e-9 * expected);
  EXPECT_NEAR(tracer.direct_irradiance({R * 0.6, 0, -R * 0.8}), expected, 1e-9 * expected);
  int outliers = 0;
  for (std::size_t i = 0; i < sol.wall.E_first.size(); ++i) {
    if (sol.wall.wall_area_mm2[i] < 0.5 * sol.wall.wall_area_mm2[0]) continue;
    outliers += std::abs(sol.wall.E_first[i] - expected) > 5 * sol.wall.E_first_se[i];
  }
  EXPECT_EQ(outliers, 0);
}

// A solution whose wall has the same radiance L everywhere, to test the port integrals alone.
SphereSolution uniform_wall(const SceneSpec& s, double L) {
  SphereSolution sol;
  sol.wall.n_theta = s.trace.wall_bins_theta;
  sol.wall.n_phi = s.trace.wall_bins_phi;
  const std::size_t n = static_cast<std::size_t>(sol.wall.n_theta * sol.wall.n_phi);
  sol.wall.E.assign(n, kPi * L / s.sphere.reflectance);
  return sol;
}

TEST(PortIrradiance, MatchesTheExactDiskViewFactor) {
  // Uniform radiance L behind the port (its film passes g_up of it): E at height h, offset r, against
  // E = πL/2·[1 − (h² + r² − a²)/√((h² + r² + a²)² − 4a²r²)]. Quasi-random error from 8 shifts;
  // allow 5 standard errors.
  const SceneSpec s = theory_sphere(1000);
  const SphereTracer tracer(s);
  const double L = 1000.0;
  const SphereSolution sol = uniform_wall(s, L);
  const TracedPort port(tracer, sol);
  const double g_up = 0.5 * (s.port.polarizer.tau_M + s.port.polarizer.tau_m);
  for (double h : {5.0, 20.0, 40.0}) {
    for (double r : {0.0, 10.0, 30.0, 49.0, 60.0, 90.0}) {
      const StokesIrradiance e = port.plane_irradiance(r, 0.0, h, 4096, 8);
      const double exact = g_up * disk_irradiance(L, s.port.radius(), h, r);
      EXPECT_NEAR(e.S0, exact, 5 * e.S0_se + 1e-9 * exact) << "h=" << h << " r=" << r;
      EXPECT_LT(e.S0_se, 1e-2 * exact + 1e-9) << "h=" << h << " r=" << r;  // resolves 1%
    }
  }
}

TEST(PortIrradiance, SmallPortGivesCosineToTheFourth) {
  // For a ≪ h the disk view factor tends to πLa²·h²/(h² + r²)², so E(r)/E(0) → cos⁴φ. With
  // a = 0.5 mm, h = 20 mm the exact finite-port correction (from the disk formula) is below 0.2%:
  // the traced ratio must sit within 5 standard errors of the exact one, and so within that
  // correction of cos⁴φ.
  SceneSpec s = theory_sphere(1000);
  s.port.diameter = 1.0;
  const SphereTracer tracer(s);
  const SphereSolution sol = uniform_wall(s, 1000.0);
  const TracedPort port(tracer, sol);
  const double h = 20.0, a = s.port.radius();
  const StokesIrradiance e0 = port.plane_irradiance(0, 0, h, 4096, 8);
  for (double r : {5.0, 10.0, 20.0, 30.0}) {
    const StokesIrradiance e = port.plane_irradiance(r, 0, h, 4096, 8);
    const double cos4 = std::pow(h * h / (h * h + r * r), 2);
    const double exact = disk_irradiance(1, a, h, r) / disk_irradiance(1, a, h, 0);
    EXPECT_LT(std::abs(exact / cos4 - 1), 2e-3) << "r=" << r;
    const double ratio = e.S0 / e0.S0;
    const double se = ratio * std::hypot(e.S0_se / e.S0, e0.S0_se / e0.S0);
    EXPECT_NEAR(ratio, exact, 5 * se + 1e-12) << "r=" << r;
    EXPECT_NEAR(ratio, cos4, std::abs(exact - cos4) + 5 * se + 1e-12) << "r=" << r;
  }
}

TEST(PortIrradiance, FilmGivesItsDegreeOfPolarizationAndAxis) {
  // Behind the port film (τM, τm, axis ψ): S0 = g_up·E, S1 = g_tp·cos2ψ·E, S2 = g_tp·sin2ψ·E, so
  // d = (τM − τm)/(τM + τm) and the angle is ψ.
  SceneSpec s = theory_sphere(1000);
  s.port.polarizer = {30.0, 0.62, 0.18};
  const SphereTracer tracer(s);
  const SphereSolution sol = uniform_wall(s, 500.0);
  const StokesIrradiance e = TracedPort(tracer, sol).plane_irradiance(3.0, -2.0, 20.0, 1024, 4);
  EXPECT_NEAR(std::hypot(e.S1, e.S2) / e.S0, 0.55, 1e-12);
  EXPECT_NEAR(0.5 * std::atan2(e.S2, e.S1) * 180 / kPi, 30.0, 1e-9);
}

// ---- Scene files -------------------------------------------------------------------------

TEST(SceneFile, TheJf500SceneLoads) {
  const SceneSpec s = load_scene(POLRIG_SOURCE_DIR "/scenes/jf500.yaml");
  EXPECT_EQ(s.sphere.diameter, 500.0);
  EXPECT_EQ(s.port.diameter, 100.0);
  EXPECT_EQ(s.sensor.lens_focal_length, 50.0);
  EXPECT_EQ(s.sensor.lens_diameter, 12.7);
  EXPECT_EQ(s.sensor.photodiode_size, 1.3);
  EXPECT_EQ(s.sensor.housing_height, 100.0);
  EXPECT_NEAR(s.port.polarizer.degree_of_polarization(), 0.55, 1e-12);
  // The dump loads back to the same text.
  EXPECT_EQ(scene_to_yaml(parse_scene(scene_to_yaml(s), "dump")), scene_to_yaml(s));
}

void expect_scene_error(const std::string& text, const std::string& expected) {
  try {
    parse_scene(text, "scenes/test.yaml");
    FAIL() << "accepted:\n" << text;
  } catch (const RigError& e) {
    EXPECT_HAS(e.what(), expected);
  }
}

TEST(SceneFile, BadScenesAreRejectedWithFileLineAndKey) {
  expect_scene_error("sphere:\n  diameter: [1\n", "scenes/test.yaml:3:1: YAML syntax error");
  expect_scene_error("sphere:\n  diametre: 500\n", "scenes/test.yaml:2: key 'sphere.diametre': unknown key");
  expect_scene_error("sphere:\n  reflectance: 1.0\n",
                     "scenes/test.yaml:2: key 'sphere.reflectance': expected a reflectance in [0, 1), got 1.0");
  expect_scene_error("sphere:\n  diameter: -5\n", "scenes/test.yaml:2: key 'sphere.diameter': expected a length > 0, got -5");
  expect_scene_error("port:\n  diameter: 600\n",
                     "scenes/test.yaml:2: key 'port.diameter': expected a port smaller than the sphere (500 mm), got 600");
  expect_scene_error("lamps:\n  - position: [0, 0, 245]\n",
                     "scenes/test.yaml:2: key 'lamps[0].position': expected a lamp inside the sphere");
  expect_scene_error("lamps: []\n", "key 'lamps': expected at least one lamp");
  expect_scene_error("port:\n  polarizer:\n    tau_M: 0.2\n    tau_m: 0.3\n",
                     "scenes/test.yaml:4: key 'port.polarizer.tau_m': expected tau_m < tau_M (0.2), got 0.3");
  expect_scene_error("sensor:\n  geometry: fisheye\n",
                     "scenes/test.yaml:2: key 'sensor.geometry': expected \"bare\" or \"lensed\", got 'fisheye'");
  expect_scene_error("sensor:\n  lens_index: 0.9\n",
                     "scenes/test.yaml:2: key 'sensor.lens_index': expected a refractive index > 1, got 0.9");
  expect_scene_error("trace:\n  photons: 1500.5\n",
                     "scenes/test.yaml:2: key 'trace.photons': expected an integer in [1000, 100000000000], got 1500.5");
}

TEST(SceneFile, AMissingFileIsNamed) {
  try {
    load_scene("/nonexistent/scene.yaml");
    FAIL();
  } catch (const RigError& e) {
    EXPECT_HAS(e.what(), "/nonexistent/scene.yaml: cannot read the scene file: no such file");
  }
}

}  // namespace
}  // namespace polrig

namespace polrig {
namespace {

// ---- The traced source in the rig pipeline ------------------------------------------------

std::string write_theory_scene(const test::TempDir& dir) {
  const std::string path = (dir.path() / "theory.yaml").string();
  test::write_file(path,
                   "sphere: {diameter: 500, reflectance: 0.98}\n"
                   "port: {diameter: 100, polarizer: {axis_deg: 0, tau_M: 0.62, tau_m: 0.18}}\n"
                   "lamps:\n  - {position: [0, 0, 0], radius: 0, power: 100}\n"
                   "baffles: []\n"
                   "trace: {photons: 200000, plane_samples: 1024}\n");
  return path;
}

TEST(SlowTracedRig, SensorOffsetBiasFollowsTheDiskViewFactor) {
  // A lamp at the centre and no baffle: the port is a uniform disk (up to the solve's noise).
  // With the port centred and the sensor off by L_S, every ΔV is the constant
  // kv·v_dec·log10(E_j/E_h), E from the exact disk view factor averaged over the photodiode
  // (2 × 2 Gauss points, as the source does): the traced expectation must match it within
  // 5 standard errors (measured: within 2.3).
  const test::TempDir dir("polrig_test_traced_");
  const std::string scene = write_theory_scene(dir);
  LoadedRig r = parse_rig("source:\n  model: traced\n  scene: " + scene +
                              "\neccentricity: {L_IS: 0, alpha_IS: 0, L_S: 0.5, alpha_S: 70}\n",
                          "inline");
  const Rig& rig = r.rig;
  ASSERT_NE(rig.source.traced, nullptr);
  const CsStudy s = cs_study(rig, CsTurn(36));
  EXPECT_TRUE(s.traced);
  const double a = 50.0, h = rig.source.cos4.L_o, g = 0.5 * 1.3 / std::sqrt(3.0);
  const auto p0 = photodiode_positions(rig.device.ring, rig.eccentricity, 0.0);
  const auto E_square = [&](const Point2& p) {
    double e = 0;
    for (int k = 0; k < 4; ++k)
      e += 0.25 * disk_irradiance(1.0, a, h, std::hypot(p.x() + ((k & 1) ? g : -g), p.y() + ((k & 2) ? g : -g)));
    return e;
  };
  for (int i = 0; i < 3; ++i) {
    const double expected = rig.device.truth.kv[i] * 0.5 *
                            std::log10(E_square(p0[2 * i]) / E_square(p0[2 * i + 1])) * 1e3;
    EXPECT_NEAR(s.summary[i].mean_br_mV, expected, 5 * s.summary[i].mean_br_se_mV) << "pair " << i + 1;
    EXPECT_GT(std::abs(expected), 0.05);  // a real signal (mV)
    // The cos⁴ law would give a much larger constant at this L_o: the port is not small.
    Rig cos4 = rig;
    cos4.source = SourceSpec{};
    cos4.source.cos4.L_o = h;
    EXPECT_GT(std::abs(cs_study(cos4, CsTurn(36)).summary[i].mean_br_mV), 5 * std::abs(expected));
  }
}

TEST(TracedRig, SimulateRunsWithTheFilmsPolarization) {
  const test::TempDir dir("polrig_test_traced_");
  const std::string scene = write_theory_scene(dir);
  LoadedRig r = parse_rig("source: {model: traced, scene: " + scene +
                              "}\nschedule: {start_deg: 0, step_deg: 90, stop_deg: 180, samples_per_stop: 2}\n",
                          "inline");
  const Simulation sim = simulate(r.rig);
  ASSERT_EQ(sim.stops.size(), 3u);
  EXPECT_NEAR(sim.stops[0].light.d, 0.55, 1e-12);
  EXPECT_GT(sim.stops[0].light.E_Wm2[0], 0);
  EXPECT_EQ(rig_to_yaml(r.rig).find("truth_from"), std::string::npos);
  EXPECT_NE(rig_to_yaml(r.rig).find(scene), std::string::npos);  // the absolute scene path
  EXPECT_EQ(r.rig.device.d, sim.stops[0].light.d);  // the rig's d is the film's
}

TEST(TracedRig, SceneAnglesAreMirroredIntoTheRigFrame) {
  // The scene is seen from above, the rig from below: a port film at +30° in the scene is at
  // −30° in the rig frame, so the sensor sees θ = θ_R + 30°.
  const test::TempDir dir("polrig_test_traced_");
  const std::string path = (dir.path() / "film30.yaml").string();
  test::write_file(path,
                   "port: {polarizer: {axis_deg: 30, tau_M: 0.62, tau_m: 0.18}}\n"
                   "lamps:\n  - {position: [0, 0, 0], radius: 0, power: 100}\nbaffles: []\n"
                   "trace: {photons: 20000, plane_samples: 64}\n");
  LoadedRig r = parse_rig("source: {model: traced, scene: " + path +
                              "}\nschedule: {angles_deg: [0, 100]}\n", "inline");
  const Simulation sim = simulate(r.rig);
  EXPECT_NEAR(sim.stops[0].light.theta_deg, 30.0, 1e-12);
  EXPECT_NEAR(sim.stops[1].light.theta_deg, 130.0, 1e-12);
}

TEST(TracedRig, ItsEffectiveRigLoadsBack) {
  // A dataset's rig.yaml must reproduce it: the dump of a traced rig leaves out the settings a
  // traced rig refuses, and loads back to the same text.
  const test::TempDir dir("polrig_test_traced_");
  const std::string scene = write_theory_scene(dir);
  const LoadedRig r = parse_rig("source: {model: traced, scene: " + scene + "}\n", "inline");
  const std::string dump = rig_to_yaml(r.rig);
  EXPECT_LACKS(dump, "E_0");
  EXPECT_LACKS(dump, "polarizer_deg");
  EXPECT_EQ(rig_to_yaml(parse_rig(dump, "dump").rig), dump);
  // A sweep may not vary what the scene sets.
  EXPECT_THROW(check_grid(r.rig, {GridAxis::parse("device.d=0.3:0.5:3")}), RigError);
}

TEST(TracedRig, TheCos4SettingsAreRefused) {
  const test::TempDir dir("polrig_test_traced_");
  const std::string scene = write_theory_scene(dir);
  for (const char* extra : {"\n  polarizer_deg: 10", "\n  E_0: 5"}) {
    try {
      parse_rig("source:\n  model: traced\n  scene: " + scene + extra + "\n", "inline");
      FAIL() << extra;
    } catch (const RigError& e) {
      EXPECT_HAS(e.what(), "expected no value with source.model traced");
    }
  }
  try {
    parse_rig("device: {d: 0.3}\nsource: {model: traced, scene: " + scene + "}\n", "inline");
    FAIL();
  } catch (const RigError& e) {
    EXPECT_HAS(e.what(), "key 'device.d': expected the port film's d = ");
  }
}

}  // namespace
}  // namespace polrig
