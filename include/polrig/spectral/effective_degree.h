#pragma once
// The effective degree of a channel's film under a source, and hence its kd (Eq. 15):
//
//   d_eff = ∫ (τM − s·τm)·S·R dλ / ∫ (τM + s·τm)·S·R dλ,       kd = d_eff − 1
//
// τM, τm: the film's transmittance along and across its axis; S: the source's spectrum; R: the
// shared blue filter × photodiode responsivity; s: a per-channel scale of the film's leakage
// (films of one sheet differ: Table 2's six kd differ). The integral runs over R's samples: R
// sets the band, and films and source must cover it. At one wavelength d_eff is
// sensor-and-rig.md §4's (τM − τm)/(τM + τm); the channel's photocurrent is
// ∫ S·R·[(τM + τm) + (τM − τm)·d·cos 2(θ − α)]/2 dλ, so for a source whose degree d does not
// depend on λ, Eq. 15's (1 + kd) is this ratio of integrals.
#include "polrig/spectral/spectrum.h"

namespace polrig {

struct FilmSpectra {
  Spectrum tau_M;  // along the axis
  Spectrum tau_m;  // across it
};

struct EffectiveDegree {
  double d_eff = 0;
  double kd() const { return d_eff - 1; }
};

// Throws SpectrumError when a film or the source does not cover R's samples, when the scaled
// leakage exceeds the pass transmittance (s·τm > τM at a film sample inside the band), when
// tau_m_scale is not in (0, 1e3], or when the weighted transmittance ∫(τM + s·τm)·S·R is zero.
EffectiveDegree effective_degree(const FilmSpectra& film, const Spectrum& source,
                                 const Spectrum& response, double tau_m_scale = 1.0);

}  // namespace polrig
