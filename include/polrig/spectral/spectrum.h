#pragma once
// A tabulated spectrum: wavelength λ in nm → a non-negative value (a transmittance, a
// responsivity, a spectral radiance…), linear between samples and undefined outside them.
#include <cstddef>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace polrig {

// A bad sample or an evaluation outside the samples. `sample` is the 0-based index of the
// offending sample (or npos when the error concerns no single sample).
class SpectrumError : public std::invalid_argument {
 public:
  SpectrumError(const std::string& what, std::size_t sample = npos)
      : std::invalid_argument(what), sample(sample) {}
  static constexpr std::size_t npos = static_cast<std::size_t>(-1);
  std::size_t sample;
};

class Spectrum {
 public:
  // Throws SpectrumError naming `name` unless there are at least two samples, as many values
  // as wavelengths, every wavelength finite and > 0 and strictly increasing (no duplicates),
  // and every value finite and ≥ 0.
  Spectrum(std::vector<double> wavelength_nm, std::vector<double> value,
           std::string name = "spectrum");

  // Linear interpolation; SpectrumError outside [min_nm(), max_nm()].
  double operator()(double nm) const;

  double min_nm() const { return wavelength_nm_.front(); }
  double max_nm() const { return wavelength_nm_.back(); }
  bool covers(double lo_nm, double hi_nm) const { return min_nm() <= lo_nm && hi_nm <= max_nm(); }
  const std::vector<double>& wavelength_nm() const { return wavelength_nm_; }
  const std::vector<double>& value() const { return value_; }
  const std::string& name() const { return name_; }

 private:
  std::vector<double> wavelength_nm_, value_;
  std::string name_;
};

// ∫ over [lo_nm, hi_nm] of the product of the factors' linear interpolants (units: the
// product's × nm). Every factor must cover the interval (SpectrumError otherwise), and at most
// five factors are allowed. The result is exact for the interpolants: on each interval of the
// union of all sample points inside [lo, hi] every factor is linear, so the product of k ≤ 5
// factors is a polynomial of degree ≤ 5, which 3-point Gauss–Legendre integrates exactly. (A
// trapezoid on the union grid would be exact only for a single factor.)
double integrate_product(std::span<const Spectrum* const> factors, double lo_nm, double hi_nm);

// ∫ of one spectrum over its own samples (the trapezoid rule, exact for the interpolant).
double integrate(const Spectrum& s);

}  // namespace polrig
