#include "polrig/spectral/effective_degree.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include <fmt/format.h>

namespace polrig {

EffectiveDegree effective_degree(const FilmSpectra& film, const Spectrum& source,
                                 const Spectrum& response, double tau_m_scale) {
  if (!(std::isfinite(tau_m_scale) && tau_m_scale > 0 && tau_m_scale <= 1e3))
    throw SpectrumError(fmt::format("tau_m scale {}: expected (0, 1000]", tau_m_scale));
  const double lo = response.min_nm(), hi = response.max_nm();
  // Both films are linear between their samples, so s·τm ≤ τM holds everywhere on the band iff
  // it holds at every sample of either grid (and at the band's ends) where both are defined.
  std::vector<double> nm{lo, hi};
  for (const Spectrum* f : {&film.tau_m, &film.tau_M})
    nm.insert(nm.end(), f->wavelength_nm().begin(), f->wavelength_nm().end());
  std::sort(nm.begin(), nm.end());
  nm.erase(std::unique(nm.begin(), nm.end()), nm.end());
  for (const double x : nm)
    if (x >= lo && x <= hi && film.tau_m.covers(x, x) && film.tau_M.covers(x, x) &&
        tau_m_scale * film.tau_m(x) > film.tau_M(x))
      throw SpectrumError(fmt::format("{} x {} = {} exceeds {} = {} at {} nm: the leakage "
                                      "cannot exceed the pass transmittance", film.tau_m.name(),
                                      tau_m_scale, tau_m_scale * film.tau_m(x),
                                      film.tau_M.name(), film.tau_M(x), x));
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
