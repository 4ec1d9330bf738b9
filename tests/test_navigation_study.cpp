// study/navigation_study.h and `polrig study navigation` (Z21 Figs. 16–17, spec sky-and-compasses.md
// §4.5–4.6): the sweeps' rigs against io/'s re-parse, bit-identity for any thread count, the tilt
// study against its closed form, the DoP bins against a computation here from the trials' datasets,
// and the command's files and refusals.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>
#include <tuple>
#include <vector>

#include <fmt/format.h>
#include <tbb/global_control.h>

#include "polrig/io/rig_yaml.h"
#include "polrig/random.h"
#include "polrig/report/navigation_study_report.h"
#include "polrig/rig/error.h"
#include "polrig/statistics.h"
#include "polrig/study/navigation_study.h"
#include "support.h"

using namespace polrig;
using namespace polrig::test;
namespace fs = std::filesystem;

namespace {

const std::string kStatic = POLRIG_SOURCE_DIR "/rigs/zhang2021-static.yaml";
const std::string kVehicle = POLRIG_SOURCE_DIR "/rigs/zhang2021-vehicle.yaml";

// Z21's static rig, `seconds` long, PNS over a `window` (its fits start once the window is full).
Rig short_rig(double seconds, double window) {
  return load_rig(kStatic, {{"trajectory.duration_s", fmt::format("{}", seconds)},
                            {"navigation.pns_window_s", fmt::format("{}", window)}})
      .rig;
}

std::string rig_error_of(const Rig& rig, std::string_view key, double value) {
  try {
    rig_with_value(rig, key, value);
  } catch (const RigError& e) {
    return e.what();
  }
  ADD_FAILURE() << key << "=" << value << ": no RigError";
  return "";
}

std::uint64_t bits(double v) { return std::bit_cast<std::uint64_t>(v); }

// The E-vector error of a reading as Fig. 16 takes it: axial, degrees.
double axial_error_deg(double a, double b) { return std::abs(std::remainder(a - b, kPi)) * 180 / kPi; }

}  // namespace

// A swept value is the rig a --set of it gives (io/rig_yaml's parse of the rig file), and the
// values a rig file could not hold are refused naming the key and the value.
TEST(NavigationStudy, SweptRigsAreTheReparsedRigs) {
  const Rig rig = load_rig(kStatic).rig;
  for (const NavigationSweep& sw : navigation_sweeps()) {
    const double value = sw.factor == "duration" ? 600 : sw.factor == "p_max" ? 0.45 : sw.factor == "noise" ? 3e-4 : 40;
    SCOPED_TRACE(sw.key);
    const Rig swept = rig_with_value(rig, sw.key, value);
    const Rig parsed = load_rig(kStatic, {{std::string(sw.key), fmt::format("{}", value)}}).rig;
    EXPECT_EQ(rig_to_yaml(swept), rig_to_yaml(parsed));
  }
  EXPECT_HAS(rig_error_of(rig, "sky.p_max", 1.5), "sky.p_max=1.5");
  EXPECT_HAS(rig_error_of(rig, "electronics.noise_sigma_V", -1), "electronics.noise_sigma_V=-1");
  EXPECT_HAS(rig_error_of(rig, "trajectory.duration_s", 0), "trajectory.duration_s=0");
  // check_rig's cross-key rule: a whole number of IMU intervals (1/100 s) per segment.
  EXPECT_HAS(rig_error_of(rig, "trajectory.duration_s", 10.005), "IMU intervals");
  // A value the rig would ignore: the vehicle's segments replace trajectory.duration_s.
  EXPECT_HAS(rig_error_of(load_rig(kVehicle).rig, "trajectory.duration_s", 600), "segment_s");

  NavigationStudySettings s;
  s.p_max = {0.5, 2};
  try {
    check_navigation_study_settings(rig, s);
    ADD_FAILURE() << "p_max 2 accepted";
  } catch (const RigError& e) {
    EXPECT_HAS(std::string(e.what()), "p_max 2");
  }
  s = {};
  s.tilts_deg = {1, 11};
  EXPECT_THROW(check_navigation_study_settings(rig, s), std::invalid_argument);
  s = {};
  s.trials = 0;
  EXPECT_THROW(check_navigation_study_settings(rig, s), std::invalid_argument);
  // Not a unit array: require_instrument's message.
  try {
    navigation_study(load_rig(kDefaultRigFile).rig, {});
    ADD_FAILURE() << "a six-photodiode rig accepted";
  } catch (const RigError& e) {
    EXPECT_HAS(std::string(e.what()), "unit");
  }
}

// Every trial a pure function of (rig, cell, trial), stored by index: the same bits under 1 and 2
// threads, in the structs and in every file the report writes. Two trials of 40 s, one value of
// each sweep (5 cells).
TEST(NavigationStudy, BitIdenticalForAnyThreadCount) {
  const Rig rig = short_rig(40, 20);
  NavigationStudySettings s;
  s.trials = 2;
  s.durations_s = {30};
  s.p_max = {0.45};
  s.noise_sigma_V = {3.1e-3};  // the rig's own value: its cell is the baseline's, bit for bit
  s.ring_tilts_deg = {40};
  NavigationStudy one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = navigation_study(rig, s);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = navigation_study(rig, s);
  }
  ASSERT_EQ(one.cells.size(), 5u);
  ASSERT_EQ(one.trials.size(), 5u * 2u * 3u);
  ASSERT_EQ(two.trials.size(), one.trials.size());
  for (std::size_t i = 0; i < one.trials.size(); ++i) {
    const NavigationTrialResult &a = one.trials[i], &b = two.trials[i];
    EXPECT_EQ(bits(a.final_north_m), bits(b.final_north_m)) << i;
    EXPECT_EQ(bits(a.final_east_m), bits(b.final_east_m)) << i;
    EXPECT_EQ(bits(a.lat_deg.mae), bits(b.lat_deg.mae)) << i;
    EXPECT_EQ(bits(a.lon_deg.rmse), bits(b.lon_deg.rmse)) << i;
    EXPECT_EQ(bits(a.nees_position), bits(b.nees_position)) << i;
    EXPECT_EQ(bits(a.nees_attitude), bits(b.nees_attitude)) << i;
    EXPECT_EQ(bits(a.final_heading_error_deg), bits(b.final_heading_error_deg)) << i;
  }
  // The trials' seeds: derive_seed(rig seed, trial), the same in every cell (common random numbers).
  EXPECT_EQ(one.trials[0].seed, derive_seed(rig.seed, 0));
  EXPECT_EQ(one.trials[3].seed, derive_seed(rig.seed, 1));
  EXPECT_EQ(one.trials[6].seed, derive_seed(rig.seed, 0));
  // Cell 3 (noise = the rig's 3.1e-3 V) repeats cell 0: the same seeds and the same rig.
  for (std::size_t i = 0; i < 6; ++i) {
    EXPECT_EQ(bits(one.trials[18 + i].final_north_m), bits(one.trials[i].final_north_m)) << i;
    EXPECT_EQ(bits(one.trials[18 + i].lon_deg.mae), bits(one.trials[i].lon_deg.mae)) << i;
  }
  // The 30 s cell ends at 30 s.
  EXPECT_NEAR(one.trials[6].final_t_s, 30, 1e-6);
  TempDir dir("polrig_test_navigation_study_");
  fs::create_directories(dir.path() / "1");
  fs::create_directories(dir.path() / "2");
  const auto files = report_navigation_study(dir.path() / "1", one, false);
  report_navigation_study(dir.path() / "2", two, false);
  ASSERT_EQ(files.size(), 7u);  // goal.csv with the six tables
  for (const DatasetFile& f : files)
    EXPECT_EQ(read_file(dir.path() / "1" / f.name), read_file(dir.path() / "2" / f.name)) << f.name;
}

// Fig. 17 against its closed form, and Fig. 16's bins against the readings of the trials' own
// datasets (simulate_navigation with each trial's seed, binned here). Three trials of 250 s.
TEST(NavigationStudy, TiltStudyMatchesTheClosedFormAndDopBinsTheReadings) {
  const Rig rig = short_rig(250, 30);
  NavigationStudySettings s;
  s.trials = 3;
  s.tilts_deg = {0.5, 1, 2};
  const NavigationStudy study = navigation_study(rig, s);

  // Every reading of the trials, simulated again here.
  std::vector<double> elevations;
  std::vector<long long> count(40, 0);
  std::vector<double> sum(40, 0), sum2(40, 0);
  std::size_t readings = 0;
  for (int k = 0; k < s.trials; ++k) {
    Rig r = rig;
    r.seed = derive_seed(rig.seed, static_cast<std::uint64_t>(k));
    const NavigationDataset d = simulate_navigation(r);
    readings += d.compass.size();
    for (double H : d.truth->sun_elevation_rad) elevations.push_back(H);
    for (const CompassEpoch& e : d.compass)
      for (const UnitSample& u : e.samples) {
        if (!std::isfinite(u.aop_rad) || !std::isfinite(u.dop)) continue;
        // The bin by comparison with its edges (b/20 ≤ d < (b+1)/20), not by the library's arithmetic.
        int b = 0;
        while (u.dop >= (b + 1) * 5 / 100.0) ++b;
        const double err = axial_error_deg(u.aop_rad, u.true_aop_rad);
        ++count[static_cast<std::size_t>(b)];
        sum[static_cast<std::size_t>(b)] += err;
        sum2[static_cast<std::size_t>(b)] += err * err;
      }
  }

  // Fig. 17. The closed form: a tilt τ of the attitude about a horizontal axis turns s^n about it,
  // so sin H′ = sin H·cos τ + cos H·sin τ·cos Δ, Δ uniform (the tilt's direction against the sun's
  // azimuth); to first order H′ − H = τ·cos Δ, E|H′ − H| = (2/π)·τ, and the SD of |τ cos Δ| is
  // τ·√(1/2 − 4/π²). Exact expectation here by Simpson's rule over Δ at the truth's mean H.
  double mean_H = 0;
  for (double H : elevations) mean_H += H / static_cast<double>(elevations.size());
  ASSERT_EQ(study.tilt.size(), 3u);
  for (const TiltErrorRow& row : study.tilt) {
    SCOPED_TRACE(row.tilt_deg);
    const double tau = row.tilt_deg * kPi / 180;
    const int n = 20000;  // Simpson, even n; the kinks at Δ = ±90° sit on nodes
    double simpson = 0;
    for (int i = 0; i <= n; ++i) {
      const double D = 2 * kPi * i / n;
      const double f = std::abs(std::asin(std::sin(mean_H) * std::cos(tau) + std::cos(mean_H) * std::sin(tau) * std::cos(D)) - mean_H);
      simpson += f * (i == 0 || i == n ? 1 : i % 2 ? 4 : 2);
    }
    const double exact_deg = simpson / (3.0 * n) * 180 / kPi;  // (h/3)·Σ / 2π with h = 2π/n
    // Every reading has a sun (the static rig's DoPs are far from degenerate).
    EXPECT_EQ(row.draws, static_cast<long long>(readings));
    // The library's quadrature at its mean H (of the measured s^n, within 0.01° of the truth's):
    // dE/dH is O(τ²) ≈ 1e-3·τ per rad at τ = 2°, so 1e-4·τ covers it.
    EXPECT_NEAR(row.exact_deg, exact_deg, 1e-4 * row.tilt_deg);
    EXPECT_NEAR(row.first_order_deg, 2 / kPi * row.tilt_deg, 1e-15);
    // The Monte-Carlo mean within 4 standard errors of the closed form (SE from the closed-form SD;
    // the readings' directions are independent draws).
    const double se = row.tilt_deg * std::sqrt(0.5 - 4 / (kPi * kPi)) / std::sqrt(static_cast<double>(row.draws));
    EXPECT_NEAR(row.mean_abs_deg, exact_deg, 4 * se);
    // The RMS of τ cos Δ is τ/√2. Var(τ² cos² Δ) = τ⁴(3/8 − 1/4) = τ⁴/8, so the mean square's SE is
    // τ²/(2√2·√N) and the RMS's ≈ that/(2·RMS) = τ/(4√N): 4 SE = τ/√N.
    EXPECT_NEAR(row.rms_deg, row.tilt_deg / std::sqrt(2.0), row.tilt_deg / std::sqrt(static_cast<double>(row.draws)));
    EXPECT_LE(row.max_abs_deg, row.tilt_deg * (1 + 1e-9));
  }

  // Fig. 16: the same counts, and the same means and SDs to rounding (the sums here are in another
  // order: 1e-12 relative).
  std::size_t nonempty = 0;
  for (const DopBin& b : study.dop) {
    const std::size_t i = static_cast<std::size_t>(std::lround(b.lo * 20));
    SCOPED_TRACE(b.lo);
    ASSERT_LT(i, count.size());
    EXPECT_EQ(b.count, count[i]);
    if (count[i] == 0) {
      EXPECT_TRUE(std::isnan(b.mean_abs_deg));
      continue;
    }
    ++nonempty;
    const double mean = sum[i] / static_cast<double>(count[i]);
    const double sd = std::sqrt(std::max(0.0, sum2[i] / static_cast<double>(count[i]) - mean * mean));
    EXPECT_NEAR(b.mean_abs_deg, mean, 1e-12 * mean);
    // sd from Σx² − n·mean² loses ≈ mean²/sd² · 1e-16 relative; the bins' mean/sd is about 1.4.
    EXPECT_NEAR(b.sd_abs_deg, sd, 1e-9 * mean);
    EXPECT_GE(b.mean_true_dop, b.lo - 0.02);  // the measured DoP scatters ~1e-3 about the true
    EXPECT_LT(b.mean_true_dop, b.hi + 0.02);
  }
  EXPECT_GE(nonempty, 4u);
  EXPECT_EQ(study.dop.back().hi, static_cast<double>(study.dop.size()) * 5 / 100);
}

// ---- the command --------------------------------------------------------------------------------

namespace {
class CliNavigationStudy : public PolrigTest {
 protected:
  CliNavigationStudy() : PolrigTest("polrig_test_cli_navigation_study_", "") {}
};
}  // namespace

TEST_F(CliNavigationStudy, WritesItsFilesAndRefusesBadOptions) {
  const std::string base = "study navigation " + shell_quote(kStatic) +
                           " --set trajectory.duration_s=60 --set navigation.pns_window_s=30 --trials 2 ";
  const bool plots = gnuplot_present();
  const Result r = ok(base + "--p-max 0.45 --tilts 1 " + (plots ? "" : "--no-plots ") + "-o " + shell_quote(tmp / "a"));
  EXPECT_HAS(r.out, "tilt 1°: mean |elevation error|");
  for (const char* f : {"trials.csv", "summary.csv", "error_vs_time.csv", "tilt.csv", "dop.csv", "manifest.yaml", "rig.yaml"})
    EXPECT_TRUE(fs::exists(tmp / "a" / f)) << f;
  if (plots) {
    for (const char* png : {"error_vs_time.png", "final_error_vs_p_max.png", "tilt.png", "dop.png"})
      EXPECT_TRUE(starts_with_png_signature(tmp / "a" / png)) << png;
  }
  const std::string manifest = read_file(tmp / "a" / "manifest.yaml");
  for (const char* f : {"trials.csv", "summary.csv", "tilt.csv", "dop.csv"}) EXPECT_HAS(manifest, f);
  const Csv trials = read_csv(tmp / "a" / "trials.csv");
  EXPECT_EQ(trials.rows.size(), 2u * 2u * 3u);  // (the rig + one P_max) × 2 trials × 3 modes
  const Csv summary = read_csv(tmp / "a" / "summary.csv");
  ASSERT_EQ(summary.rows.size(), 2u * 3u);
  EXPECT_EQ(summary.rows[3][summary.col("factor")], "p_max");
  EXPECT_EQ(summary.rows[3][summary.col("key")], "sky.p_max");
  EXPECT_EQ(read_csv(tmp / "a" / "tilt.csv").rows.size(), 1u);
  EXPECT_EQ(read_csv(tmp / "a" / "error_vs_time.csv").rows.size(), 60u);  // one per 1 Hz reading

  // Bad options: exit 2, the option and the value named, nothing written.
  const auto refused = [&](const std::string& args, const char* dir, std::initializer_list<const char*> words) {
    const Result b = polrig(args + " --no-plots -o " + shell_quote(tmp / dir));
    EXPECT_EQ(b.status, 2) << args << "\n" << b.err;
    for (const char* w : words) EXPECT_HAS(b.err, w);
    EXPECT_FALSE(fs::exists(tmp / dir)) << dir;
  };
  refused(base + "--p-max 0.5,1.5", "p", {"--p-max", "1.5", "sky.p_max"});
  refused(base + "--noise 1e-4,x", "n", {"--noise", "x"});
  refused(base + "--tilts 11", "t", {"--tilts", "11"});
  refused(base + "--durations 10.005", "d", {"--durations", "10.005", "IMU intervals"});
  refused(base + "--ring-tilts 200", "g", {"--ring-tilts", "200"});
  // The third review's finding 17: a run without a compass reading (every statistic nan) is refused.
  refused(base + "--durations 0.5", "r", {"--durations 0.5", "a 0.5 s run holds no compass reading"});
  refused("study navigation " + shell_quote(kStatic) + " --set trajectory.duration_s=0.5 --trials 2", "q",
          {"trajectory.duration_s", "a 0.5 s run holds no compass reading"});
  refused("study navigation " + shell_quote(kVehicle) + " --trials 1 --durations 60", "v", {"--durations", "segment_s"});
  refused("study navigation " + shell_quote(kDefaultRigFile), "s", {"unit"});
}

// The filter's consistency over Monte-Carlo trials (Bar-Shalom et al. 2001 §5.4.2): each trial's INS
// starts at an error drawn from P0 (navigation.initial_errors), so N·(mean NEES) is χ²(N·d) for a
// consistent filter. 100 trials of the shipped static rig, 20 min, R fixed at the σ_H the chain
// delivers (0.0998°, docs/validation.md): with the tilt columns (the default) the NEES of the final
// position (d = 2) and attitude (d = 3) and the mean NIS over 120 000 updates lie inside their 99.9 %
// bands; with Z21's position-only H the position NEES is an order of magnitude outside (the INS's
// tilt enters the measured elevation unmodelled).
TEST(SlowNavigationStudy, TheDefaultFilterIsConsistentAndZ21sHIsNot) {
  constexpr double z999 = 3.2905;
  const auto band999 = [&](double mean, double d, int n) {
    const double dof = d * n;
    return mean >= d * chi2_mean_quantile(dof, -z999) && mean <= d * chi2_mean_quantile(dof, z999);
  };
  NavigationStudySettings s;
  s.trials = 100;
  s.tilts_deg = {};
  for (const char* m : {"elevation", "elevation-z21"}) {
    const Rig rig = load_rig(kStatic, {{"navigation.measurement", m}, {"navigation.adaptive", "false"}}).rig;
    const NavigationStudy study = navigation_study(rig, s);
    ASSERT_EQ(study.consistency.size(), 1u);
    const NavigationConsistency& c = study.consistency[0];
    std::printf("%s: NEES position %.3g [%.3g, %.3g], attitude %.3g [%.3g, %.3g], NIS %.4g [%.4g, %.4g] (95 %% bands)\n", m,
                c.nees_position.mean, c.nees_position.lo, c.nees_position.hi, c.nees_attitude.mean, c.nees_attitude.lo,
                c.nees_attitude.hi, c.nis.mean, c.nis.lo, c.nis.hi);
    EXPECT_EQ(c.trials, 100);
    if (std::string(m) == "elevation") {
      EXPECT_TRUE(band999(c.nees_position.mean, 2, c.trials)) << c.nees_position.mean;
      EXPECT_TRUE(band999(c.nees_attitude.mean, 3, c.trials)) << c.nees_attitude.mean;
      EXPECT_TRUE(band999(c.nis.mean, 1, static_cast<int>(c.nis.dof))) << c.nis.mean;
    } else {
      EXPECT_GT(c.nees_position.mean, 10 * c.nees_position.hi);
    }
  }
}

// The azimuth measurements on the static rig: without zero-velocity updates the INS's tilt grows to
// 1–2° (5°/h gyros, Schuler) and the azimuth's model, linear in φ, is then wrong by more than σ_A
// (its second-order terms ~φ²·s_U/ρ²): NEES ~17. With navigation.zupt the tilt stays at the
// accelerometers' level and every measurement's filter is consistent, NEES and NIS inside their
// 99.9 % bands (docs/validation.md's table).
TEST(SlowNavigationStudy, ZeroVelocityUpdatesMakeTheAzimuthFiltersConsistent) {
  constexpr double z999 = 3.2905;
  const auto band999 = [&](double mean, double d, double n) {
    return mean >= d * chi2_mean_quantile(d * n, -z999) && mean <= d * chi2_mean_quantile(d * n, z999);
  };
  NavigationStudySettings s;
  s.trials = 100;
  s.tilts_deg = {};
  for (const char* m : {"azimuth", "sun-vector", "elevation"}) {
    for (const char* zupt : {"true", "false"}) {
      if (std::string(zupt) == "false" && std::string(m) != "azimuth") continue;
      const Rig rig = load_rig(kStatic, {{"navigation.measurement", m}, {"navigation.adaptive", "false"},
                                         {"navigation.zupt", zupt}}).rig;
      const NavigationConsistency c = navigation_study(rig, s).consistency.at(0);
      std::printf("%s, zupt %s: NEES position %.3g [%.3g, %.3g], attitude %.3g [%.3g, %.3g], NIS %.4g [%.4g, %.4g]\n", m,
                  zupt, c.nees_position.mean, c.nees_position.lo, c.nees_position.hi, c.nees_attitude.mean,
                  c.nees_attitude.lo, c.nees_attitude.hi, c.nis.mean, c.nis.lo, c.nis.hi);
      if (std::string(zupt) == "true") {
        EXPECT_TRUE(band999(c.nees_position.mean, 2, c.trials)) << m << " " << c.nees_position.mean;
        EXPECT_TRUE(band999(c.nees_attitude.mean, 3, c.trials)) << m << " " << c.nees_attitude.mean;
        EXPECT_TRUE(band999(c.nis.mean, 1, c.nis.dof)) << m << " " << c.nis.mean;
      } else {
        EXPECT_GT(c.nees_position.mean, 3 * c.nees_position.hi);
      }
    }
  }
}

// Issue 34 §3's goal: with the whole sun vector and zero-velocity updates the integrated solution
// ends no worse than the better of SINS and PNS, in position and in heading, in at least 95 of 100
// trials on both shipped rigs (99 and 100 measured), its position NEES inside the 99.9 % band. With
// the elevation alone the heading is unobservable and the integrated heading is SINS's coin flip.
TEST(SlowNavigationStudy, TheSunVectorWithZeroVelocityUpdatesMeetsTheGoalOnBothRigs) {
  constexpr double z999 = 3.2905;
  NavigationStudySettings s;
  s.trials = 100;
  s.tilts_deg = {};
  for (const std::string& path : {kStatic, kVehicle}) {
    for (const char* m : {"sun-vector", "elevation"}) {
      const Rig rig = load_rig(path, {{"navigation.measurement", m}, {"navigation.adaptive", "false"},
                                      {"navigation.zupt", "true"}}).rig;
      const NavigationStudy study = navigation_study(rig, s);
      ASSERT_EQ(study.goal.size(), 1u);
      const NavigationGoal& g = study.goal[0];
      const NavigationConsistency& c = study.consistency.at(0);
      std::printf("%s, %s + zupt: goal position %d, heading %d, both %d of %d; NEES position %.3g\n", path.c_str(), m,
                  g.position_met, g.heading_met, g.both_met, g.trials, c.nees_position.mean);
      EXPECT_EQ(g.trials, 100);
      EXPECT_GE(g.position_met, 95) << m;
      if (std::string(m) == "sun-vector") {
        EXPECT_GE(g.both_met, 95);
        EXPECT_GE(c.nees_position.mean, 2 * chi2_mean_quantile(200, -z999));
        EXPECT_LE(c.nees_position.mean, 2 * chi2_mean_quantile(200, z999));
      } else {
        EXPECT_LT(g.heading_met, 75);
      }
    }
  }
}

// Wilson–Hilferty's χ² quantiles against the tables (Abramowitz & Stegun Table 26.8).
TEST(NavigationStudy, ChiSquareBandsAgreeWithTheTables) {
  for (auto [n, lo, hi] : {std::tuple{10.0, 3.247, 20.483}, {40.0, 24.433, 59.342}, {100.0, 74.222, 129.561}}) {
    EXPECT_NEAR(n * chi2_mean_quantile(n, -kNormalQuantile975) / lo, 1.0, n < 40 ? 8e-3 : 5e-4) << n;
    EXPECT_NEAR(n * chi2_mean_quantile(n, kNormalQuantile975) / hi, 1.0, 1e-4) << n;
  }
}
