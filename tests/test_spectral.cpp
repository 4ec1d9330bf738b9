// The spectral model of kd: spectra, their integrals, Planck's law, the effective degree, the
// CSV reader and `polrig spectral kd`. Every expected value is a closed form or a number
// written by hand here, never the code's own helpers.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <vector>

#include "polrig/io/measured.h"
#include "polrig/io/spectrum_csv.h"
#include "polrig/spectral/effective_degree.h"
#include "polrig/spectral/sources.h"
#include "polrig/spectral/spectrum.h"
#include "support.h"

using namespace polrig;
using namespace polrig::test;

namespace {

// ---- Spectrum: construction and interpolation

TEST(Spectrum, InterpolatesLinearlyAndRefusesOutside) {
  const Spectrum s({400, 500, 700}, {1, 3, 0}, "s");
  EXPECT_DOUBLE_EQ(s(400), 1);
  EXPECT_DOUBLE_EQ(s(450), 2);
  EXPECT_DOUBLE_EQ(s(500), 3);
  EXPECT_DOUBLE_EQ(s(650), 0.75);
  EXPECT_DOUBLE_EQ(s(700), 0);
  EXPECT_THROW(s(399.999), SpectrumError);
  EXPECT_THROW(s(700.001), SpectrumError);
  EXPECT_THROW(s(std::nan("")), SpectrumError);
}

TEST(Spectrum, RefusesBadSamplesNamingThem) {
  const double inf = std::numeric_limits<double>::infinity();
  const auto message = [](std::vector<double> x, std::vector<double> y) -> std::string {
    try {
      Spectrum s(std::move(x), std::move(y), "film.csv");
    } catch (const SpectrumError& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_HAS(message({400, 390, 500}, {1, 1, 1}), "film.csv: sample 2: wavelength 390 nm is below");
  EXPECT_HAS(message({400, 400, 500}, {1, 1, 1}), "wavelength 400 nm repeats");
  EXPECT_HAS(message({400, 450, 500}, {1, -0.1, 1}), "sample 2 at 450 nm: value -0.1");
  EXPECT_HAS(message({400, 450, 500}, {1, std::nan(""), 1}), "value nan");
  EXPECT_HAS(message({400, inf}, {1, 1}), "wavelength inf nm");
  EXPECT_HAS(message({-5, 400}, {1, 1}), "wavelength -5 nm; expected a finite wavelength > 0");
  EXPECT_HAS(message({400}, {1}), "1 sample(s)");
  EXPECT_HAS(message({400, 500}, {1}), "2 wavelengths but 1 values");
  try {
    Spectrum({400, 500, 500}, {1, 1, 1});
  } catch (const SpectrumError& e) {
    EXPECT_EQ(e.sample, 2u);
  }
}

// ---- Integration against closed forms

// Coefficients c[k] of Σ c_k λ^k.
using Poly = std::vector<double>;
Poly times(const Poly& a, const Poly& b) {
  Poly c(a.size() + b.size() - 1, 0.0);
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < b.size(); ++j) c[i + j] += a[i] * b[j];
  return c;
}
double integral(const Poly& p, double lo, double hi) {
  double s = 0;
  for (std::size_t k = 0; k < p.size(); ++k)
    s += p[k] * (std::pow(hi, double(k + 1)) - std::pow(lo, double(k + 1))) / double(k + 1);
  return s;
}
// A linear function sampled at the given wavelengths (its interpolant is the function itself).
Spectrum sampled(const Poly& linear, std::vector<double> nm) {
  std::vector<double> v;
  for (double x : nm) v.push_back(linear[0] + linear[1] * x);
  return Spectrum(std::move(nm), std::move(v));
}

TEST(SpectrumIntegral, LinearSpectrumMatchesClosedForm) {
  const Poly f{0.2, 0.003};
  const Spectrum s = sampled(f, {380, 401.5, 455, 600, 731});
  EXPECT_NEAR(integrate(s), integral(f, 380, 731), 1e-12 * integral(f, 380, 731));
  const std::array<const Spectrum*, 1> one{&s};
  EXPECT_NEAR(integrate_product(one, 420, 700), integral(f, 420, 700), 1e-12);
}

TEST(SpectrumIntegral, ProductsOfLinearSpectraOnDifferentGridsAreExact) {
  // Up to five factors, each linear (so their interpolants are exact), sampled on different
  // grids: the product is a polynomial of degree ≤ 5, integrated here by its antiderivative.
  const std::vector<Poly> f{{1.0, 0.001}, {2.0, -0.002}, {0.1, 0.0005}, {3.0, 0.0}, {0.5, 0.001}};
  const std::vector<std::vector<double>> grids{
      {300, 800}, {300, 333, 512, 650, 800}, {290, 410.25, 777, 810}, {250, 900}, {300, 500, 800}};
  std::vector<Spectrum> s;
  for (std::size_t i = 0; i < f.size(); ++i) s.push_back(sampled(f[i], grids[i]));
  Poly p{1.0};
  std::vector<const Spectrum*> factors;
  for (std::size_t i = 0; i < f.size(); ++i) {
    p = times(p, f[i]);
    factors.push_back(&s[i]);
    const double exact = integral(p, 320, 730);
    EXPECT_NEAR(integrate_product(factors, 320, 730), exact, 1e-12 * std::abs(exact))
        << factors.size() << " factors";
  }
  factors.push_back(&s[0]);
  EXPECT_THROW(integrate_product(factors, 320, 730), SpectrumError);  // six factors
}

TEST(SpectrumIntegral, RefusesAFactorThatDoesNotCoverTheInterval) {
  const Spectrum a({300, 800}, {1, 1}, "a"), b({400, 700}, {1, 1}, "b");
  const std::array<const Spectrum*, 2> ab{&a, &b};
  EXPECT_NO_THROW(integrate_product(ab, 400, 700));
  try {
    integrate_product(ab, 350, 700);
    ADD_FAILURE() << "no error";
  } catch (const SpectrumError& e) {
    EXPECT_HAS(std::string(e.what()), "b: its samples [400, 700] nm do not cover [350, 700] nm");
  }
}

// ---- Planck's law

// The wavelength of the largest B_λ(·, T), by golden-section search.
double peak_nm(double T) {
  double a = 100, b = 3000;
  const double r = (std::sqrt(5.0) - 1) / 2;
  while (b - a > 1e-9) {
    const double c = b - r * (b - a), d = a + r * (b - a);
    if (planck_radiance(c, T) > planck_radiance(d, T)) b = d; else a = c;
  }
  return (a + b) / 2;
}

TEST(Planck, WienDisplacementLaw) {
  // λ_max·T = b = 2.897771955e-3 m·K (CODATA 2018). A search on function values finds a
  // maximum only to a relative ~√ε·(a few) ≈ 1e-8 (B is flat there: B ≈ B_max·(1 − κδ²/2)
  // with κ ≈ 5, so values within 2e-16 of each other cannot be told apart for δ < 1e-8).
  for (double T : {kIlluminantA_K, kSunBlackbody_K, 1500.0, 10000.0})
    EXPECT_NEAR(peak_nm(T) * 1e-9 * T, 2.897771955e-3, 3e-8 * 2.897771955e-3) << T << " K";
}

TEST(Planck, StefanBoltzmannRadiance) {
  // ∫ B_λ dλ = σT⁴/π, σ = 5.670374419e-8 W·m⁻²·K⁻⁴ (CODATA 2018). Trapezoid on a geometric
  // grid (ratio 1 + 1e-4) from 50 nm to 1 mm: the truncated tails are < 1e-9 of the total
  // (Wien side: x = hc/λkT > 49; Rayleigh–Jeans side: 5/π⁴·x³ with x < 2.5e-3), the
  // trapezoid's error ~ (1e-4)²/12.
  for (double T : {kIlluminantA_K, kSunBlackbody_K}) {
    std::vector<double> nm, v;
    for (double x = 50; x < 1e6; x *= 1.0001) {
      nm.push_back(x);
      v.push_back(planck_radiance(x, T));
    }
    const double expected = 5.670374419e-8 * std::pow(T, 4) / M_PI;
    EXPECT_NEAR(integrate(Spectrum(nm, v)), expected, 1e-8 * expected) << T << " K";
  }
}

TEST(Planck, SampledBlackbodyAndItsRange) {
  const Spectrum b = blackbody(3000, 320, 730.5, 1.0);
  EXPECT_EQ(b.min_nm(), 320);
  EXPECT_EQ(b.max_nm(), 730.5);
  EXPECT_EQ(b.wavelength_nm().size(), 412u);  // 320, 321, …, 730, 730.5
  EXPECT_EQ(blackbody(3000, 320, 730).wavelength_nm().size(), 4101u);  // every 0.1 nm
  EXPECT_DOUBLE_EQ(b(555), planck_radiance(555, 3000));
  EXPECT_THROW(planck_radiance(500, 0), std::invalid_argument);
  EXPECT_THROW(planck_radiance(500, std::nan("")), std::invalid_argument);
  EXPECT_THROW(planck_radiance(-1, 3000), std::invalid_argument);
  EXPECT_THROW(blackbody(3000, 500, 400), std::invalid_argument);
}

TEST(RayleighSky, WeightsTheSunByInverseFourthPower) {
  const Spectrum sun({400, 550, 700}, {2, 2, 2}, "flat sun");
  const Spectrum sky = rayleigh_sky(sun);
  EXPECT_DOUBLE_EQ(sky(550), 2);
  EXPECT_NEAR(sky(400), 2 * std::pow(550.0 / 400.0, 4), 1e-12);
  EXPECT_NEAR(sky(700), 2 * std::pow(550.0 / 700.0, 4), 1e-12);
}

// ---- The effective degree

TEST(EffectiveDegree, FlatFilmsGiveTheirOwnDegreeForAnySource) {
  const double M = 0.8, m = 0.013;
  const FilmSpectra film{Spectrum({300, 800}, {M, M}), Spectrum({300, 800}, {m, m})};
  const Spectrum response({320, 440, 560, 730}, {0, 0.2, 0.3, 0});
  const double d = (M - m) / (M + m);
  for (double T : {kIlluminantA_K, kSunBlackbody_K}) {
    const EffectiveDegree e = effective_degree(film, blackbody(T, 320, 730), response);
    EXPECT_NEAR(e.d_eff, d, 1e-15);
    EXPECT_NEAR(e.kd(), d - 1, 1e-15);
  }
  EXPECT_NEAR(effective_degree(film, blackbody(2856, 320, 730), response, 3.0).d_eff,
              (M - 3 * m) / (M + 3 * m), 1e-15);
}

TEST(EffectiveDegree, TwoLineSourceIsTheWeightedMean) {
  // Films and response are flat across two narrow triangular "lines" at 420 nm (height 3, base
  // 4 nm, area 6) and 650 nm (height 1, area 2); at 420 nm τM = 0.7, τm = 0.03, R = 0.2, at 650
  // nm τM = 0.85, τm = 0.2, R = 0.1.
  //   d_eff = [6·0.67·0.2 + 2·0.65·0.1] / [6·0.73·0.2 + 2·1.05·0.1] = 0.934 / 1.086
  const std::vector<double> x{300, 415, 425, 645, 655, 800};
  const FilmSpectra film{Spectrum(x, {0.5, 0.7, 0.7, 0.85, 0.85, 0.9}),
                         Spectrum(x, {0.2, 0.03, 0.03, 0.2, 0.2, 0.4})};
  const Spectrum response(x, {0.05, 0.2, 0.2, 0.1, 0.1, 0.0});
  const Spectrum lines({300, 418, 420, 422, 648, 650, 652, 800}, {0, 0, 3, 0, 0, 1, 0, 0});
  EXPECT_NEAR(effective_degree(film, lines, response).d_eff, 0.934 / 1.086, 1e-14);
  // leakage doubled: [6·0.64·0.2 + 2·0.45·0.1] / [6·0.76·0.2 + 2·1.25·0.1] = 0.858 / 1.162
  EXPECT_NEAR(effective_degree(film, lines, response, 2.0).d_eff, 0.858 / 1.162, 1e-14);
}

TEST(EffectiveDegree, HotterSourceLowersDegreeOfAFilmThatImprovesWithWavelength) {
  // If d(λ) rises with λ and the weight ratio B(λ, T_hot)/B(λ, T_cold) falls with λ (it does
  // for Planck's law), the hot source's weighted mean of d is the lower one (Chebyshev's sum
  // inequality for similarly/oppositely ordered sequences).
  const std::vector<double> x{320, 400, 500, 600, 730};
  const FilmSpectra film{Spectrum(x, {0.6, 0.7, 0.8, 0.85, 0.85}),
                         Spectrum(x, {0.2, 0.05, 0.01, 0.005, 0.001})};
  const Spectrum response(x, {0.1, 0.3, 0.3, 0.2, 0.1});
  const double cold = effective_degree(film, blackbody(2856, 320, 730), response).d_eff;
  const double hot = effective_degree(film, blackbody(10000, 320, 730), response).d_eff;
  EXPECT_LT(hot, cold);
}

TEST(EffectiveDegree, RefusesImpossibleInput) {
  const std::vector<double> x{320, 500, 730};
  const FilmSpectra film{Spectrum(x, {0.8, 0.8, 0.8}, "M"), Spectrum(x, {0.1, 0.3, 0.1}, "m")};
  const Spectrum response(x, {1, 1, 1});
  const Spectrum lamp = blackbody(2856, 320, 730);
  EXPECT_NO_THROW(effective_degree(film, lamp, response, 2.0));
  EXPECT_THROW(effective_degree(film, lamp, response, 3.0), SpectrumError);  // 0.9 > 0.8
  EXPECT_THROW(effective_degree(film, lamp, response, 0.0), SpectrumError);
  EXPECT_THROW(effective_degree(film, blackbody(2856, 330, 730), response), SpectrumError);
  EXPECT_THROW(effective_degree(film, lamp, Spectrum(x, {0, 0, 0})), SpectrumError);
}

// τM dips between τm's samples: s·τm ≤ τM holds at every τm sample but not at τM's 500 nm one
// (τm(500) = 0.1, τM(500) = 0.15: scale 2 gives 0.2 > 0.15).
TEST(EffectiveDegree, RefusesLeakageAbovePassAtAPassSampleOnly) {
  const FilmSpectra film{Spectrum({320, 500, 730}, {0.8, 0.15, 0.8}, "M"),
                         Spectrum({320, 730}, {0.1, 0.1}, "m")};
  const Spectrum response({320, 730}, {1, 1});
  const Spectrum lamp = blackbody(2856, 320, 730);
  EXPECT_NO_THROW(effective_degree(film, lamp, response, 1.0));
  try {
    effective_degree(film, lamp, response, 2.0);
    ADD_FAILURE() << "leakage 0.2 above pass 0.15 at 500 nm accepted";
  } catch (const SpectrumError& e) {
    EXPECT_NE(std::string(e.what()).find("at 500 nm"), std::string::npos) << e.what();
  }
}

// ---- CSV files

class SpectrumCsv : public ::testing::Test {
 protected:
  TempDir dir{"polrig_test_spectral_"};
  fs::path file(const std::string& text) {
    const fs::path p = dir.path() / "s.csv";
    write_file(p, text);
    return p;
  }
  std::string error_of(const std::string& text) {
    try {
      read_film_csv(file(text));
    } catch (const DataError& e) {
      return e.what();
    }
    return "no error";
  }
};

TEST_F(SpectrumCsv, ReadsCommentedFile) {
  const FilmSpectra f = read_film_csv(file("# a comment\nwavelength_nm,tau_M,tau_m\n400,0.7,0.01\n"
                                           "500,0.8,0.001\n"));
  EXPECT_DOUBLE_EQ(f.tau_M(450), 0.75);
  EXPECT_DOUBLE_EQ(f.tau_m(400), 0.01);
}

TEST_F(SpectrumCsv, ErrorsNameFileLineColumnAndValue) {
  const std::string h = "wavelength_nm,tau_M,tau_m\n";
  EXPECT_HAS(error_of(h + "400,0.7,0.01\n390,0.8,0.001\n"),
             "s.csv:3: column 'wavelength_nm': 390 is below the previous row's 400");
  EXPECT_HAS(error_of(h + "400,0.7,0.01\n400,0.8,0.001\n"), "s.csv:3: column 'wavelength_nm': 400 repeats");
  EXPECT_HAS(error_of(h + "400,0.7,-0.01\n500,0.8,0.001\n"), "s.csv:2: column 'tau_m': -0.01; expected a value >= 0");
  EXPECT_HAS(error_of(h + "400,1.2,0.01\n500,0.8,0.001\n"), "s.csv:2: column 'tau_M': 1.2 exceeds 1");
  EXPECT_HAS(error_of(h + "400,0.7,0.01\n500,0.8,nan\n"), "s.csv:3: column 'tau_m': expected a finite number, got 'nan'");
  EXPECT_HAS(error_of(h + "400,0.7,0.01\n500,0.3,0.4\n"), "s.csv:3: column 'tau_m': 0.4 exceeds tau_M = 0.3");
  EXPECT_HAS(error_of(h + "0,0.7,0.01\n500,0.3,0.1\n"), "s.csv:2: column 'wavelength_nm': 0; expected a wavelength > 0");
  EXPECT_HAS(error_of("wavelength_nm,tau_M\n400,0.7\n500,0.8\n"), "missing column 'tau_m'");
  EXPECT_HAS(error_of(h + "400,0.7,0.01\n"), "1 data row(s)");
}

TEST_F(SpectrumCsv, ShippedSpectraAreValid) {
  const fs::path data = fs::path(POLRIG_SOURCE_DIR) / "data" / "spectra";
  const FilmSpectra film = read_film_csv(data / "sheet-polarizer-synthetic.csv");
  for (const char* r : {"blue-filter-photodiode-synthetic.csv", "blue-filter-redleak-photodiode-synthetic.csv"}) {
    const Spectrum response = read_spectrum_csv(data / r, "response");
    EXPECT_TRUE(film.tau_M.covers(response.min_nm(), response.max_nm())) << r;
  }
  for (const char* column : {"extraterrestrial", "direct_am15"}) {
    const Spectrum sun = read_spectrum_csv(data / "astm-g173.csv", column);
    EXPECT_EQ(sun.min_nm(), 300);
    EXPECT_EQ(sun.max_nm(), 800);
    EXPECT_EQ(sun.wavelength_nm().size(), 601u);
  }
  // Two values of the ASTM G173-03 table, read off it by hand.
  EXPECT_DOUBLE_EQ(read_spectrum_csv(data / "astm-g173.csv", "extraterrestrial")(500), 1.916);
  EXPECT_DOUBLE_EQ(read_spectrum_csv(data / "astm-g173.csv", "direct_am15")(500), 1.3391);
}

// ---- The command

class SpectralCli : public PolrigTest {
 protected:
  SpectralCli() : PolrigTest("polrig_test_spectral_cli_", "") {}
  const std::string data = (fs::path(POLRIG_SOURCE_DIR) / "data" / "spectra").string() + "/";
};

TEST_F(SpectralCli, WritesKdForLampAndSky) {
  const std::string args = "spectral kd --films " + data + "sheet-polarizer-synthetic.csv --response " +
                           data + "blue-filter-photodiode-synthetic.csv --sun " + data +
                           "astm-g173.csv --lamp-temperature 2856 --no-plots -o " +
                           shell_quote(tmp / "out");
  ok(args);
  const Csv kd = read_csv(tmp / "out" / "kd.csv");
  ASSERT_EQ(kd.rows.size(), 6u);
  const double lamp = std::stod(kd.rows[0][kd.col("kd_lamp")]);
  const double sky = std::stod(kd.rows[0][kd.col("kd_sky")]);
  EXPECT_DOUBLE_EQ(std::stod(kd.rows[0][kd.col("kd_sky_minus_lamp")]), sky - lamp);
  EXPECT_LT(lamp, 0);
  EXPECT_TRUE(fs::exists(tmp / "out" / "spectra.csv"));
  EXPECT_TRUE(fs::exists(tmp / "out" / "manifest.yaml"));
  // an existing folder is not replaced without --force
  EXPECT_NE(polrig(args).status, 0);
  ok(args + " --force");
}

TEST_F(SpectralCli, BadInputWritesNothing) {
  write_file(tmp / "bad.csv", "wavelength_nm,tau_M,tau_m\n320,0.7,0.01\n310,0.8,0.001\n");
  const Result r = polrig("spectral kd --films " + shell_quote(tmp / "bad.csv") + " --response " +
                          data + "blue-filter-photodiode-synthetic.csv --no-plots -o " +
                          shell_quote(tmp / "out"));
  EXPECT_NE(r.status, 0);
  EXPECT_HAS(r.err, "bad.csv:3: column 'wavelength_nm': 310 is below");
  EXPECT_FALSE(fs::exists(tmp / "out"));
  const Result s = polrig("spectral kd --films " + data + "sheet-polarizer-synthetic.csv --response " +
                          data + "blue-filter-photodiode-synthetic.csv --tau-m-scale 1,1,1 "
                          "--no-plots -o " + shell_quote(tmp / "out"));
  EXPECT_NE(s.status, 0);
  EXPECT_HAS(s.err, "--tau-m-scale: 3 values; expected 6");
  EXPECT_FALSE(fs::exists(tmp / "out"));
}

}  // namespace
