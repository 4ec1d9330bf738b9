#pragma once
// Single-scattering Rayleigh sky (spec sky-and-compasses.md §1.2): the E-vector, degree and angle
// of linear polarization, and the radiance models, for a viewing direction v and the sun s, both
// unit vectors in ENU (x east, y north, z up).
#include <utility>
#include <vector>

#include "polrig/vec3.h"

namespace polrig {

enum class SkyRadiance { Uniform, Rayleigh, CieClear };

// P_max: a constant, or a table P_max(h_s) over the sun's elevation (degrees), interpolated
// linearly and held constant beyond its ends.
struct MaxDegree {
  double constant = 0.70;
  std::vector<std::pair<double, double>> table;  // (h_s in degrees, P_max), rising h_s
  double at(double sun_elevation_deg) const;
};

struct SkyModel {
  MaxDegree P_max;
  SkyRadiance radiance = SkyRadiance::Uniform;
};

// What the sky sends along −v (light arriving from direction v).
struct SkyLight {
  double radiance = 1;   // relative: 1 for `uniform`, the model's value otherwise
  double dop = 0;        // P(γ) = P_max·sin²γ/(1 + cos²γ)
  double aop_deg = 0;    // χ, in the local meridian frame of v (from e_θ towards e_φ), [0°, 180°)
  Vec3 e_vector{};       // e = (s × v)/|s × v|, ENU; zero where undefined (γ = 0° or 180°)
  double S0() const { return radiance; }
};

// s: unit vector to the sun; v: unit viewing direction; h_s: the sun's elevation (for P_max(h_s)).
SkyLight sky_light(const Vec3& s, const Vec3& v, const SkyModel& model);

}  // namespace polrig
