#pragma once
// The diffuse polarized sky of a plane-parallel Rayleigh atmosphere over a Lambertian ground, by
// adding–doubling per Fourier term in azimuth (spec skies.md §2; de Haan, Bosma & Hovenier 1987;
// Hansen & Travis 1974 §3.2). Directions off the quadrature are carried through the doubling as
// rows of zero weight, so their radiances are as exact as the quadrature's, not interpolated.
#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "polrig/sky/aerosol.h"

namespace polrig {

// Aerosol mixed evenly with the air through the one layer (spec skies.md §2 "Aerosols";
// docs/physics.md §24). Its phase matrix is truncated by δ-M at l = streams/2 − 1 and the
// once-scattered sky is then put back exactly (the single-scattering correction).
struct AerosolSettings {
  double tau = 0;                                 // optical depth, [0, 100]; 0: no aerosol
  double ssa = 1;                                 // single-scattering albedo ϖ_a, (0, 1]
  std::shared_ptr<const PhaseMatrixTable> phase;  // needed when tau > 0
};

struct VectorRtSettings {
  double tau_rayleigh = 0.1;      // total optical depth, > 0
  double depolarization = 0.0279; // ρ of air, [0, 0.5)
  double ground_albedo = 0;       // Lambertian, [0, 1]
  int streams = 32;               // discrete ordinates over both hemispheres (even, 4..128)
  AerosolSettings aerosol;
  // The sun's direct beam through the layer: false, plane-parallel (air mass 1/μ₀, the exact
  // tables' geometry); true, pseudo-spherical (chapman_air_mass: the beam crosses spherical
  // shells; the scattering and the views stay plane-parallel).
  bool pseudo_spherical = false;
};

// The lowest sun the settings' sky takes, degrees: 2° plane-parallel (its air mass 1/μ₀ is 45 %
// above the real one there, Kasten & Young 1989), 1° pseudo-spherical (below it the sun's disk,
// 0.53°, and the refraction at the horizon, ~0.5°, move the beam by their own size: the path then
// depends on the refraction and the air's profile, which one homogeneous layer does not have).
double min_sun_elevation_deg(const VectorRtSettings& s);

// The air mass of a beam at cos zenith mu0 ∈ [0, 1] through an exponential atmosphere of scale
// height H = 8 km over a sphere of radius R = 6371 km (the Chapman function Ch(R/H, θ₀), Chapman
// 1931): m = (1/H)∫₀^∞ e^{−h/H} ds along the slanted ray, by Simpson's rule in x = √(h/H), where
// the integrand is smooth even at the horizon. 1/μ₀ for a high sun, √(πR/2H) ≈ 35.4 at the horizon.
double chapman_air_mass(double mu0);

// Throws std::invalid_argument naming the value of the first setting outside its range, an
// aerosol without its phase matrix, or streams too few for it (its δ-M truncation negative at
// some scattering angle: not a phase function).
void check_vector_rt(const VectorRtSettings& s);

// The once-scattered diffuse sky at the ground under the settings' layer with its aerosol's phase
// matrix untruncated (no ground), as the single-scattering correction (Nakajima & Tanaka 1988,
// "TMS") adds it to the δ-M solution: the scattering τϖP of the real layer, the extinction τ' of
// the δ-M layer (the light of the forward peak travels on with the beam):
// I = (τϖP·Z rotated)(1, 0, 0, 0)ᵀ/(4πμτ')·∫₀^τ' e^{−t/μ₀ − (τ'−t)/μ} dt, in polrig's view frame
// (as DiffuseField), L/E₀. Without an aerosol τ' = τ and this is the exact once-scattered sky.
class SingleScatteringSky {
 public:
  explicit SingleScatteringSky(const VectorRtSettings& s);
  Eigen::Vector4d down(double mu0, double mu, double phi) const;
  // The same with the sun beam's air mass already known (sun_air_mass(mu0)): what a sky that asks
  // for many views under one sun calls.
  Eigen::Vector4d down(double mu0, double air_mass, double mu, double phi) const;
  double sun_air_mass(double mu0) const;

 private:
  VectorRtSettings settings_;
  double extinction_tau_ = 0;
};

// The diffuse Stokes field for one sun (cosine of its zenith angle mu0, sun at relative azimuth 0)
// in chosen directions, as Fourier coefficients in the relative azimuth φ:
//   I(φ) = Σ_m I_m cos mφ, Q(φ) = Σ_m Q_m cos mφ, U(φ) = Σ_m U_m sin mφ, V(φ) = Σ_m V_m sin mφ.
// Units: radiance per unit extraterrestrial irradiance normal to the sun's beam (L/E₀, sr⁻¹).
// Frame (polrig's, sky-and-compasses.md §0): the view direction v (where the sensor looks, opposite
// to the light's travel), its meridian frame (e_θ down the meridian, e_φ towards rising math
// azimuth), χ from e_θ towards e_φ: Q = L·P·cos 2χ, U = L·P·sin 2χ. φ is the view's math azimuth
// (anticlockwise seen from above) less the sun's.
// With an aerosol, `down` holds the sky less its δ-M once-scattered part and `single` puts the
// exact once-scattered sky back in down_at; `up` is the δ-M solution's.
struct DiffuseField {
  std::vector<double> mu;  // the |cosines| of the views' zenith angles, as asked for
  // down[m][u]: the sky seen from the ground looking up at mu[u]; up[m][u]: the atmosphere seen
  // from above its top looking down at mu[u] (the reflected field).
  std::vector<std::vector<Eigen::Vector4d>> down, up;
  std::shared_ptr<const SingleScatteringSky> single;  // null without an aerosol
  double mu0 = 1;
  Eigen::Vector4d down_at(std::size_t u, double phi) const;
  Eigen::Vector4d up_at(std::size_t u, double phi) const;
};

// The atmosphere in a plot's title or a message: "tau 0.1, albedo 0" and, with an aerosol,
// ", aerosol tau 0.2, ssa 0.788".
std::string atmosphere_text(const VectorRtSettings& s);

// Solves the field for a sun at cos zenith mu0 ∈ (0, 1] and reports it at the view cosines
// `view_mu` (each in (0, 1]). Throws std::invalid_argument for settings or cosines out of range.
DiffuseField solve_vector_rt(const VectorRtSettings& s, double mu0, const std::vector<double>& view_mu);

// The diffuse fluxes for the conservation check: with the sun's irradiance E₀ = 1 normal to the
// beam, the upward flux leaving the top, the downward diffuse flux at the ground and the direct
// flux μ₀e^{−τ/μ₀} there (per unit horizontal area). With an aerosol these are the δ-M layer's:
// its direct beam carries the forward peak, e^{−τ'/μ₀}.
struct DiffuseFluxes {
  double up_top = 0, down_diffuse_bottom = 0, down_direct_bottom = 0;
};
DiffuseFluxes vector_rt_fluxes(const VectorRtSettings& s, double mu0);

// The Rayleigh optical depth of dry air (Bodhaine et al. 1999, J. Atmos. Oceanic Technol. 16,
// 1854, Eqs. 4–5, 22, 30): the refractive index of 360 ppm CO₂ air (Peck & Reeves 1962), the
// cross-section σ = 24π³(n² − 1)²/(λ⁴N_s²(n² + 2)²)·F with the King factor F = (6 + 3ρ)/(6 − 7ρ)
// of the depolarization ρ, and τ = σ·P·N_A/(m_a·g) at g = 980.616 cm s⁻² (45°, sea level).
// Throws std::invalid_argument outside 250–4000 nm, 1–1100 hPa or ρ ∈ [0, 0.5).
double rayleigh_optical_depth_bodhaine(double wavelength_nm, double pressure_hPa, double depolarization);

}  // namespace polrig
