// The device: Eq. 1 / Eq. 15 voltages, Eq. 5's bias, the ADC (Eq. 3) and the noise streams.
#include <gtest/gtest.h>

#include <cmath>

#include "polrig/device/params.h"
#include "polrig/device/electronics.h"
#include "polrig/device/sensor.h"
#include "polrig/random.h"

namespace polrig {
namespace {

const std::array<double, 6> kUniform{1, 1, 1, 1, 1, 1};

TEST(Params, TheoryValuesFollowFromTheFilmAxes) {
  const CalibrationParams t = CalibrationParams::theory(kWang2019FilmAxesDeg);
  const std::array<double, 6> alpha{0, 0, -120, -120, 120, 120};
  for (int m = 0; m < 6; ++m) EXPECT_NEAR(t.alpha_deg[m], alpha[m], 1e-12) << "m=" << m + 1;
  EXPECT_EQ(t.kv, (std::array<double, 3>{1, 1, 1}));
  EXPECT_EQ(t.k_mV, (std::array<double, 3>{0, 0, 0}));
  EXPECT_EQ(t.kd, (std::array<double, 6>{0, 0, 0, 0, 0, 0}));
}

// Eq. 1: V_i = 0.5·log10[(1 + d·cos(2θ − φ_i)) / (1 − d·cos(2θ − φ_i))], φ_i = 0°, 120°, 240°.
TEST(Sensor, TheoryDeviceReproducesEquationOne) {
  const CalibrationParams t = CalibrationParams::theory(kWang2019FilmAxesDeg);
  const Electronics e;
  for (double d : {0.05, 0.3, 0.55, 0.8}) {
    for (double theta = 0; theta < 180; theta += 7.5) {
      const auto V = pair_voltages(t, e, kUniform, theta, d);
      for (int i = 0; i < 3; ++i) {
        const double c = d * std::cos((2 * theta - 120.0 * i) * M_PI / 180.0);
        EXPECT_NEAR(V[i], 0.5 * std::log10((1 + c) / (1 - c)), 1e-14)
            << "d=" << d << " θ=" << theta << " i=" << i;
      }
    }
  }
}

TEST(Sensor, PublishedMaximumVoltages) {
  // Spec §2: d = 0.8813 gives max V = 600 mV (= Vref); d = 0.05 gives 21.73 mV. The d and the
  // voltage are quoted to 4 digits: dV/dd = 0.5·(2/ln10)/(1 − d²) ≈ 1.94 V at d = 0.8813, so
  // ±0.00005 in d is ±0.1 mV; 21.73 mV is quoted to ±0.005 mV.
  const CalibrationParams t = CalibrationParams::theory(kWang2019FilmAxesDeg);
  const Electronics e;
  EXPECT_NEAR(pair_voltage(t, e, 0, 1, 1, 0.0, 0.8813), 0.600, 1e-4);
  EXPECT_NEAR(pair_voltage(t, e, 0, 1, 1, 0.0, 0.05) * 1e3, 21.73, 0.005);
}

TEST(Sensor, CalibrationParametersEnterAsEquation15) {
  const CalibrationParams p = CalibrationParams::wang2019_indoor();
  const Electronics e;
  const double d = 0.55, theta = 37.0;
  const auto V = pair_voltages(p, e, kUniform, theta, d);
  for (int i = 0; i < 3; ++i) {
    const int j = 2 * i, h = 2 * i + 1;
    const double num = 1 + (1 + p.kd[j]) * d * std::cos((2 * theta + p.alpha_deg[j]) * M_PI / 180);
    const double den = 1 - (1 + p.kd[h]) * d * std::cos((2 * theta + p.alpha_deg[h]) * M_PI / 180);
    EXPECT_NEAR(V[i], p.kv[i] * 0.5 * std::log10(num / den) + p.k_mV[i] * 1e-3, 1e-14);
  }
}

TEST(Sensor, UnequalIrradianceAddsEquationFiveBias) {
  const CalibrationParams p = CalibrationParams::wang2019_indoor();
  const Electronics e;
  const std::array<double, 6> E{4.51, 4.49, 4.52, 4.50, 4.47, 4.53};
  for (double theta : {0.0, 33.0, 91.0, 150.0}) {
    const auto V = pair_voltages(p, e, E, theta, 0.55);
    const auto V0 = pair_voltages(p, e, kUniform, theta, 0.55);
    for (int i = 0; i < 3; ++i)
      EXPECT_NEAR(V[i] - V0[i], p.kv[i] * 0.5 * std::log10(E[2 * i] / E[2 * i + 1]), 1e-15);
  }
}

TEST(Adc, RoundsExactHalfCountsUp) {
  Electronics e;
  e.vref_V = 0.5;  // a power of two: V/Vref·2^15 is exact, so the half counts are exact
  const double lsb = e.vref_V / 32768.0;
  EXPECT_EQ(adc_count(2.5 * lsb, e), 3);
  EXPECT_EQ(adc_count(-2.5 * lsb, e), -2);  // half up is towards +∞, not away from zero
  EXPECT_EQ(adc_count(0.5 * lsb, e), 1);
  EXPECT_EQ(adc_count(-0.5 * lsb, e), 0);
  EXPECT_EQ(adc_count(std::nextafter(2.5, 0.0) * lsb, e), 2);
  EXPECT_EQ(adc_count(0.0, e), 0);
}

TEST(Adc, ClampsToTheSignedRange) {
  const Electronics e;  // 16 bits, Vref 0.6 V
  EXPECT_EQ(adc_count(0.6, e), 32767);
  EXPECT_EQ(adc_count(5.0, e), 32767);
  EXPECT_EQ(adc_count(-0.6, e), -32767);
  EXPECT_EQ(adc_count(-5.0, e), -32767);
  EXPECT_EQ(adc_count(0.6 * 32766.0 / 32768.0, e), 32766);
  EXPECT_NEAR(adc_quantize(0.6, e), 0.6 * 32767.0 / 32768.0, 1e-15);
}

TEST(Adc, QuantizationErrorIsAtMostHalfAnLsb) {
  const Electronics e;
  const double lsb = e.vref_V / 32768.0;
  for (double v = -0.55; v < 0.55; v += 0.000123)
    EXPECT_LE(std::abs(adc_quantize(v, e) - v), 0.5 * lsb * (1 + 1e-12)) << v;
}

TEST(Noise, IsAPureFunctionOfItsCounters) {
  // Values from an implementation outside polrig (Python, integers mod 2⁶⁴) of random.h's
  // algorithm: SplitMix64 (its mixer checked there against Vigna's published first output for
  // state 1234567, 6457827717110365317), the counters mixed in order, a 53-bit uniform in (0, 1]
  // and Box–Muller. Bit-identical results on every platform need exactly these numbers; libm's
  // log and cos may differ in the last place, hence 1e-15 for the normal deviates.
  EXPECT_EQ(uniform_unit(1, 2, 3, 4), 0.8345914937343463);
  EXPECT_EQ(uniform_unit(20190806, 0, 0, 0), 0.6973096687204471);
  EXPECT_EQ(uniform_unit(7, 123456, 2, 39), 0.12004825914324735);
  EXPECT_NEAR(standard_normal(1, 2, 3, 4), -0.586190786834022, 1e-15);
  EXPECT_NEAR(standard_normal(20190806, 0, 0, 0), 0.8491444661752259, 1e-15);
  EXPECT_NEAR(standard_normal(7, 123456, 2, 39), -1.3157646201309343, 1e-15);
  // Each counter matters.
  EXPECT_NE(standard_normal(1, 2, 3, 4), standard_normal(1, 2, 3, 5));
  EXPECT_NE(standard_normal(1, 2, 3, 4), standard_normal(1, 2, 4, 4));
  EXPECT_NE(standard_normal(1, 2, 3, 4), standard_normal(1, 3, 3, 4));
  EXPECT_NE(standard_normal(1, 2, 3, 4), standard_normal(2, 2, 3, 4));
}

TEST(Noise, HasZeroMeanAndUnitVariance) {
  // N = 10^6 deviates: the mean has standard error 1/√N = 0.001 and the variance √(2/N) =
  // 0.0014; allow 5 standard errors. Neighbouring channels must be uncorrelated to the same
  // standard error.
  const int n = 1000000;
  double sum = 0, sum2 = 0, cross = 0, sum4 = 0;
  for (int k = 0; k < n; ++k) {
    const double a = standard_normal(7, static_cast<std::uint64_t>(k / 40), 0, k % 40);
    const double b = standard_normal(7, static_cast<std::uint64_t>(k / 40), 1, k % 40);
    sum += a;
    sum2 += a * a;
    sum4 += a * a * a * a;
    cross += a * b;
  }
  EXPECT_NEAR(sum / n, 0.0, 5 * 1e-3);
  EXPECT_NEAR(sum2 / n, 1.0, 5 * std::sqrt(2.0 / n));
  EXPECT_NEAR(cross / n, 0.0, 5 * 1e-3);
  EXPECT_NEAR(sum4 / n, 3.0, 5 * std::sqrt(96.0 / n));  // Gaussian kurtosis; Var(x⁴) = 96
}

}  // namespace
}  // namespace polrig
