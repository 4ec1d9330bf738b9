#pragma once
// The scattering matrix of a mirror-symmetric medium of randomly oriented scatterers, and the
// phase matrix it gives between two directions, each Stokes vector in its own meridian frame
// (spec skies.md §2; Hovenier, van der Mee & Domke 2004 §2.7).
#include <Eigen/Core>

#include "polrig/vec3.h"

namespace polrig {

// The six independent elements at one scattering angle Θ, in the scattering plane frame
// (Q = I_l − I_r, l in the scattering plane, (l, r, k) right-handed):
//     | a1  b1  0   0  |
//     | b1  a2  0   0  |
//     | 0   0   a3  b2 |
//     | 0   0  −b2  a4 |
// normalised so that a1 averages 1 over the sphere (½∫a1 dcosΘ = 1).
struct ScatteringElements {
  double a1 = 0, a2 = 0, a3 = 0, a4 = 0, b1 = 0, b2 = 0;
  Eigen::Matrix4d matrix() const;
};

// Rayleigh scattering with the depolarization factor ρ (Hansen & Travis 1974 Eq. 2.15):
// Δ = (1 − ρ)/(1 + ρ/2), Δ' = (1 − 2ρ)/(1 − ρ), and with c = cos Θ
//   a1 = Δ·¾(1 + c²) + (1 − Δ),  a2 = Δ·¾(1 + c²),  b1 = −Δ·¾(1 − c²),
//   a3 = Δ·¾·2c,                 a4 = Δ·Δ'·¾·2c,     b2 = 0.
ScatteringElements rayleigh_elements(double cos_theta, double depolarization);

// The propagation direction of cosine mu (mu > 0 upward, z up) and math azimuth phi:
// k = (√(1 − μ²) cos φ, √(1 − μ²) sin φ, μ), with its meridian frame e_θ = ∂k/∂θ and
// e_φ = (−sin φ, cos φ, 0), so that (e_θ, e_φ, k) is right-handed; at μ = ±1 the frame still
// follows φ. A Stokes vector of light travelling along k has Q > 0 along e_θ and U > 0 along
// (e_θ + e_φ)/√2 (the polarization angle from e_θ towards e_φ).
struct Direction {
  Vec3 k, e_theta, e_phi;
};
Direction direction(double mu, double phi);

// Z = L(ψ_out)·P(Θ)·L(ψ_in): the Stokes vector of light travelling along `in` (in its meridian
// frame) scattered into `out` (in its meridian frame); `P` holds the elements at
// cos Θ = in.k·out.k. L(ψ) takes a Stokes vector into a frame whose first axis lies at ψ from the
// old one, towards the old second axis (stokes_rotation). In the forward and backward directions,
// where the scattering plane is undefined, any plane through k gives the same Z.
Eigen::Matrix4d phase_matrix(const Direction& in, const Direction& out, const ScatteringElements& P);

// L(ψ): Q' = Q cos 2ψ + U sin 2ψ, U' = −Q sin 2ψ + U cos 2ψ.
Eigen::Matrix4d stokes_rotation(double psi);

}  // namespace polrig
