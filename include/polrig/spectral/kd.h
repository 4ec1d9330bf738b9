#pragma once
// `polrig spectral kd`'s values: each channel's effective degree and kd under the lamp and under
// the sky, and the spectra a user looks at. Values only; reading the CSVs is io/spectrum_csv's.
#include <string>
#include <vector>

#include "polrig/spectral/effective_degree.h"
#include "polrig/spectral/spectrum.h"

namespace polrig {

// One channel: its leakage scale s and its effective degree under each source.
struct ChannelKd {
  double tau_m_scale = 1;
  EffectiveDegree lamp, sky;
  double kd_sky_minus_lamp() const { return sky.kd() - lamp.kd(); }
};
// effective_degree under both sources (its SpectrumError for this channel otherwise).
ChannelKd channel_kd(const FilmSpectra& film, const Spectrum& lamp, const Spectrum& sky,
                     const Spectrum& response, double tau_m_scale);

// On a 1 nm grid over the response's band (from ceil(min) in 1 nm steps, then the band's end):
// the films, their single-wavelength degree (τM − τm)/(τM + τm) (NaN where τM + τm = 0), R, and
// each source's S·R normalised to its largest value on the grid.
struct KdSpectra {
  std::vector<double> wavelength_nm, tau_M, tau_m, film_d, response, lamp_weight, sky_weight;
};
KdSpectra kd_spectra(const FilmSpectra& film, const Spectrum& response, const Spectrum& lamp,
                     const Spectrum& sky);

// `polrig spectral kd` on spectra already read: the lamp a blackbody at lamp_K over the response's
// band, the sky the Rayleigh-scattered `sun` (sunlight × λ⁻⁴); one ChannelKd per entry of
// tau_m_scale, and the spectra.
struct SpectralKd {
  std::vector<ChannelKd> channels;
  KdSpectra spectra;
};
// How the caller's user named the inputs, for the messages: the CLI "--films PATH", "--sun PATH",
// "--tau-m-scale"; Python "films PATH", "sun PATH", "tau_m_scale".
struct SpectralKdNames {
  std::string films, sun, tau_m_scale;
};
// Throws SpectrumError "NAME: its wavelengths [a, b] nm do not cover the response's [c, d] nm"
// when the films or the sun do not span the response's band, and "channel c (SCALE s): ..." for
// a channel effective_degree refuses.
SpectralKd spectral_kd(const FilmSpectra& film, const Spectrum& response, double lamp_K,
                       const Spectrum& sun, const std::vector<double>& tau_m_scale,
                       const SpectralKdNames& names);

}  // namespace polrig
