#include "polrig/spectral/spectrum.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "polrig/quadrature.h"

namespace polrig {

Spectrum::Spectrum(std::vector<double> wavelength_nm, std::vector<double> value, std::string name)
    : wavelength_nm_(std::move(wavelength_nm)), value_(std::move(value)), name_(std::move(name)) {
  if (wavelength_nm_.size() != value_.size())
    throw SpectrumError(fmt::format("{}: {} wavelengths but {} values", name_,
                                    wavelength_nm_.size(), value_.size()));
  if (wavelength_nm_.size() < 2)
    throw SpectrumError(fmt::format("{}: {} sample(s); a spectrum needs at least two", name_,
                                    wavelength_nm_.size()));
  for (std::size_t i = 0; i < wavelength_nm_.size(); ++i) {
    const double nm = wavelength_nm_[i], v = value_[i];
    if (!std::isfinite(nm) || nm <= 0)
      throw SpectrumError(fmt::format("{}: sample {}: wavelength {} nm; expected a finite "
                                      "wavelength > 0", name_, i + 1, nm), i);
    if (!std::isfinite(v) || v < 0)
      throw SpectrumError(fmt::format("{}: sample {} at {} nm: value {}; expected a finite "
                                      "value >= 0", name_, i + 1, nm, v), i);
    if (i > 0 && nm <= wavelength_nm_[i - 1])
      throw SpectrumError(
          fmt::format("{}: sample {}: wavelength {} nm {} the previous one ({} nm); wavelengths "
                      "must increase strictly", name_, i + 1, nm,
                      nm == wavelength_nm_[i - 1] ? "repeats" : "is below",
                      wavelength_nm_[i - 1]), i);
  }
}

double Spectrum::operator()(double nm) const {
  if (!(nm >= min_nm() && nm <= max_nm()))
    throw SpectrumError(fmt::format("{}: {} nm is outside its samples [{}, {}] nm", name_, nm,
                                    min_nm(), max_nm()));
  // the first sample ≥ nm; interpolate from the one before it
  const auto hi = std::lower_bound(wavelength_nm_.begin(), wavelength_nm_.end(), nm);
  const std::size_t j = static_cast<std::size_t>(hi - wavelength_nm_.begin());
  if (wavelength_nm_[j] == nm) return value_[j];
  const double t = (nm - wavelength_nm_[j - 1]) / (wavelength_nm_[j] - wavelength_nm_[j - 1]);
  return value_[j - 1] + t * (value_[j] - value_[j - 1]);
}

double integrate_product(std::span<const Spectrum* const> factors, double lo_nm, double hi_nm) {
  if (factors.empty() || factors.size() > 5)
    throw SpectrumError(fmt::format("integrate_product: {} factors; expected 1 to 5",
                                    factors.size()));
  if (!(std::isfinite(lo_nm) && std::isfinite(hi_nm) && lo_nm <= hi_nm))
    throw SpectrumError(fmt::format("integrate_product: bad interval [{}, {}] nm", lo_nm, hi_nm));
  for (const Spectrum* f : factors)
    if (!f->covers(lo_nm, hi_nm))
      throw SpectrumError(fmt::format("{}: its samples [{}, {}] nm do not cover [{}, {}] nm",
                                      f->name(), f->min_nm(), f->max_nm(), lo_nm, hi_nm));
  std::vector<double> grid{lo_nm, hi_nm};
  for (const Spectrum* f : factors)
    for (double nm : f->wavelength_nm())
      if (nm > lo_nm && nm < hi_nm) grid.push_back(nm);
  std::sort(grid.begin(), grid.end());
  grid.erase(std::unique(grid.begin(), grid.end()), grid.end());

  static const QuadratureRule rule = gauss_legendre_01(3);
  double sum = 0;
  for (std::size_t i = 0; i + 1 < grid.size(); ++i) {
    const double a = grid[i], width = grid[i + 1] - a;
    double interval = 0;
    for (std::size_t q = 0; q < rule.x.size(); ++q) {
      double product = 1;
      for (const Spectrum* f : factors) product *= (*f)(a + rule.x[q] * width);
      interval += rule.w[q] * product;
    }
    sum += interval * width;
  }
  return sum;
}

double integrate(const Spectrum& s) {
  const std::vector<double>& x = s.wavelength_nm();
  const std::vector<double>& y = s.value();
  double sum = 0;
  for (std::size_t i = 0; i + 1 < x.size(); ++i) sum += 0.5 * (y[i] + y[i + 1]) * (x[i + 1] - x[i]);
  return sum;
}

}  // namespace polrig
