#pragma once
// Source spectra for the spectral model: a blackbody (the integrating sphere's tungsten lamp)
// and single-scattering Rayleigh skylight (sunlight weighted by λ⁻⁴).
#include "polrig/spectral/spectrum.h"

namespace polrig {

// CIE standard illuminant A, the tungsten-filament reference: a Planckian radiator at 2856 K
// (CIE 15:2004; defined with c2 = 1.435e-2 m·K, which with today's c2 = 1.438777e-2 m·K is the
// same spectrum at about 2863.5 K — polrig uses today's constants at the temperature given).
inline constexpr double kIlluminantA_K = 2856.0;
// The Sun's effective temperature, for a blackbody stand-in of the solar spectrum.
inline constexpr double kSunBlackbody_K = 5778.0;
// The temperatures the model accepts (a lamp filament to a hot star).
inline constexpr double kMinTemperature_K = 500.0, kMaxTemperature_K = 50000.0;

// Planck's law, spectral radiance per unit wavelength:
//   B_λ(λ, T) = 2hc² / λ⁵ / (exp(hc / (λ k_B T)) − 1)      in W·m⁻²·sr⁻¹·nm⁻¹
// (CODATA 2018 exact h, c, k_B). std::invalid_argument outside λ > 0 or the temperature range.
double planck_radiance(double wavelength_nm, double temperature_K);

// B_λ(·, T) sampled on [lo_nm, hi_nm] every step_nm (the last step may be shorter; both ends
// are samples). Linear interpolation departs from Planck's curve by a relative h²/8·B''/B:
// at 2856 K and 320 nm, 1.1e-4 for 1 nm samples and 1.1e-6 for the default 0.1 nm, which
// moves d_eff by < 1e-9 (docs/validation.md).
Spectrum blackbody(double temperature_K, double lo_nm, double hi_nm, double step_nm = 0.1);

// Single-scattering Rayleigh skylight: the sunlight at each of `sun`'s samples times
// (550 nm / λ)⁴ (the Rayleigh cross-section's λ⁻⁴; relative units, normalised to the sun at
// 550 nm). Leaves out the sunlight's extinction on its way to the scattering air (other than
// whatever `sun` already carries), the λ-dependence of the refractive index and of the
// depolarisation factor, multiple scattering and aerosols (docs/physics.md).
Spectrum rayleigh_sky(const Spectrum& sun);

}  // namespace polrig
