#include "polrig/spectral/sources.h"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace polrig {

namespace {
constexpr double h = 6.62607015e-34;   // J·s
constexpr double c = 299792458.0;      // m/s
constexpr double k_B = 1.380649e-23;   // J/K

void check_temperature(double temperature_K) {
  if (!(temperature_K >= kMinTemperature_K && temperature_K <= kMaxTemperature_K))
    throw std::invalid_argument(fmt::format("blackbody temperature {} K: expected [{}, {}] K",
                                            temperature_K, kMinTemperature_K, kMaxTemperature_K));
}
}  // namespace

double planck_radiance(double wavelength_nm, double temperature_K) {
  check_temperature(temperature_K);
  if (!(std::isfinite(wavelength_nm) && wavelength_nm > 0))
    throw std::invalid_argument(fmt::format("wavelength {} nm: expected > 0", wavelength_nm));
  const double lambda = wavelength_nm * 1e-9;
  const double per_m = 2 * h * c * c / std::pow(lambda, 5) / std::expm1(h * c / (lambda * k_B * temperature_K));
  return per_m * 1e-9;  // per metre of wavelength → per nanometre
}

Spectrum blackbody(double temperature_K, double lo_nm, double hi_nm, double step_nm) {
  check_temperature(temperature_K);
  if (!(std::isfinite(lo_nm) && std::isfinite(hi_nm) && lo_nm > 0 && hi_nm > lo_nm))
    throw std::invalid_argument(fmt::format("blackbody: bad range [{}, {}] nm", lo_nm, hi_nm));
  if (!(std::isfinite(step_nm) && step_nm > 0 && (hi_nm - lo_nm) / step_nm <= 1e7))
    throw std::invalid_argument(fmt::format("blackbody: step {} nm: expected > 0 and at most "
                                            "1e7 samples", step_nm));
  const auto n = static_cast<std::size_t>(std::ceil((hi_nm - lo_nm) / step_nm - 1e-9));
  std::vector<double> nm, value;
  for (std::size_t i = 0; i <= n; ++i) {
    const double x = i == n ? hi_nm : lo_nm + static_cast<double>(i) * step_nm;
    nm.push_back(x);
    value.push_back(planck_radiance(x, temperature_K));
  }
  return Spectrum(std::move(nm), std::move(value), fmt::format("blackbody {} K", temperature_K));
}

Spectrum rayleigh_sky(const Spectrum& sun) {
  std::vector<double> value = sun.value();
  for (std::size_t i = 0; i < value.size(); ++i) value[i] *= std::pow(550.0 / sun.wavelength_nm()[i], 4);
  return Spectrum(sun.wavelength_nm(), std::move(value), "Rayleigh sky from " + sun.name());
}

}  // namespace polrig
