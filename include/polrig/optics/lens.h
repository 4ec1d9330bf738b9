#pragma once
// A plano-convex lens traced exactly (Snell's law at both surfaces, Fresnel transmission for
// unpolarized light). Frame: the lens axis along z; the convex surface faces +z (towards the
// port), its vertex at z = thickness; the plane face at z = 0 faces the photodiode below.
#include <array>
#include <optional>

namespace polrig {

struct PolarizedRay;

struct PlanoConvexLens {
  double radius_of_curvature;  // R > 0
  double thickness;            // centre thickness
  double diameter;
  double index;                // refractive index n

  // R from the thin-lens focal length: f = R/(n − 1) (lensmaker's equation, one flat side).
  static PlanoConvexLens from_focal_length(double f, double thickness, double diameter, double n);
  // Paraxial back focal length behind the plane face for light from +z: f − t/n.
  double back_focal_length() const;
};

struct LensRay {
  std::array<double, 3> origin, direction;  // direction of unit length
  double transmittance = 1;                 // product of the Fresnel transmittances
};

// Traces a ray through the lens in either direction; nothing when it misses the aperture or is
// totally internally reflected.
std::optional<LensRay> trace_through(const PlanoConvexLens& lens, const LensRay& in);
// The same trace (identical result), carrying `polarization` through both faces with refract()
// when it is not null; its k must equal in.direction (std::invalid_argument otherwise; x_hat is
// re-orthogonalised to in.direction). On success polarization->k is the output direction and
// S0 has been multiplied by the polarized Fresnel transmittances; otherwise it is left unchanged.
// For unpolarized input S0 differs from `transmittance` (which depolarizes between the faces) by
// ¼(T_p1 − T_s1)(T_p2 − T_s2) for a meridional ray: the first face's partial polarization.
std::optional<LensRay> trace_through(const PlanoConvexLens& lens, const LensRay& in,
                                     PolarizedRay* polarization);

// Fresnel power transmittance for unpolarized light from index n1 to n2 at incidence cos θ_i.
double fresnel_transmittance(double n1, double n2, double cos_i);

}  // namespace polrig
