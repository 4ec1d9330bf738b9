#include "polrig/spectral/effective_degree.h"

#include <array>
#include <cmath>

#include <fmt/format.h>

namespace polrig {

EffectiveDegree effective_degree(const FilmSpectra& film, const Spectrum& source,
                                 const Spectrum& response, double tau_m_scale) {
  if (!(std::isfinite(tau_m_scale) && tau_m_scale > 0 && tau_m_scale <= 1e3))
    throw SpectrumError(fmt::format("tau_m scale {}: expected (0, 1000]", tau_m_scale));
  const double lo = response.min_nm(), hi = response.max_nm();
  const auto& nm = film.tau_m.wavelength_nm();
  for (std::size_t i = 0; i < nm.size(); ++i)
    if (nm[i] >= lo && nm[i] <= hi && film.tau_M.covers(nm[i], nm[i]) &&
        tau_m_scale * film.tau_m.value()[i] > film.tau_M(nm[i]))
      throw SpectrumError(fmt::format("{} x {} = {} exceeds {} = {} at {} nm: the leakage "
                                      "cannot exceed the pass transmittance", film.tau_m.name(),
                                      tau_m_scale, tau_m_scale * film.tau_m.value()[i],
                                      film.tau_M.name(), film.tau_M(nm[i]), nm[i]), i);
  const std::array<const Spectrum*, 3> pass{&film.tau_M, &source, &response};
  const std::array<const Spectrum*, 3> leak{&film.tau_m, &source, &response};
  const double M = integrate_product(pass, lo, hi);
  const double m = tau_m_scale * integrate_product(leak, lo, hi);
  if (!(M + m > 0))
    throw SpectrumError(fmt::format("the source ({}) seen through the films and {} gives no "
                                    "signal over [{}, {}] nm", source.name(), response.name(),
                                    lo, hi));
  return {(M - m) / (M + m)};
}

}  // namespace polrig
