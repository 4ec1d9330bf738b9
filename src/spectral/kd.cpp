#include "polrig/spectral/kd.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/format.h>

#include "polrig/spectral/sources.h"

namespace polrig {

ChannelKd channel_kd(const FilmSpectra& film, const Spectrum& lamp, const Spectrum& sky,
                     const Spectrum& response, double tau_m_scale) {
  return {tau_m_scale, effective_degree(film, lamp, response, tau_m_scale),
          effective_degree(film, sky, response, tau_m_scale)};
}

KdSpectra kd_spectra(const FilmSpectra& film, const Spectrum& response, const Spectrum& lamp,
                     const Spectrum& sky) {
  KdSpectra t;
  for (double nm = std::ceil(response.min_nm()); nm < response.max_nm(); nm += 1)
    t.wavelength_nm.push_back(nm);
  t.wavelength_nm.push_back(response.max_nm());
  double lamp_max = 0, sky_max = 0;
  for (double nm : t.wavelength_nm) {
    lamp_max = std::max(lamp_max, lamp(nm) * response(nm));
    sky_max = std::max(sky_max, sky(nm) * response(nm));
  }
  for (double nm : t.wavelength_nm) {
    const double M = film.tau_M(nm), m = film.tau_m(nm);
    t.tau_M.push_back(M);
    t.tau_m.push_back(m);
    t.film_d.push_back(M + m > 0 ? (M - m) / (M + m) : std::nan(""));  // no light passes
    t.response.push_back(response(nm));
    t.lamp_weight.push_back(lamp(nm) * response(nm) / lamp_max);
    t.sky_weight.push_back(sky(nm) * response(nm) / sky_max);
  }
  return t;
}

SpectralKd spectral_kd(const FilmSpectra& film, const Spectrum& response, double lamp_K,
                       const Spectrum& sun, const std::vector<double>& tau_m_scale,
                       const SpectralKdNames& names) {
  const double lo = response.min_nm(), hi = response.max_nm();
  const auto check_covers = [&](const Spectrum& s, const std::string& name) {
    if (!s.covers(lo, hi))
      throw SpectrumError(fmt::format("{}: its wavelengths [{}, {}] nm do not cover the response's "
                                      "[{}, {}] nm", name, s.min_nm(), s.max_nm(), lo, hi));
  };
  check_covers(film.tau_M, names.films);
  check_covers(film.tau_m, names.films);
  const Spectrum lamp = blackbody(lamp_K, lo, hi);
  check_covers(sun, names.sun);
  const Spectrum sky = rayleigh_sky(sun);
  SpectralKd out;
  for (std::size_t c = 0; c < tau_m_scale.size(); ++c) {
    try {
      out.channels.push_back(channel_kd(film, lamp, sky, response, tau_m_scale[c]));
    } catch (const SpectrumError& e) {
      throw SpectrumError(fmt::format("channel {} ({} {}): {}", c + 1, names.tau_m_scale,
                                      tau_m_scale[c], e.what()));
    }
  }
  out.spectra = kd_spectra(film, response, lamp, sky);
  return out;
}

}  // namespace polrig
