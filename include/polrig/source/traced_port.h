#pragma once
// Light below the port of a traced sphere: the Stokes irradiance that the port, seen through its
// polarizer film, casts on a plane L_o below it (design.md, "The traced source").
//
// E(P) = ∫_port L(W(Q)) · cos θ_P · cos θ_Q / |Q − P|² dA_Q, with W(Q) the first surface seen
// from P through the port point Q (the wall, a baffle or a lamp) and L its radiance from the
// sphere solve. Both cosines are (z_Q − z_P)/|Q − P|. The film turns unpolarized radiance L into
// Stokes L·(g_up, g_tp·cos 2ψ, g_tp·sin 2ψ), g_up = (τM + τm)/2, g_tp = (τM − τm)/2, ψ its axis
// (normal incidence; the oblique-incidence correction is not modelled yet).
//
// Port points are a randomly shifted rank-1 lattice (quasi-random) mapped to the disk; the same
// points serve every P, so differences between nearby points are nearly free of sampling noise.
// Standard errors come from independent random shifts.
#include "polrig/source/sphere_tracer.h"

namespace polrig {

struct StokesIrradiance {
  double S0 = 0, S1 = 0, S2 = 0;           // W/m², lab frame (x, y)
  double S0_se = 0, S1_se = 0, S2_se = 0;  // standard errors
};

class TracedPort {
 public:
  TracedPort(const SphereTracer& tracer, const SphereSolution& solution);

  // At (x, y) on the plane L_o below the port plane, with `samples` port points per shift and
  // `shifts` independent shifts.
  StokesIrradiance plane_irradiance(double x, double y, double L_o, long long samples,
                                    int shifts) const;
  // One shift's estimate alone (no standard error): shift k is the same set of port points
  // wherever it is evaluated.
  //
  // With L_ref > 0 the uniform part is integrated exactly (disk_irradiance) and only L − L_ref is
  // sampled (a control variate): for a nearly uniform port the sampling error shrinks by
  // |L − L_ref|/L and varies smoothly from point to point.
  StokesIrradiance plane_irradiance_shift(double x, double y, double L_o, long long samples,
                                          int shift, double L_ref = 0) const;

 private:
  const SphereTracer& tracer_;
  const SphereSolution& solution_;
};

// The exact irradiance below a uniform Lambertian disk of radiance L and radius a, at height h
// and offset r (design.md): E = π·L·½·[1 − (h² + r² − a²)/√((h² + r² + a²)² − 4a²r²)].
double disk_irradiance(double L, double a, double h, double r);

}  // namespace polrig
