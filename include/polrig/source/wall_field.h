#pragma once
// The wall irradiance after the first strike, computed instead of sampled.
//
// On a sphere, two wall elements see each other with cos θ·cos θ'/d² = 1/(4R²) wherever they
// are, so the light the wall sends to the wall reaches every wall point equally: a constant C.
// Only what stands inside the sphere breaks that symmetry. A baffle or a lamp hides part of the
// wall from a point W and shows its own surface instead:
//
//   E_after(W) = C + δ(W),  δ(W) = Σ_occluders ∫_{occluder seen from W} (L_occluder − L_behind) cos θ_W dω,
//
// with L_behind the radiance of the surface the occluder hides. L_behind of a wall point is
// ρ·(E_direct + C)/π: the correction's effect on itself, O(δ·Ω_occluder/π), is dropped. Baffle
// faces have the uniform radiance ρ_b·E_face/π of the photon solve; lamps reflect ρ_l·C/π (their
// emission is the first strike). C follows from energy: the wall mean of C + δ equals the photon
// solve's mean irradiance after the first strike, which the whole sphere's photons measure to
// ~1e-4; no single bin's photon noise reaches the field.
//
// δ is tabulated on a grid uniform in θ (from +z) and φ, and interpolated by Catmull–Rom splines; the
// integrals use Gauss–Legendre × trapezoid rules over each baffle's disk and each lamp's cone.
#include <vector>

#include "polrig/progress.h"
#include "polrig/source/scene.h"

namespace polrig {

class SphereTracer;
struct SphereSolution;

struct WallField {
  double C = 0;                // W/m², the uniform part
  int n_theta = 0, n_phi = 0;  // nodes θ_i = π·i/(n_theta − 1), φ_j = 2π·j/n_phi
  std::vector<double> delta;   // W/m², δ at the nodes, θ-major
  double R = 0;                // sphere radius, mm

  bool empty() const { return delta.empty(); }
  // C + δ at a point of the wall.
  double after_first_strike(const Vec3& wall_point) const;
};

// The field of a solved sphere: uses the solution's baffle irradiances and mean after-first-strike
// wall irradiance, and traces rays with `tracer`.
WallField compute_wall_field(const SphereTracer& tracer, const SphereSolution& solution,
                             int n_theta = 181, int n_phi = 360, const Progress& progress = {});

}  // namespace polrig
