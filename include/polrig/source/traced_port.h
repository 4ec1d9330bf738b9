#pragma once
// Light below the port of a traced sphere: the irradiance the port casts on a point P of a
// plane h below it (design.md, "The traced source"),
//
//   E(P) = ∫_port L(W(Q)) · T(k) · cos θ_P · cos θ_Q / |Q − P|² dA_Q,
//
// with W(Q) the first surface seen from P through the port point Q, L its radiance from the
// sphere solve, k the direction the light travels (from Q to P) and T(k) the transmission of
// whatever films the caller puts in its way (1 for bare radiometry). Both cosines are
// (z_Q − z_P)/|Q − P|.
//
// The integral is split so that its sampled part is smooth:
//   1. the wall alone, as if nothing stood in the sphere: L_wall along every ray. Its uniform
//      part L_ref is integrated by a fixed Gauss rule over the port (exact to ~1e-10), the
//      rest, (L_wall − L_ref)·T·G, by quasi-random port points: a randomly shifted rank-1
//      lattice, the same points for every P, so differences between nearby points are nearly
//      free of sampling noise; independent shifts give standard errors;
//   2. each baffle and lamp, by a fixed rule over its disk or its cone of directions: where it is
//      the first surface seen through the port, its radiance replaces the wall's. Its outline
//      would otherwise be a jump in the sampled integrand that the points cross differently at
//      every P.
#include <functional>
#include <vector>

#include "polrig/source/sphere_tracer.h"

namespace polrig {

// Transmission along a ray that travels in unit direction k (downwards, out of the port).
using RayTransmission = std::function<double(const Vec3& k)>;

struct StokesIrradiance {
  double S0 = 0, S1 = 0, S2 = 0;           // W/m², lab frame (x, y)
  double S0_se = 0, S1_se = 0, S2_se = 0;  // standard errors
};

class TracedPort {
 public:
  // L_ref: the uniform radiance of part 1 (typically the port's mean radiance).
  TracedPort(const SphereTracer& tracer, const SphereSolution& solution, double L_ref = 0);

  // E(P) at (x, y) on the plane h below the port plane, one value per shift k = 0 … shifts − 1
  // of `samples` quasi-random port points (shift k is the same set of points wherever it is
  // evaluated); the fixed-rule parts are shared by all shifts.
  std::vector<double> irradiance(double x, double y, double h, const RayTransmission& T,
                                 long long samples, int shifts) const;
  // The same for several transmissions at one point, [transmission][shift]: the rays, the
  // radiance along them and their geometry are computed once for all. Each value is bit-identical
  // to irradiance() with that transmission alone.
  std::vector<std::vector<double>> irradiance(double x, double y, double h,
                                              const std::vector<RayTransmission>& Ts,
                                              long long samples, int shifts) const;

  // The Stokes irradiance on the plane, through the port film, with standard errors from
  // `shifts` shifts. S0 is the irradiance; S1 and S2 are what ideal sheet analyzers lying in the
  // plane measure, S1 = E(0°) − E(90°), S2 = E(45°) − E(135°) (at oblique incidence the four
  // analyzers do not add up to S0 exactly).
  StokesIrradiance plane_stokes(double x, double y, double h, long long samples, int shifts) const;

  // The parts of irradiance(), for tests and reports.
  double uniform_part(const Vec3& P, const RayTransmission& T) const;
  double sampled_part(const Vec3& P, const RayTransmission& T, long long samples, int shift) const;
  std::vector<double> sampled_parts(const Vec3& P, const std::vector<RayTransmission>& Ts,
                                    long long samples, int shift) const;
  double occluder_part(const Vec3& P, const RayTransmission& T) const;
  // The fixed-rule parts for several transmissions at once (rays and radiance shared).
  std::vector<double> uniform_parts(const Vec3& P, const std::vector<RayTransmission>& Ts) const;
  std::vector<double> occluder_parts(const Vec3& P, const std::vector<RayTransmission>& Ts) const;

 private:
  double wall_radiance_along(const Vec3& Q, const Vec3& up) const;

  const SphereTracer& tracer_;
  const SphereSolution& solution_;
  double L_ref_ = 0;
};

// The port's mean radiance as seen from h below its centre, E(0)/F(0) with F the disk's view
// factor: the L_ref that makes TracedPort's sampled part small.
double mean_port_radiance(const SphereTracer& tracer, const SphereSolution& solution, double h);

// The exact irradiance below a uniform Lambertian disk of radiance L and radius a, at height h
// and offset r (design.md): E = π·L·½·[1 − (h² + r² − a²)/√((h² + r² + a²)² − 4a²r²)].
double disk_irradiance(double L, double a, double h, double r);

}  // namespace polrig
