#pragma once
// Polarization ray tracing with Stokes vectors in an explicit transverse frame per ray, rotated
// onto each element's eigenframe before its Mueller matrix (Chipman, Lam & Young, "Polarized
// Light and Optical Systems", CRC 2018, ch. 9–10; O-type sheet polarizer at oblique incidence:
// P. Yeh, Opt. Rev. 16, 192 (2009), "Leakage of light in LCDs").
//
// Frames. A ray's Stokes vector is referred to (x_hat, y_hat = k × x_hat): (x_hat, y_hat, k) is
// right-handed and angles run from x_hat towards y_hat. Lab-frame Stokes vectors (angles from lab
// x towards lab y, seen from +z, as linear_polarizer takes them) map as follows: a ray going up
// (k = +z) with x_hat = x has y_hat = y, the same numbers; a ray going down (k = −z) with
// x_hat = x has y_hat = −y, so S_ray = diag(1, 1, −1, −1)·S_lab (an angle ψ becomes −ψ).
#include <array>

#include "polrig/optics/polarizer.h"
#include "polrig/vec3.h"

namespace polrig {


struct PolarizedRay {
  Vec3 k;      // unit propagation direction
  Vec3 x_hat;  // unit, ⊥ k
  Stokes S;
};

// Unpolarized light along k; x_hat is the lab axis most nearly ⊥ k, made ⊥ k (lab x for k = ±z).
PolarizedRay unpolarized_ray(const Vec3& k, double S0);

// Re-expresses S in the frame whose x-axis is u projected onto the plane ⊥ k (normalised): a
// frame rotation by the angle α from x_hat to that axis about k, S' = frame_rotation(α)·S.
// Throws std::invalid_argument when u is (nearly) parallel to k.
void set_frame(PolarizedRay& ray, const Vec3& u);

// A dichroic (O-type) sheet polarizer in the plane of unit normal film_normal, transmission axis
// `axis` (unit, in that plane), power transmittances tau_M / tau_m for light polarized along /
// across the axis at normal incidence. The film absorbs along m = film_normal × axis: it passes
// the ordinary wave e_t ∝ k × m with tau_M and attenuates k × e_t with tau_m. The tau's keep
// their normal-incidence values at any incidence (no longer path through the film, no change of
// the extraordinary absorption with angle). On return x_hat = e_t. The ray must cross the film
// (k not in its plane).
void pass_sheet_polarizer(PolarizedRay& ray, const Vec3& film_normal, const Vec3& axis,
                          double tau_M, double tau_m);

// Refraction from index n1 into n2 at an interface of unit normal `normal` (either orientation):
// Snell's law for k, and the Fresnel power transmittances T_s, T_p as a diattenuator in the s/p
// frame, s = unit(k × normal). On return x_hat = s (normal to the plane of incidence, the same
// before and after), so y_hat = k_out × s is the outgoing p direction and S1 > 0 means s. At
// normal incidence (sin θ_i < 1e-9, where T_s = T_p to double precision) x_hat is kept.
// Returns false on total internal reflection, leaving the ray unchanged.
bool refract(PolarizedRay& ray, const Vec3& normal, double n1, double n2);

// Unpolarized light through two such sheet polarizers lying in one plane (unit normal
// film_normal), in closed form: the first leaves S = (a1, b1, 0, 0) on its ordinary wave e1, and
// the second passes a2·S0 + b2·S1 on its own e2, so per unit input
//   T(k) = a1·a2 + b1·b2·cos 2χ,   cos χ = e1·e2,  e_i = unit(k × (film_normal × axis_i)),
// with a = (τM + τm)/2, b = (τM − τm)/2 of each film. The same number as the two
// pass_sheet_polarizer calls, at a few per cent of their cost (no frames, no trigonometry).
class SheetPolarizerPair {
 public:
  SheetPolarizerPair(const Vec3& film_normal, const Vec3& axis1, double tau_M1, double tau_m1,
                     const Vec3& axis2, double tau_M2, double tau_m2);
  double transmittance(const Vec3& k) const;

 private:
  Vec3 m1_, m2_;  // absorption axes
  double aa_, bb_;
};

// Diattenuator along x with power transmittances T_x, T_y (no retardance).
MuellerMatrix diattenuator(double T_x, double T_y);

}  // namespace polrig
