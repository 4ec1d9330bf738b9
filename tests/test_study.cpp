// Studies: every "Published behaviour" item of spec §2–3, the CS method's exact properties,
// the simulation's noise statistics and determinism.
#include <gtest/gtest.h>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <thread>
#include <cmath>
#include <complex>
#include <cstring>
#include <limits>
#include <numbers>
#include <random>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

#include <fmt/format.h>

#include "polrig/calib/angles.h"
#include "polrig/progress.h"
#include "polrig/rig/keys.h"
#include "polrig/sim/simulate.h"
#include "polrig/source/source.h"
#include "polrig/study/adc_limit.h"
#include "polrig/study/cs.h"
#include "polrig/study/heading_trials.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/study/sweep.h"
#include "polrig/vector_log.h"
#include "polrig/side_by_side.h"
#include "polrig/statistics.h"
#include "polrig/units.h"
#include "thread_ranks.h"

namespace polrig {
namespace {

// The paper's CS simulation is of an ideal device: theory parameters (kv = 1, v_dec = 0.5 V).
Rig ideal_rig(double L_IS, double alpha_IS, double L_S, double alpha_S) {
  Rig rig;
  rig.device.truth = rig.device.theory();
  rig.eccentricity = {L_IS, alpha_IS, L_S, alpha_S};
  return rig;
}

double max_abs(const std::vector<double>& v) {
  double m = 0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}

// First Fourier harmonic of a curve sampled over one full turn.
std::complex<double> first_harmonic(const std::vector<double>& v) {
  std::complex<double> c = 0;
  const double n = static_cast<double>(v.size());
  for (std::size_t k = 0; k < v.size(); ++k)
    c += v[k] * std::polar(2.0 / n, -2.0 * std::numbers::pi * static_cast<double>(k) / n);
  return c;
}

// ---- ADC accuracy limit (paper §2.4, Fig. 6) ---------------------------------------------

TEST(PublishedAdcLimit, AboutTwoHundredthsOfADegreeAtDFivePercent) {
  // "the max error is ±0.02° when d is equal to 0.05": quoted to one digit, ±0.005°.
  const AdcLimit l = adc_accuracy_limit(0.05, Electronics{}, kWang2019FilmAxesDeg);
  EXPECT_NEAR(l.limit_deg, 0.02, 0.005);
  EXPECT_NEAR(l.vmax_mV, 21.73, 0.005);
}

TEST(PublishedAdcLimit, AboutOneThousandthOfADegreeAtDPointSeven) {
  // "the accuracy limit was about ±0.001° when d was ~0.7": one digit, ±0.0005°.
  const AdcLimit l = adc_accuracy_limit(0.7, Electronics{}, kWang2019FilmAxesDeg);
  EXPECT_NEAR(l.limit_deg, 0.001, 0.0005);
}

TEST(PublishedAdcLimit, FallsMonotonicallyWithD) {
  double previous = 1e9;
  for (int k = 1; k <= 14; ++k) {  // d = 0.05 … 0.70
    const AdcLimit l = adc_accuracy_limit(0.05 * k, Electronics{}, kWang2019FilmAxesDeg);
    EXPECT_LT(l.limit_deg, previous) << "d=" << l.d;
    previous = l.limit_deg;
  }
}

TEST(PublishedAdcLimit, SaturationAboveDPoint8813BreaksTheLimit) {
  // Above d = 0.8813 the largest voltage exceeds Vref and clamps: the error jumps.
  const AdcLimit below = adc_accuracy_limit(0.88, Electronics{}, kWang2019FilmAxesDeg);
  const AdcLimit above = adc_accuracy_limit(0.90, Electronics{}, kWang2019FilmAxesDeg);
  EXPECT_LT(below.vmax_mV, 600.0);
  EXPECT_GT(above.vmax_mV, 600.0);
  EXPECT_GT(above.limit_deg, 100 * below.limit_deg);
}

TEST(AdcLimit, ErrorIsZeroWithoutQuantization) {
  Electronics fine;
  fine.adc_bits = 31;  // LSB 0.3 nV: the limit shrinks by 2^15 against 16 bits
  const AdcLimit l16 = adc_accuracy_limit(0.5, Electronics{}, kWang2019FilmAxesDeg);
  const AdcLimit l31 = adc_accuracy_limit(0.5, fine, kWang2019FilmAxesDeg);
  EXPECT_LT(l31.limit_deg, l16.limit_deg * 1e-3);
}

// ---- CS method (paper §3.2, Figs. 8–12) --------------------------------------------------

TEST(PublishedCs, PortOffsetAloneGivesANearSineWhoseCsAverageIsNearZero) {
  // L_IS = 0.05 mm, α_IS = 0°, sensor centred.
  const CsStudy s = cs_study(ideal_rig(0.05, 0.0, 0.0, 0.0), CsTurn(360));
  for (int i = 0; i < 3; ++i) {
    const std::vector<double>& br = s.dv_br_V[i];
    const std::complex<double> c1 = first_harmonic(br);
    // Near-sine: the first harmonic carries all but a fraction ~L_IS·L_photo/a ≈ 1e-3 of it.
    std::vector<double> residual(br.size());
    for (std::size_t k = 0; k < br.size(); ++k)
      residual[k] = br[k] - std::real(c1 * std::polar(1.0, 2 * std::numbers::pi * k / 360.0));
    EXPECT_LT(max_abs(residual), 2e-3 * std::abs(c1)) << "pair " << i + 1;
    // ΔV_mr ≈ 0: bounded by the second-order ripple v_dec·|log10(1 − 4b²/a²)| (see
    // Cs.CentredSensorHasZeroConstantAndASecondOrderRipple), ~1e-3 of the ΔV_br amplitude.
    const double a = 20.0 * 20.0 + 14.0 * 14.0 + 0.05 * 0.05, b = 14.0 * 0.05;
    EXPECT_LE(max_abs(s.dv_mr_V[i]), 0.5 * std::abs(std::log10(1 - 4 * b * b / (a * a))))
        << "pair " << i + 1;
    EXPECT_LT(max_abs(s.dv_mr_V[i]), 2e-3 * std::abs(c1)) << "pair " << i + 1;
  }
}

TEST(PublishedCs, AmplitudeIsSetByLIsAndPhaseByAlphaIs) {
  const CsStudy a = cs_study(ideal_rig(0.05, 0.0, 0.0, 0.0), CsTurn(360));
  const CsStudy b = cs_study(ideal_rig(0.10, 0.0, 0.0, 0.0), CsTurn(360));
  const CsStudy c = cs_study(ideal_rig(0.05, 40.0, 0.0, 0.0), CsTurn(360));
  for (int i = 0; i < 3; ++i) {
    // Linear in L_IS to first order: the ratio is 2 up to O(L_IS/L_o)² ≈ 1e-5.
    EXPECT_NEAR(std::abs(first_harmonic(b.dv_br_V[i])) / std::abs(first_harmonic(a.dv_br_V[i])),
                2.0, 1e-4);
    // Turning the port by α_IS is turning the whole picture: a pure shift of the curve,
    // exact for a centred sensor.
    for (int k = 0; k < 360; ++k)
      EXPECT_NEAR(c.dv_br_V[i][k], a.dv_br_V[i][(k + 320) % 360], 1e-15);
  }
}

TEST(PublishedCs, SensorOffsetAloneGivesConstantsWithinHalfAMillivolt) {
  // L_S = 0.02 mm, α_S = 70°, port centred: every ΔV is constant and |ΔV| ≤ 0.5 mV; Eq. 6 is
  // then exact.
  const CsStudy s = cs_study(ideal_rig(0.0, 0.0, 0.02, 70.0), CsTurn(360));
  for (int i = 0; i < 3; ++i) {
    EXPECT_LT(s.summary[i].bsd_mV, 1e-12);
    EXPECT_LT(s.summary[i].asd_mV, 1e-12);
    EXPECT_LE(std::abs(s.summary[i].mean_br_mV), 0.5);
    EXPECT_GT(std::abs(s.summary[i].mean_br_mV), 0.01);  // not trivially zero
    EXPECT_NEAR(s.summary[i].mean_mr_mV, s.summary[i].eq6_mV, 1e-12);
  }
}

TEST(PublishedCs, BothOffsetsSuperpose) {
  // ΔV(both) − ΔV(port only) − ΔV(sensor only) is second order in the offsets: below 1e-3 of
  // the curve, and a quarter when both offsets halve.
  const auto residual = [](double scale) {
    const CsTurn turn(360);
    const CsStudy both = cs_study(ideal_rig(0.05 * scale, 0, 0.02 * scale, 70), turn);
    const CsStudy port = cs_study(ideal_rig(0.05 * scale, 0, 0, 0), turn);
    const CsStudy sensor = cs_study(ideal_rig(0, 0, 0.02 * scale, 70), turn);
    double r = 0, size = 0;
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 360; ++k) {
        r = std::max(r, std::abs(both.dv_br_V[i][k] - port.dv_br_V[i][k] - sensor.dv_br_V[i][k]));
        size = std::max(size, std::abs(both.dv_br_V[i][k]));
      }
    return std::pair{r, size};
  };
  const auto [r1, size1] = residual(1.0);
  const auto [r2, size2] = residual(0.5);
  EXPECT_LT(r1, 1e-3 * size1);
  EXPECT_NEAR(r1 / r2, 4.0, 0.1);
}

TEST(PublishedCs, FirstCsDeviationPeaksAtAlphaS240) {
  for (double L_IS : {0.0, 0.05}) {
    Rig base = ideal_rig(L_IS, 0.0, 0.02, 0.0);
    const SweepResult r = sweep(base, {GridAxis::parse("eccentricity.alpha_S=0:359:360")},
                                CsTurn(360));
    std::size_t best = 0;
    for (std::size_t p = 0; p < r.points(); ++p)
      if (r.summaries[p][0].mean_mr_mV > r.summaries[best][0].mean_mr_mV) best = p;
    EXPECT_EQ(r.axes[0].value(static_cast<int>(best)), 240.0) << "L_IS=" << L_IS;
  }
}

class SlowPublishedCsGrid : public ::testing::Test {
 protected:
  // L_IS and L_S each over [0.001, 1] mm, α_S = 240° (Figs. 11–12).
  static SweepResult grid() {
    return sweep(ideal_rig(0.0, 0.0, 0.0, 240.0),
                 {GridAxis::parse("eccentricity.L_IS=0.001:1:60"),
                  GridAxis::parse("eccentricity.L_S=0.001:1:60")},
                 CsTurn(360));
  }
};

TEST_F(SlowPublishedCsGrid, EquationSixMatchesTheExpectationToBetterThan023Percent) {
  const SweepResult r = grid();
  double worst = 0;
  for (std::size_t p = 0; p < r.points(); ++p)
    for (const CsPairSummary& s : r.summaries[p])
      worst = std::max(worst, std::abs((s.eq6_mV - s.mean_mr_mV) / s.mean_mr_mV));
  EXPECT_LT(worst, 0.0023);
}

TEST_F(SlowPublishedCsGrid, AsdBarelyDependsOnLsAndAsdOverBsdIsAFewPercent) {
  const SweepResult r = grid();
  // At L_IS = 1 mm (last outer index): ASD over L_S varies far less than over L_IS, where it
  // grows as L_IS² (the CS residue is second order in the port offset).
  double lo = 1e9, hi = 0;
  for (int j = 0; j < 60; ++j) {
    const CsPairSummary& s = r.summaries[59 * 60 + j][0];
    lo = std::min(lo, s.asd_mV);
    hi = std::max(hi, s.asd_mV);
    EXPECT_GT(100 * s.asd_mV / s.bsd_mV, 1.0);
    EXPECT_LT(100 * s.asd_mV / s.bsd_mV, 5.0);
  }
  EXPECT_LT((hi - lo) / hi, 0.01);
  const double asd_1 = r.summaries[59 * 60 + 30][0].asd_mV;
  const double asd_half = r.summaries[29 * 60 + 30][0].asd_mV;
  const double L1 = r.axes[0].value(59), Lh = r.axes[0].value(29);
  EXPECT_NEAR(asd_1 / asd_half, (L1 * L1) / (Lh * Lh), 0.01 * (L1 * L1) / (Lh * Lh));
}

TEST_F(SlowPublishedCsGrid, ExpectationBarelyDependsOnLIs) {
  // At L_S = 1 mm, the expectation depends on L_IS only through L_IS² beside L_o² + L_R²
  // (Eq. 6): a relative change ≤ L_IS²/(L_o² + L_photo²), plus Eq. 6's own 0.23%.
  const SweepResult r = grid();
  const double first = r.summaries[0 * 60 + 59][0].mean_mr_mV;
  const double bound = 1.0 / (20.0 * 20.0 + 14.0 * 14.0) + 0.0023;
  for (int i = 0; i < 60; ++i) {
    const double e = r.summaries[static_cast<std::size_t>(i) * 60 + 59][0].mean_mr_mV;
    EXPECT_LT(std::abs(e - first) / std::abs(first), bound);
  }
}

TEST(Cs, AverageIsExactlyConstantWhenThePortIsCentred) {
  // Constant up to rounding only: |Rot·P|² carries a few ulps of L² ≈ 200 mm², i.e. ~3e-16
  // relative to L_o² + L², which log10 turns into ~3e-16 V. Allow 1e-15 V (1e-12 mV).
  const CsStudy s = cs_study(ideal_rig(0.0, 0.0, 0.7, 123.0), CsTurn(360));
  for (int i = 0; i < 3; ++i)
    for (int k = 1; k < 360; ++k) EXPECT_NEAR(s.dv_mr_V[i][k], s.dv_mr_V[i][0], 1e-15);
}

TEST(Cs, CentredSensorHasZeroConstantAndASecondOrderRipple) {
  // Sensor centred (L_R1 = L_R2): Eq. 6's constant is 0. The exact CS average is
  // v_dec·log10[(a² − 4b²cos²ψ_h)/(a² − 4b²cos²ψ_j)], a = L_o² + L_photo² + L_IS²,
  // b = L_photo·L_IS: zero mean over a turn, ripple at most v_dec·|log10(1 − 4b²/a²)|.
  const double L_IS = 0.3;
  const CsStudy s = cs_study(ideal_rig(L_IS, 17.0, 0.0, 0.0), CsTurn(360));
  const double a = 20.0 * 20.0 + 14.0 * 14.0 + L_IS * L_IS, b = 14.0 * L_IS;
  const double bound = 0.5 * std::abs(std::log10(1 - 4 * b * b / (a * a)));
  for (int i = 0; i < 3; ++i) {
    // Zero up to rounding, 1e-15 V = 1e-12 mV (see AverageIsExactlyConstantWhenThePortIsCentred).
    EXPECT_NEAR(s.summary[i].eq6_mV, 0.0, 1e-12);
    EXPECT_NEAR(s.summary[i].mean_mr_mV, 0.0, 1e-12);
    EXPECT_LE(max_abs(s.dv_mr_V[i]), bound * (1 + 1e-9));
    EXPECT_GT(max_abs(s.dv_mr_V[i]), 0.3 * bound);  // the ripple is real, not zero
  }
}

TEST(Cs, RigGainScalesDeviationsAndEquationSix) {
  Rig ideal = ideal_rig(0.05, 0, 0.02, 70);
  Rig real = ideal;
  real.device.truth = CalibrationParams::wang2019_indoor();
  const CsTurn turn(360);
  const CsStudy a = cs_study(ideal, turn), b = cs_study(real, turn);
  for (int i = 0; i < 3; ++i) {
    const double kv = real.device.truth.kv[i];
    EXPECT_NEAR(b.summary[i].bsd_mV, kv * a.summary[i].bsd_mV, 1e-12);
    EXPECT_NEAR(b.summary[i].eq6_mV, kv * a.summary[i].eq6_mV, 1e-12);
  }
}

// ---- The simulation ----------------------------------------------------------------------

TEST(Simulate, ExtremeVoltagesFollowTheTableAngleAnticlockwise) {
  // End-to-end sign check: with a theory device and no eccentricity or noise, the sensor
  // reports θ = θ_R − ψ_P.
  Rig rig = ideal_rig(0, 0, 0, 0);
  rig.electronics.noise_sigma_V = 0;
  rig.source.polarizer_deg = 10.0;
  rig.schedule.angles_deg = {30.0, 100.0, 200.0};
  const Simulation sim = simulate(rig);
  for (const Stop& s : sim.stops) {
    const SensorAngles a = sensor_angles(rig.device.truth, rig.electronics, s.V_ideal);
    EXPECT_NEAR(axis_difference_deg(a.theta12.theta_deg, s.theta_R_deg - 10.0), 0.0, 1e-9);
  }
}

TEST(Simulate, NoiseAndAdcStatisticsMatchTheirModel) {
  // σ = 0.1 mV ≫ LSB = 18 µV: the samples' standard deviation is √(σ² + LSB²/12). Each stop's
  // n = 40 estimate has relative error 1/√(2(n−1)); averaged over 37·3 of them, 1.1%. The mean of
  // the samples has error σ/√40 about V_ecc. Allow 5 standard errors.
  const Rig rig;
  const Simulation sim = simulate(rig, true);
  const double lsb = rig.electronics.vref_V / 32768.0;
  const double sigma = std::sqrt(std::pow(rig.electronics.noise_sigma_V, 2) + lsb * lsb / 12);
  double sd_sum = 0, z2 = 0;
  int count = 0;
  for (const Stop& s : sim.stops)
    for (int i = 0; i < 3; ++i) {
      sd_sum += s.V_std[i];
      const double z = (s.V_mean[i] - s.V_ecc[i]) / (sigma / std::sqrt(40.0));
      z2 += z * z;
      ++count;
    }
  const double rel_err = 1.0 / std::sqrt(2.0 * 39.0 * count);
  EXPECT_NEAR(sd_sum / count / sigma, 1.0, 5 * rel_err);
  EXPECT_NEAR(z2 / count, 1.0, 5 * std::sqrt(2.0 / count));
  ASSERT_EQ(sim.samples.size(), 37u * 40u);
  for (const auto& v : sim.samples)
    for (double x : v) EXPECT_EQ(x, adc_quantize(x, rig.electronics));  // on the ADC grid
}

TEST(Simulate, IsBitIdenticalForAnyThreadCount) {
  const Rig rig;
  Simulation one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = simulate(rig, true);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = simulate(rig, true);
  }
  ASSERT_EQ(one.stops.size(), two.stops.size());
  for (std::size_t s = 0; s < one.stops.size(); ++s) {
    EXPECT_EQ(one.stops[s].V_mean, two.stops[s].V_mean);
    EXPECT_EQ(one.stops[s].V_std, two.stops[s].V_std);
  }
  EXPECT_EQ(one.samples, two.samples);
}

TEST(Simulate, SeedChangesTheNoiseOnly) {
  Rig a, b;
  b.seed = a.seed + 1;
  const Simulation sa = simulate(a), sb = simulate(b);
  EXPECT_EQ(sa.stops[3].V_ecc, sb.stops[3].V_ecc);
  EXPECT_NE(sa.stops[3].V_mean, sb.stops[3].V_mean);
}

TEST(Sweep, GridValuesIncludeBothEndsAndOrderIsRowMajor) {
  const GridAxis a = GridAxis::parse("eccentricity.L_S=0.001:1:5");
  EXPECT_EQ(a.value(0), 0.001);
  EXPECT_EQ(a.value(4), 1.0);
  EXPECT_DOUBLE_EQ(a.value(2), 0.5005);
  const SweepResult r = sweep(Rig{}, {a, GridAxis::parse("eccentricity.L_IS=0:0.2:3")}, CsTurn(36));
  ASSERT_EQ(r.points(), 15u);
  EXPECT_EQ(r.indices(4), (std::vector<int>{1, 1}));
  // Each point equals the CS study of the rig with those values set.
  Rig rig;
  rig.eccentricity.L_S = a.value(1);
  rig.eccentricity.L_IS = 0.1;
  const CsStudy s = cs_study(rig, CsTurn(36));
  EXPECT_EQ(r.summaries[4][2].asd_mV, s.summary[2].asd_mV);
}

TEST(Sweep, GridValuesAreRoundedExactlyAsTheirFifteenDigitText) {
  // The former definition of a grid value: format with 15 significant digits and parse back.
  const auto by_text = [](double v) { return std::strtod(fmt::format("{:.15g}", v).c_str(), nullptr); };
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> decade(-12.0, 18.0);
  long mismatches = 0;
  const auto check = [&](double v) {
    const double fast = round_to_15_digits(v), slow = by_text(v);
    if (fast != slow || std::signbit(fast) != std::signbit(slow))
      if (mismatches++ < 5) ADD_FAILURE() << fmt::format("{}: {} but the text gives {}", v, fast, slow);
  };
  for (double v : {0.0, -0.0, 0.5, 1.5, 2.5, 100000000000000.5, 100000000000001.5, 999999999999999.5,
                   0.15000000000000002, 1e-8, 9.99999999999999e-9, 1e15, 1e22, 5e-324})
    check(v);
  for (int k = 0; k < 300000; ++k) {
    check((rng() % 2 ? 1 : -1) * std::pow(10.0, decade(rng)));
    const double a = static_cast<double>(rng() % 1000) * 0.001;
    const double b = a + static_cast<double>(rng() % 100000) * 0.01;
    const int count = 2 + static_cast<int>(rng() % 1000);
    const int i = static_cast<int>(rng() % static_cast<std::uint64_t>(count));
    check((a * (count - 1 - i) + b * i) / (count - 1));
    check((1e14 + static_cast<double>(rng() % 800000000000000ULL)) + 0.5);  // exact halves
  }
  EXPECT_EQ(mismatches, 0);
}

TEST(Sweep, AHundredMillionValuesAreCheckedWithoutText) {
  // Every value goes through the key's check: the first bad one is the last, named exactly.
  try {
    GridAxis::parse("eccentricity.L_S=1:-1e-8:1e8");
    FAIL() << "expected RigError";
  } catch (const RigError& e) {
    EXPECT_NE(std::string(e.what()).find("key 'eccentricity.L_S': expected a length in [0, 100] mm, got -1e-08"),
              std::string::npos) << e.what();
  }
  const GridAxis a{find_rig_key("eccentricity.L_S"), 0.0, 1.0, 100000000};
  EXPECT_EQ(a.value(50000000), 0.500000005);
  EXPECT_EQ(a.value(99999999), 1.0);
}

TEST(Sweep, AnAxisOfListedValuesEqualsTheParsedAxisWithTheSameValues) {
  const GridAxis parsed = GridAxis::parse("eccentricity.L_S=0.001:1:5");
  std::vector<double> v;
  for (int i = 0; i < parsed.count; ++i) v.push_back(parsed.value(i));
  const GridAxis listed = GridAxis::list("eccentricity.L_S", v);
  EXPECT_EQ(listed.count, 5);
  EXPECT_EQ(listed.text(), "eccentricity.L_S=[0.001 … 1] (5 values)");
  const GridAxis other = GridAxis::parse("eccentricity.L_IS=0:0.2:3");
  const SweepResult a = sweep(Rig{}, {parsed, other}, CsTurn(36));
  const SweepResult b = sweep(Rig{}, {listed, other}, CsTurn(36));
  for (std::size_t p = 0; p < a.points(); ++p)
    for (std::size_t i = 0; i < 3; ++i) EXPECT_EQ(a.summaries[p][i].asd_mV, b.summaries[p][i].asd_mV);
  // Values in any order, checked one by one by the key's own check; NaN is not a value.
  EXPECT_EQ(GridAxis::list("eccentricity.alpha_S", {350, 10, 10}).value(1), 10.0);
  const auto message = [](std::string_view key, std::vector<double> values) {
    try {
      GridAxis::list(key, std::move(values));
    } catch (const RigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message("eccentricity.L_S", {0.1, 200, -1}),
            "grid eccentricity.L_S: value 1: expected a length in [0, 100] mm, got 200");
  EXPECT_NE(message("eccentricity.L_S", {0.1, std::nan("")}).find("value 1: expected a length in [0, 100] mm, got nan"),
            std::string::npos);
  EXPECT_NE(message("eccentricity.nope", {1}).find("unknown key 'eccentricity.nope'"), std::string::npos);
  EXPECT_NE(message("source.model", {1}).find("is not a single real number"), std::string::npos);
  EXPECT_NE(message("eccentricity.L_S", {}).find("expected 1 to 1e8 values, got 0"), std::string::npos);
}

// The sweep steps one rig through the grid, setting only the keys whose index changed: every
// point equals the study of a rig given all of that point's values in axis order (a key swept
// twice: the later axis wins), field for field.
TEST(Sweep, EachPointIsTheStudyOfTheRigWithThatPointsValues) {
  const std::vector<GridAxis> axes{GridAxis::parse("eccentricity.L_IS=0:1:3"),
                                   GridAxis::parse("eccentricity.alpha_S=0:300:4"),
                                   GridAxis::parse("eccentricity.L_S=0.01:0.5:7"),
                                   GridAxis::parse("eccentricity.L_IS=0.5:2:5")};
  const CsTurn turn(360);
  const SweepResult result = sweep(Rig{}, axes, turn);
  ASSERT_EQ(result.points(), 3u * 4 * 7 * 5);
  std::vector<double> scratch;
  for (std::size_t p = 0; p < result.points(); ++p) {
    Rig r;
    const std::vector<int> idx = grid_indices(axes, p);
    for (std::size_t a = 0; a < axes.size(); ++a) axes[a].key->real(r) = axes[a].value(idx[a]);
    const CsSummary expected = cs_summary(r, turn, scratch);
    EXPECT_EQ(std::memcmp(&expected, &result.summaries[p], sizeof(CsSummary)), 0) << "point " << p;
  }
}

TEST(Sweep, StreamsBlocksInGridOrderWithBoundedMemory) {
  const std::vector<GridAxis> axes{GridAxis::parse("eccentricity.L_S=0.001:1:300"),
                                   GridAxis::parse("eccentricity.alpha_S=0:359:250")};
  const CsTurn turn(8);
  const SweepResult whole = sweep(Rig{}, axes, turn);
  std::size_t next = 0, largest = 0, calls = 0, progress_calls = 0;
  std::vector<double> scratch;
  sweep(Rig{}, axes, turn,
        [&](std::size_t first, std::span<const CsSummary> block) {
          // A slow write (the sink runs on a writer thread beside the next blocks' pieces): a
          // buffer filled again before its write ended would show in the values checked below.
          std::this_thread::sleep_for(std::chrono::milliseconds(2));
          EXPECT_EQ(first, next);
          for (std::size_t k = 0; k < block.size(); ++k)
            EXPECT_EQ(block[k][0].asd_mV, cs_summary([&] {
                        Rig r;
                        const std::vector<int> idx = grid_indices(axes, first + k);
                        r.eccentricity.L_S = axes[0].value(idx[0]);
                        r.eccentricity.alpha_S = axes[1].value(idx[1]);
                        return r;
                      }(), turn, scratch).front().asd_mV) << first + k;
          next += block.size();
          largest = std::max(largest, block.size());
          ++calls;
        },
        [&](std::size_t done, std::size_t total) {
          EXPECT_EQ(done, next);
          EXPECT_EQ(total, 75000u);
          ++progress_calls;
        });
  EXPECT_EQ(next, 75000u);
  EXPECT_LE(largest, 32768u) << "a block holds more than 32768 points";
  EXPECT_GT(calls, 1u);
  EXPECT_EQ(progress_calls, calls);
  EXPECT_EQ(whole.points(), 75000u);
}

TEST(Sweep, ResumingAtABlockComputesOnlyTheRestAndTheSameValues) {
  const std::vector<GridAxis> axes{GridAxis::parse("eccentricity.L_S=0.001:1:300"),
                                   GridAxis::parse("eccentricity.alpha_S=0:359:50")};
  const CsTurn turn(8);
  const SweepResult whole = sweep(Rig{}, axes, turn);
  const std::size_t block = sweep_block_size(whole.points());
  ASSERT_EQ(block, 4096u);  // 15,000 points: blocks of 4096, the last of 2712
  std::size_t next = 2 * block;
  sweep(Rig{}, axes, turn, [&](std::size_t first, std::span<const CsSummary> b) {
    ASSERT_EQ(first, next);
    for (std::size_t k = 0; k < b.size(); ++k)
      for (int i = 0; i < 3; ++i) {
        EXPECT_EQ(b[k][i].asd_mV, whole.summaries[first + k][i].asd_mV);
        EXPECT_EQ(b[k][i].bsd_mV, whole.summaries[first + k][i].bsd_mV);
      }
    next += b.size();
  }, SweepProgress{}, SweepOptions{.first_point = 2 * block});
  EXPECT_EQ(next, whole.points());
  // Nothing is left when the grid is done; a point inside a block is refused.
  sweep(Rig{}, axes, turn, [&](std::size_t, std::span<const CsSummary>) { FAIL(); }, SweepProgress{},
        SweepOptions{.first_point = whole.points()});
  EXPECT_THROW(sweep(Rig{}, axes, turn, [](std::size_t, std::span<const CsSummary>) {}, SweepProgress{},
                     SweepOptions{.first_point = 100}),
               std::invalid_argument);
}

TEST(Sweep, ASinkFailureIsThrownAndNoLaterBlockIsHandedOn) {
  // The sink runs on a writer thread while the next block's pieces are computed (study/sweep.cpp):
  // its error must still reach the caller, and the blocks after the failed one must not be written.
  const std::vector<GridAxis> axes{GridAxis::parse("eccentricity.L_S=0.001:1:300"),
                                   GridAxis::parse("eccentricity.alpha_S=0:359:50")};  // 4 blocks
  std::size_t calls = 0;
  try {
    sweep(Rig{}, axes, CsTurn(8), [&](std::size_t first, std::span<const CsSummary>) {
      ++calls;
      if (first > 0) throw std::runtime_error("sweep.h5: disk full");
    });
    FAIL() << "expected the sink's error";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "sweep.h5: disk full");
  }
  EXPECT_EQ(calls, 2u);
}

TEST(Sweep, AFailedWriteIsSaidBeforeABadPointInALaterBlock) {
  // Thirteen varying axes (no corners checked up front), schedule.start_deg the first: its bad
  // value begins block 1 (point 4096). Block 0's write fails while block 1 is computed: the
  // write's error comes first in grid order, in one process and on ranks.
  std::vector<GridAxis> axes{GridAxis::parse("schedule.start_deg=0:400:2")};
  for (int k = 0; k < 12; ++k) axes.push_back(GridAxis::parse("eccentricity.alpha_S=0:1:2"));
  ASSERT_EQ(sweep_block_size(grid_points(axes)), 4096u);
  const auto failing_sink = [](std::size_t, std::span<const CsSummary>) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));  // still writing when block 1 fails
    throw std::runtime_error("sweep.h5: disk full");
  };
  try {
    sweep(Rig{}, axes, CsTurn(4), failing_sink);
    FAIL() << "expected the write's error";
  } catch (const RigError& e) {
    FAIL() << "the bad point was said before the earlier block's failed write: " << e.what();
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "sweep.h5: disk full");
  }
  for (int size : {2, 3}) {
    const auto errors = test::with_thread_ranks(size, [&](const Ranks& ranks) {
      sweep(Rig{}, axes, CsTurn(4), failing_sink, SweepProgress{}, SweepOptions{.ranks = &ranks});
    });
    EXPECT_EQ(errors, std::vector<std::string>(static_cast<std::size_t>(size), "sweep.h5: disk full")) << size;
  }
}

// The datasets' stops side by side (side_by_side.h): every piece's work done once, the results
// collected in order; never more than threads + 1 pieces in flight; the first failing piece in
// order is the error thrown, whichever thread met it.
TEST(SideBySide, WorksSideBySideCollectsInOrderAndBoundsThePiecesInFlight) {
  for (int threads : {1, 2, 4}) {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
    std::vector<std::atomic<int>> worked(40);
    std::vector<std::size_t> collected;
    std::atomic<int> in_flight{0}, most{0};
    side_by_side_in_order(
        worked.size(),
        [&](std::size_t i) {
          const int now = ++in_flight;
          for (int m = most.load(); now > m && !most.compare_exchange_weak(m, now);) {}
          // Later pieces finish first: collecting must still go in order.
          std::this_thread::sleep_for(std::chrono::microseconds(200 * (i % 5 == 0 ? 10 : 1)));
          ++worked[i];
          return i;
        },
        [&](std::size_t i) {
          collected.push_back(i);
          --in_flight;
        });
    std::vector<std::size_t> in_order(worked.size());
    for (std::size_t i = 0; i < in_order.size(); ++i) in_order[i] = i;
    EXPECT_EQ(collected, in_order) << threads;
    for (std::size_t i = 0; i < worked.size(); ++i) EXPECT_EQ(worked[i].load(), 1) << threads << " " << i;
    EXPECT_LE(most.load(), usable_threads() + 1) << threads;
    EXPECT_EQ(usable_threads(), std::min(threads, tbb::this_task_arena::max_concurrency())) << threads;
  }
  // Four threads whatever the machine (five pieces in flight), so that stop 4 fails while stop 3
  // is still at work: stop 3's error must still be the one thrown.
  const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 4);
  tbb::task_arena four(4);
  four.execute([&] {
    ASSERT_EQ(usable_threads(), 4);
    for (int run = 0; run < 5; ++run) {
      std::atomic<bool> later_failed_first{false};
      try {
        side_by_side_in_order(
            12,
            [&](std::size_t i) {
              if (i == 4) {
                later_failed_first = true;
                throw std::runtime_error("stop_0004.exr: disk full");
              }
              if (i == 3) {
                for (int k = 0; k < 200 && !later_failed_first; ++k)
                  std::this_thread::sleep_for(std::chrono::milliseconds(1));
                throw std::runtime_error("stop_0003.exr: disk full");
              }
              return i;
            },
            [](std::size_t) {});
        FAIL() << "expected stop 3's error";
      } catch (const std::runtime_error& e) {
        EXPECT_STREQ(e.what(), "stop_0003.exr: disk full") << run;
      }
      EXPECT_TRUE(later_failed_first) << run;  // stop 4 did fail first
    }
  });
  EXPECT_THROW(side_by_side_in_order(
                   5, [](std::size_t i) { return i; },
                   [](std::size_t i) {
                     if (i == 2) throw std::runtime_error("stops.csv: cannot collect");
                   }),
               std::runtime_error);
}

TEST(Sweep, AnInteriorPointThatBreaksARuleIsNamedBeforeItIsComputed) {
  // Thirteen varying axes: too many corners to check up front, so the rule is found while
  // sweeping, at the first bad point in grid order.
  std::vector<GridAxis> axes;
  for (int k = 0; k < 12; ++k) axes.push_back(GridAxis::parse("eccentricity.alpha_S=0:1:2"));
  axes.push_back(GridAxis::parse("schedule.start_deg=0:400:2"));
  bool sunk = false;
  try {
    sweep(Rig{}, axes, CsTurn(4), [&](std::size_t, std::span<const CsSummary>) { sunk = true; });
    FAIL() << "expected RigError";
  } catch (const RigError& e) {
    EXPECT_NE(std::string(e.what()).find("eccentricity.alpha_S=0, schedule.start_deg=400): key "
                                         "'schedule.stop_deg'"),
              std::string::npos) << e.what();
  }
  EXPECT_FALSE(sunk) << "a block with a bad point was handed on";
}

// Sweeps shared between ranks (SweepOptions::ranks), with ranks on threads (tests/thread_ranks.h):
// what the MPI build does across processes, tested in every build.
namespace {
bool same_bits(const CsSummary& a, const CsSummary& b) { return std::memcmp(&a, &b, sizeof(CsSummary)) == 0; }
}  // namespace

TEST(SweepOnRanks, Rank0ReceivesEveryBlockInGridOrderBitIdenticalToOneProcess) {
  const std::vector<GridAxis> axes{GridAxis::parse("eccentricity.L_S=0.001:1:300"),
                                   GridAxis::parse("eccentricity.alpha_S=0:359:50")};
  const CsTurn turn(8);
  const SweepResult whole = sweep(Rig{}, axes, turn);
  const std::size_t block = sweep_block_size(whole.points());
  ASSERT_EQ(block, 4096u);  // 15,000 points: 3 blocks of 4096 (shards of 1365 and 1366 on 3 ranks), one of 2712
  for (int size : {1, 2, 3, 5}) {
    for (std::size_t first_point : {std::size_t{0}, block}) {
      std::vector<CsSummary> got;
      std::vector<std::size_t> firsts, progress_done;
      const auto errors = test::with_thread_ranks(size, [&](const Ranks& ranks) {
        sweep(Rig{}, axes, turn,
              [&](std::size_t first, std::span<const CsSummary> b) {
                EXPECT_EQ(ranks.rank(), 0) << "the sink is called on rank 0 only";
                firsts.push_back(first);
                got.insert(got.end(), b.begin(), b.end());
              },
              [&](std::size_t done, std::size_t) {
                EXPECT_EQ(ranks.rank(), 0) << "progress is reported on rank 0 only";
                progress_done.push_back(done);
              },
              SweepOptions{.first_point = first_point, .ranks = &ranks});
      });
      for (const std::string& e : errors) EXPECT_EQ(e, "") << size << " ranks";
      ASSERT_EQ(got.size(), whole.points() - first_point) << size << " ranks";
      for (std::size_t p = 0; p < got.size(); ++p)
        ASSERT_TRUE(same_bits(got[p], whole.summaries[first_point + p])) << size << " ranks, point " << p;
      std::vector<std::size_t> expected_firsts;
      for (std::size_t b = first_point; b < whole.points(); b += block) expected_firsts.push_back(b);
      EXPECT_EQ(firsts, expected_firsts) << "one sink call per block, in grid order";
      ASSERT_EQ(progress_done.size(), expected_firsts.size());
      EXPECT_EQ(progress_done.back(), whole.points());
    }
  }
}

TEST(SweepOnRanks, MoreRanksThanPointsLeaveSomeRanksIdleAndTheResultTheSame) {
  const std::vector<GridAxis> axes{GridAxis::parse("eccentricity.L_S=0.001:1:5")};
  const SweepResult whole = sweep(Rig{}, axes, CsTurn(8));
  std::vector<CsSummary> got;
  const auto errors = test::with_thread_ranks(7, [&](const Ranks& ranks) {
    sweep(Rig{}, axes, CsTurn(8), [&](std::size_t, std::span<const CsSummary> b) {
      got.insert(got.end(), b.begin(), b.end());
    }, SweepProgress{}, SweepOptions{.ranks = &ranks});
  });
  for (const std::string& e : errors) EXPECT_EQ(e, "");
  ASSERT_EQ(got.size(), 5u);
  for (std::size_t p = 0; p < 5; ++p) EXPECT_TRUE(same_bits(got[p], whole.summaries[p])) << p;
}

TEST(SweepOnRanks, ABadPointOnRank1sShardStopsEveryRankWithOneProcesssMessage) {
  // Thirteen varying axes (no corners checked up front): the first bad point is 2048 (the
  // second axis at its second value), in block 0's second half, which rank 1 of 2 computes.
  std::vector<GridAxis> axes{GridAxis::parse("eccentricity.alpha_S=0:1:2"), GridAxis::parse("schedule.start_deg=0:400:2")};
  for (int k = 0; k < 11; ++k) axes.push_back(GridAxis::parse("eccentricity.alpha_S=0:1:2"));
  ASSERT_EQ(sweep_block_size(grid_points(axes)), 4096u);
  std::string alone;
  try {
    sweep(Rig{}, axes, CsTurn(4), [](std::size_t, std::span<const CsSummary>) {});
  } catch (const RigError& e) {
    alone = e.what();
  }
  ASSERT_NE(alone.find("eccentricity.alpha_S=0, schedule.start_deg=400, eccentricity.alpha_S=0"), std::string::npos) << alone;
  bool sunk = false;
  const auto errors = test::with_thread_ranks(2, [&](const Ranks& ranks) {
    try {
      sweep(Rig{}, axes, CsTurn(4), [&](std::size_t, std::span<const CsSummary>) { sunk = true; },
            SweepProgress{}, SweepOptions{.ranks = &ranks});
    } catch (const RigError&) {
      throw;  // the kind of error one process throws (exit 2 in the CLI)
    } catch (const std::exception& e) {
      throw std::runtime_error(std::string("not a RigError: ") + e.what());
    }
  });
  EXPECT_EQ(errors, (std::vector<std::string>{alone, alone}));
  EXPECT_FALSE(sunk) << "rank 0 handed on a block of the round that failed";
}

TEST(SweepOnRanks, ASinkFailureOnRank0StopsEveryRankAtTheNextCollective) {
  // Rank 0 writes a block on its writer thread while the next is computed: a failed write is found
  // when the next block is handed on and said at the collective after it; the last block's at
  // the end. Either way every rank stops with the sink's message and no later block is written.
  const std::vector<GridAxis> axes{GridAxis::parse("eccentricity.L_S=0.001:1:300"),
                                   GridAxis::parse("eccentricity.alpha_S=0:359:50")};  // 4 blocks
  const std::size_t block = sweep_block_size(grid_points(axes));
  for (int size : {2, 3})
    for (std::size_t failing : {std::size_t{1}, std::size_t{3}}) {
      std::vector<std::size_t> written;
      const auto errors = test::with_thread_ranks(size, [&](const Ranks& ranks) {
        sweep(Rig{}, axes, CsTurn(8), [&](std::size_t first, std::span<const CsSummary>) {
          written.push_back(first / block);
          if (first == failing * block) throw std::runtime_error("disk full");
        }, SweepProgress{}, SweepOptions{.ranks = &ranks});
      });
      EXPECT_EQ(errors, std::vector<std::string>(static_cast<std::size_t>(size), "disk full")) << size;
      std::vector<std::size_t> expected(failing + 1);
      for (std::size_t b = 0; b <= failing; ++b) expected[b] = b;
      EXPECT_EQ(written, expected) << size << " ranks, block " << failing << " failing";
    }
}

TEST(Sweep, IsBitIdenticalForAnyThreadCount) {
  const std::vector<GridAxis> axes{GridAxis::parse("eccentricity.L_S=0.001:1:40"),
                                   GridAxis::parse("eccentricity.alpha_IS=0:350:36")};
  SweepResult one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = sweep(Rig{}, axes, CsTurn(360));
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = sweep(Rig{}, axes, CsTurn(360));
  }
  for (std::size_t p = 0; p < one.points(); ++p)
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(one.summaries[p][i].asd_mV, two.summaries[p][i].asd_mV);
      EXPECT_EQ(one.summaries[p][i].mean_mr_mV, two.summaries[p][i].mean_mr_mV);
    }
}

// The AVX2 and AVX-512 code paths of the CS study (vector_log.h) do the IEEE operations of the
// baseline x86-64 ones in the same order: every summary and curve has the same bits, so a sweep
// gives the same file on any x86-64 machine (MPI ranks may run on different CPUs).
TEST(Cs, EveryCodePathGivesTheSameBits) {
  if (!avx2_paths()) GTEST_SKIP() << "this CPU has no AVX2: only the baseline paths exist";
  const std::vector<GridAxis> axes{GridAxis::parse("eccentricity.L_IS=0:2:9"),
                                   GridAxis::parse("eccentricity.L_S=0:1.5:7"),
                                   GridAxis::parse("eccentricity.alpha_S=0:359:37")};
  const Rig rig;
  set_baseline_paths_only(true);
  const SweepResult baseline = sweep(rig, axes, CsTurn(360));
  const CsStudy baseline_study = cs_study(rig, CsTurn(720));
  std::vector<SimdPaths> wider{SimdPaths::Avx2};
  set_widest_paths(SimdPaths::Avx512);
  if (avx512_paths()) wider.push_back(SimdPaths::Avx512);
  for (const SimdPaths paths : wider) {
    SCOPED_TRACE(paths == SimdPaths::Avx512 ? "AVX-512" : "AVX2");
    set_widest_paths(paths);
    const SweepResult best = sweep(rig, axes, CsTurn(360));
    const CsStudy best_study = cs_study(rig, CsTurn(720));
    ASSERT_EQ(best.points(), baseline.points());
    std::size_t differing = 0;
    for (std::size_t p = 0; p < best.points(); ++p)
      differing += std::memcmp(&best.summaries[p], &baseline.summaries[p], sizeof(CsSummary)) != 0;
    EXPECT_EQ(differing, 0u) << "of " << best.points() << " grid points";
    for (int i = 0; i < 3; ++i) {
      EXPECT_EQ(best_study.dv_br_V[i], baseline_study.dv_br_V[i]);
      EXPECT_EQ(best_study.dv_mr_V[i], baseline_study.dv_mr_V[i]);
    }
  }
  set_widest_paths(SimdPaths::Avx512);
}

// The study's six moments, summed side by side in its own loop (src/study/cs.cpp), are
// mean_and_population_sd's of each curve bit for bit (the same interleaved order, statistics.h),
// for turns whose length is and is not a multiple of the eight lanes.
TEST(Cs, TheSummaryIsMeanAndPopulationSdOfItsCurves) {
  Rig rig;
  rig.eccentricity = {0.3, 20, 0.7, 110};
  for (const int steps : {360, 362, 6}) {
    SCOPED_TRACE(steps);
    const CsStudy study = cs_study(rig, CsTurn(steps));
    std::vector<double> scratch;
    const CsSummary summary = cs_summary(rig, CsTurn(steps), scratch);
    for (int i = 0; i < 3; ++i) {
      const MeanAndSpread br = mean_and_population_sd(study.dv_br_V[i]), mr = mean_and_population_sd(study.dv_mr_V[i]);
      EXPECT_EQ(summary[i].bsd_mV, br.sd * 1e3);
      EXPECT_EQ(summary[i].mean_br_mV, br.mean * 1e3);
      EXPECT_EQ(summary[i].asd_mV, mr.sd * 1e3);
      EXPECT_EQ(summary[i].mean_mr_mV, mr.mean * 1e3);
    }
  }
}

// cos⁴'s closed form of Eq. 5's logarithm, ln(E_j/E_h) = 2·ln(D_h/D_j) (docs/physics.md),
// against the irradiance-based computation every other source uses (Source's own
// log_ratio_over_turn on the same rig: falloffs, their ratio, log_array). Both start from the same
// D_m = L_o² + L_m². The irradiances' ratio carries at most 7 roundings of relative size u = 2⁻⁵³
// (two quotients and two squares per falloff pair, then the ratio): ≤ 7u absolute in its log;
// the closed form's quotient one, doubled: ≤ 2u. Each log_array adds ≤ 2 ulp of its result
// (vector_log.h), the closed form's doubled with it. So |difference| ≤ 9u + 4·ulp(|value|): a
// few ulp of the log values, and a few u where they are near 0 (ratios near 1). Random
// eccentricities, port distances and table-turn sizes, on every code path.
TEST(Cs, Cos4LogRatiosMatchTheIrradiancesWithinRounding) {
  std::mt19937_64 rng(20261123);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto ulp = [](double x) {
    x = std::abs(x);
    return std::nextafter(x, std::numeric_limits<double>::infinity()) - x;
  };
  const double u = std::ldexp(1.0, -53);
  double worst = 0;  // the largest |difference| in units of the bound
  for (const bool baseline_only : {false, true}) {
    set_baseline_paths_only(baseline_only);
    for (int trial = 0; trial < 400; ++trial) {
      Rig rig;
      rig.eccentricity = {5.0 * std::pow(unit(rng), 3), 360.0 * unit(rng), 5.0 * std::pow(unit(rng), 3),
                          360.0 * unit(rng)};
      rig.source.cos4.L_o = 5.0 + 100.0 * unit(rng);
      const CsTurn turn(2 * (1 + trial % 200));
      const std::size_t values = static_cast<std::size_t>(3 * turn.steps());
      std::vector<double> closed(values), from_irradiance(values);
      rig.light->log_ratio_over_turn(rig.source_view(), turn, closed);
      rig.light->Source::log_ratio_over_turn(rig.source_view(), turn, from_irradiance);
      for (std::size_t v = 0; v < values; ++v) {
        const double bound = 9 * u + 4 * ulp(std::max(std::abs(closed[v]), std::abs(from_irradiance[v])));
        const double diff = std::abs(closed[v] - from_irradiance[v]);
        ASSERT_LE(diff, bound) << "trial " << trial << " value " << v << ": " << closed[v] << " vs "
                               << from_irradiance[v];
        worst = std::max(worst, diff / bound);
      }
    }
  }
  set_baseline_paths_only(false);
  RecordProperty("worst_fraction_of_bound", std::to_string(worst));
}

// The closed form's AVX-512, AVX2 and baseline paths give the same bits, value by value.
TEST(Cs, Cos4LogRatiosGiveTheSameBitsOnEveryPath) {
  if (!avx2_paths()) GTEST_SKIP() << "this CPU has no AVX2: only the baseline paths exist";
  const bool avx512 = avx512_paths();
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 100; ++trial) {
    Rig rig;
    rig.eccentricity = {3.0 * unit(rng), 360.0 * unit(rng), 3.0 * unit(rng), 360.0 * unit(rng)};
    const CsTurn turn(2 * (1 + trial * 7));
    std::vector<double> baseline(static_cast<std::size_t>(3 * turn.steps()));
    set_widest_paths(SimdPaths::Baseline);
    rig.light->log_ratio_over_turn(rig.source_view(), turn, baseline);
    for (const SimdPaths paths : {SimdPaths::Avx2, SimdPaths::Avx512}) {
      if (paths == SimdPaths::Avx512 && !avx512) continue;
      std::vector<double> wide(baseline.size());
      set_widest_paths(paths);
      rig.light->log_ratio_over_turn(rig.source_view(), turn, wide);
      ASSERT_EQ(std::memcmp(wide.data(), baseline.data(), wide.size() * sizeof(double)), 0)
          << "trial " << trial << (paths == SimdPaths::Avx512 ? " AVX-512" : " AVX2");
    }
  }
  set_widest_paths(SimdPaths::Avx512);
}

// ---- Progress reports ---------------------------------------------------------------------

TEST(Progress, FormatsStageFractionAndEta) {
  EXPECT_EQ(format_duration(0), "0:00");
  EXPECT_EQ(format_duration(59.4), "0:59");
  EXPECT_EQ(format_duration(59.6), "1:00");
  EXPECT_EQ(format_duration(754), "12:34");
  EXPECT_EQ(format_duration(3723), "1:02:03");
  EXPECT_EQ(format_duration(-1), "0:00");
  EXPECT_EQ(format_progress({"study cs: poses", 0.421, 5.0, 13.2}), "study cs: poses   42 %  ETA 0:13");
  EXPECT_EQ(format_progress({"trace", 0.999, 5.0, 0.1}), "trace   99 %  ETA 0:00");  // never "100 %" early
  EXPECT_EQ(format_progress({"trace", 0.0, 0.1, -1}), "trace    0 %  ETA ?");
  EXPECT_EQ(format_progress({"trace", 1.0, 75.0, 0}), "trace  100 %  1:15");  // done: the time taken
}

TEST(Progress, ReportsFromManyThreadsEndAtTheWholeStage) {
  std::vector<ProgressReport> seen;
  const Progress p([&](const ProgressReport& r) { seen.push_back(r); }, 0.0);  // every advance
  p.begin("stage", 1000);
  tbb::parallel_for(0, 1000, [&](int) { p.advance(); });
  p.finish();
  ASSERT_FALSE(seen.empty());
  for (std::size_t k = 1; k < seen.size(); ++k) EXPECT_LE(seen[k - 1].fraction, seen[k].fraction);
  EXPECT_EQ(seen.back().stage, "stage");
  EXPECT_EQ(seen.back().fraction, 1.0);
  for (const ProgressReport& r : seen) {
    EXPECT_GE(r.fraction, 0.0);
    EXPECT_LE(r.fraction, 1.0);
  }
}

TEST(Progress, AQuickStageAndTheDefaultHandleAreSilent) {
  int reports = 0;
  const Progress p([&](const ProgressReport&) { ++reports; }, 3600.0);
  p.begin("quick", 10);
  p.advance(10);
  p.finish();
  EXPECT_EQ(reports, 0);
  const Progress none;
  EXPECT_FALSE(static_cast<bool>(none));
  none.begin("x", 1);  // no sink: nothing to call
  none.advance();
  none.finish();
}

}  // namespace
}  // namespace polrig

namespace polrig {
namespace {

bool all_finite(std::span<const double> v) {
  return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
}

// What `simulate` and `study cs` would write for this rig is finite; returns the first
// quantity that is not, or "".
std::string first_non_finite(const Rig& rig) {
  const Simulation sim = simulate(rig);
  for (const Stop& s : sim.stops) {
    if (!all_finite(s.light.E_Wm2)) return "E";
    for (const auto* v : {&s.V_ideal, &s.V_ecc, &s.V_mean, &s.V_std})
      if (!all_finite(*v)) return "V";
  }
  const CsStudy cs = cs_study(rig, CsTurn(36));
  for (int i = 0; i < 3; ++i) {
    if (!all_finite(cs.dv_br_V[i]) || !all_finite(cs.dv_mr_V[i])) return "CS deviations";
    const CsPairSummary& p = cs.summary[i];
    for (double x : {p.bsd_mV, p.asd_mV, p.mean_br_mV, p.mean_mr_mV})
      if (!std::isfinite(x)) return "CS summary";
    // Eq. 6 is NaN ("not defined") for a source without its closed form (formats.md §6.2).
    if (rig.light->has(Source::kClosedFormEq6) && !std::isfinite(p.eq6_mV)) return "CS summary";
  }
  return "";
}

Rig short_schedule() {
  Rig rig;
  rig.schedule.start_deg = 0;
  rig.schedule.step_deg = 30;
  rig.schedule.stop_deg = 360;
  rig.schedule.samples_per_stop = 4;
  return rig;
}

// Every real rig key at either end of its range (an open end nudged one ulp inside): the
// simulation and the CS study stay finite, so no value a rig may hold makes them write NaN or
// infinity (issue 8: L_S = 1e300, L_o = 1e-300, kv = 1e300 … did).
TEST(RigRanges, EveryKeyAtEitherEndOfItsRangeGivesFiniteResults) {
  const double inf = std::numeric_limits<double>::infinity();
  int checked = 0;
  for (const RigKey& k : rig_keys()) {
    if (k.kind != RigKey::Kind::Real && k.kind != RigKey::Kind::RealArray) continue;
    ASSERT_TRUE(k.range.has_value()) << k.path << " has no range";
    // The camera's keys (device.kind dofp-camera): simulate and the CS study here are the
    // six-photodiode sensor's, which does not read them.
    if (!k.read_by_instrument("six-photodiode")) continue;
    for (bool upper : {false, true}) {
      double v = upper ? k.range->hi : k.range->lo;
      if (upper ? k.range->hi_open : k.range->lo_open) v = std::nextafter(v, upper ? -inf : inf);
      ASSERT_TRUE(std::isfinite(v)) << k.path;
      Rig rig = short_schedule();
      if (!k.read_by_source(rig.source.model)) {  // a key of another model: a rig of that model
        rig.source.model = std::string(k.sources);
        rig.light = make_source(rig.source);
      }
      if (!k.read_by_sky_model(rig.source.sky.model)) rig.source.sky.model = std::string(k.sky_models.substr(0, k.sky_models.find(' ')));  // sky.rt.*
      if (k.path == "sky.rt.wavelength_nm" || k.path == "sky.rt.pressure_hPa") rig.source.sky.tau_rayleigh = "bodhaine";
      if (k.path.starts_with("sky.rt.aerosol.")) {  // an aerosol of IPRT A4's phase matrix
        rig.source.sky.aerosol_phase_matrix =
            std::string(POLRIG_SOURCE_DIR) + "/data/aerosol-phase-matrix/iprt-a4-spheroids-350nm.txt";
        rig.source.sky.rt.aerosol.tau = 0.2;
      }
      if (k.kind == RigKey::Kind::Real) k.real(rig) = v;
      else for (double& x : k.array(rig)) x = v;
      if (k.path == "schedule.start_deg" || k.path == "schedule.stop_deg")
        rig.schedule.start_deg = rig.schedule.stop_deg = v;  // one stop there
      if (k.path == "schedule.step_deg" && !upper) rig.schedule.count = 3;  // step 0: a static series (schedule.count)
      ASSERT_FALSE(check_rig(rig).has_value()) << k.path << " = " << v << ": " << check_rig(rig)->message;
      EXPECT_EQ(first_non_finite(rig), "") << k.path << " = " << v;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 2 * (23 + 17));  // every real key (17 of the sky's, 6 of them sky.rt.*), both ends
}

// Past the ranges (a rig built in code), simulate stops on the first non-finite voltage and says
// where, instead of the ADC's anonymous "non-finite voltage" (issue 8).
TEST(RigRanges, ANonFiniteVoltageIsNamedByStopAndPair) {
  Rig rig = short_schedule();
  rig.device.ring.L_photo = 1e300;  // cos⁴ falls to 0 off the axis: log10(0/0)
  try {
    simulate(rig);
    FAIL() << "simulate accepted L_photo = 1e300";
  } catch (const std::domain_error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("stop 0 (θ_R = 0°): pair 1's voltage is not finite"), std::string::npos) << msg;
  }
}

// The corners where the light is weakest against the strongest gain, and the reverse.
TEST(RigRanges, ExtremeCornersGiveFiniteResults) {
  Rig dim = short_schedule();
  dim.source.cos4 = {0.1, 1e-3};  // L_o, E_0
  dim.device.ring.L_photo = 500;
  dim.eccentricity = {100, 0, 100, 180};
  dim.electronics.volts_per_decade = 10;
  dim.device.truth.kv = {2, 2, 2};
  dim.device.truth.k_mV = {1000, -1000, 1000};
  EXPECT_EQ(first_non_finite(dim), "");
  Rig bright = short_schedule();
  bright.source.cos4 = {1000, 1e5};
  bright.device.ring.L_photo = 0.1;
  bright.electronics = {0.01, 2, 0.01, 1.0};  // volts_per_decade, adc_bits, vref_V, noise_sigma_V
  bright.device.truth.kv = {0.5, 0.5, 0.5};
  EXPECT_EQ(first_non_finite(bright), "");
}

// ---------------------------------------------------------------------------------------------
// The source seam
// ---------------------------------------------------------------------------------------------

// A time-dependent source written here: uniform light whose angle turns at 1°/s and whose degree
// grows by 0.001 per second, so that each stop's light tells the time simulate gave it.
class ClockSource final : public Source {
 public:
  std::string_view kind() const override { return "clock"; }
  unsigned flags() const override { return kTimeDependent | kUniformReference; }
  Polarization polarization(const SourceView&, const SourcePose& pose) const override {
    return {std::fmod(pose.t_s, 180.0), 0.3 + 0.001 * pose.t_s};
  }
  void irradiance(const SourceView&, const SourcePose&, std::span<double> E) const override {
    for (double& e : E) e = 7.0;
  }
  std::array<double, 6> ideal_irradiance(const SourceView&, const SourcePose&) const override {
    return {7, 7, 7, 7, 7, 7};
  }
};

// simulate passes each stop's time t_k (Schedule::stop_times_s) to the source: the paper's 10°
// steps at 5°/s with 1 s of dwell are 3 s apart (spec sky-and-compasses.md §1.4).
TEST(SourceSeam, SimulatePassesEachStopsTimeToTheSource) {
  Rig rig;
  rig.light = std::make_shared<const ClockSource>();
  const Simulation sim = simulate(rig);
  ASSERT_EQ(sim.stops.size(), 37u);
  for (std::size_t k = 0; k < sim.stops.size(); ++k) {
    const double t = 3.0 * static_cast<double>(k);
    EXPECT_NEAR(sim.stops[k].t_s, t, 1e-12) << k;
    EXPECT_NEAR(sim.stops[k].light.theta_deg, std::fmod(t, 180.0), 1e-12) << k;
    EXPECT_NEAR(sim.stops[k].light.d, 0.3 + 0.001 * t, 1e-15) << k;
  }
}

// A source with a uniform reference and no Eq. 6: the CS study takes the default per-pose turn,
// finds no eccentricity bias under uniform light (every ratio is 1) and writes Eq. 6 as NaN.
TEST(SourceSeam, TheCsStudyAsksTheSourceWhatItCanDo) {
  Rig rig;
  rig.light = std::make_shared<const ClockSource>();
  const CsStudy s = cs_study(rig, CsTurn(36));
  EXPECT_FALSE(s.standard_errors);
  EXPECT_FALSE(s.coaxial_reference);
  EXPECT_FALSE(s.eq6);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(s.summary[i].bsd_mV, 0.0);
    EXPECT_EQ(s.summary[i].mean_br_mV, 0.0);
    EXPECT_TRUE(std::isnan(s.summary[i].eq6_mV));
  }
  const CsStudy cos4 = cs_study(Rig{}, CsTurn(36));
  EXPECT_TRUE(cos4.eq6);
  EXPECT_FALSE(cos4.standard_errors);
}

// The factory is the only place naming the models: every kind it lists is accepted by the
// source.model key, and an unknown one is refused naming the key.
TEST(SourceSeam, TheFactoryKnowsTheKindsTheKeyAccepts) {
  const RigKey* model = find_rig_key("source.model");
  ASSERT_NE(model, nullptr);
  for (std::string_view kind : source_kinds()) EXPECT_TRUE(model->valid_text(kind)) << kind;
  EXPECT_FALSE(model->valid_text("fisheye"));
  SourceSpec spec;
  spec.model = "fisheye";
  try {
    make_source(spec);
    FAIL();
  } catch (const SourceSettingError& e) {
    EXPECT_EQ(e.key, "source.model");
  }
  EXPECT_EQ(make_source(SourceSpec{})->kind(), "cos4");
}

}  // namespace
}  // namespace polrig

// ---------------------------------------------------------------------------------------------
// study heading (study/heading_trials)
// ---------------------------------------------------------------------------------------------

// The settings' ranges, named by field (Python's keywords) or by the caller's names (the CLI's).
TEST(HeadingTrials, SettingsOutOfRangeAreRefusedByName) {
  polrig::HeadingStudySettings s;
  EXPECT_NO_THROW(polrig::check_heading_study_settings(s));
  s.p_max_min = 0.9;
  try {
    polrig::check_heading_study_settings(s, [](std::string_view f) { return "--" + std::string(f); });
    ADD_FAILURE() << "p_max_min above p_max_max accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "--p_max_min 0.9 is above --p_max_max 0.7");
  }
  s = {};
  s.roll_sd_deg = 31;
  try {
    polrig::check_heading_study_settings(s);
    ADD_FAILURE() << "roll_sd_deg 31 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "roll_sd_deg: expected a finite number in [0, 30] °, got 31");
  }
  s = {};
  s.trials = 0;
  EXPECT_THROW(polrig::heading_trials(polrig::Rig{}, s), std::invalid_argument);
  s = {};
  s.sync_max_s = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(polrig::check_heading_study_settings(s), std::invalid_argument);
}

// A level body, no turn, no INS error, a mount turned by m_z about the sensor's axis only: the
// sensor frame turns by m_z anticlockwise, so θ_b falls by m_z and so does the heading
// (level: H = A_s + θ_b). Through the device without noise, only the 16-bit ADC is left: its
// accuracy limit at d ≥ 0.49 is below 0.0015° (docs/validation.md, Fig. 6: 0.00102° at d = 0.7,
// ∝ 1/d).
TEST(HeadingTrials, MountAzimuthOffsetShiftsTheHeadingByMinusItself) {
  polrig::Rig rig;
  rig.electronics.noise_sigma_V = 0;
  polrig::HeadingStudySettings s;
  s.trials = 400;
  s.roll_sd_deg = s.pitch_sd_deg = 0;
  s.sync_max_s = 0;
  s.ins_tilt_sd_deg = 0;
  s.mount_tilt_sd_deg = 0;
  s.mount_azimuth_sd_deg = 2.0;
  double worst_device = 0;
  for (const polrig::HeadingTrial& t : polrig::heading_trials(rig, s)) {
    ASSERT_EQ(t.status, polrig::HeadingStatus::Ok);
    EXPECT_NEAR(t.error_mount_deg, -t.mount_z_deg, 1e-9) << t.index;
    EXPECT_NEAR(t.error_sync_deg, 0.0, 1e-9);
    worst_device = std::max(worst_device, std::abs(t.error_deg + t.mount_z_deg));
  }
  EXPECT_LT(worst_device, 0.0015);
  std::printf("largest heading error of a noise-free sensor through the ADC: %.2g deg\n", worst_device);
}
