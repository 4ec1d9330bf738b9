#pragma once
// Berry's sky (Berry, Dennis & Lee 2004, New J. Phys. 6, 162; spec skies.md §3; docs/physics.md
// §22): an analytic E-vector pattern with the four neutral points of real skies. Babinet and
// Brewster lie on the solar meridian δ_Ba above and δ_Br below the sun; Arago and the fourth point
// are their antipodes. In the stereographic coordinate ζ = tan(θ/2)·e^{iφ} (θ the zenith angle, φ
// the math azimuth; the projection from the nadir onto the horizontal plane, x east, y north)
//
//     w(ζ) = −4 (ζ − ζ_Ba)(ζ − ζ_Br)(ζ + 1/ζ_Ba*)(ζ + 1/ζ_Br*) /
//            [(1 + |ζ|²)² |ζ_Ba + 1/ζ_Ba*| |ζ_Br + 1/ζ_Br*|],
//
// whose modulus is sin α·sin β (α, β the view's angular distances from Babinet and Brewster), and
// the E-vector makes the angle ψ = ½ arg w − φ_s with the plane's x axis (the projection is
// conformal, so ψ is the angle on the sky too). When the two points meet at the sun (δ = 0) the
// pattern is single scattering's, e ⊥ the scattering plane and |w| = sin²γ.
#include <array>
#include <complex>

#include "polrig/vec3.h"

namespace polrig {

// The two distances, degrees along the solar meridian, each in [0°, 90°).
struct BerryDistances {
  double babinet_deg = 0, brewster_deg = 0;
};

// Berry's field under one sun.
class BerryField {
 public:
  // s: unit vector to the sun (ENU). Throws std::invalid_argument for a distance outside
  // [0°, 90°) or non-finite, or Brewster at or beyond the nadir (θ_s + δ_Br ≥ 179°).
  BerryField(const Vec3& s, const BerryDistances& d);

  // w·e^{−2iφ_s} at the view v (unit, ENU): its modulus is |w|, half its argument the E-vector's
  // angle ψ in the stereographic plane. Written with (1 + ζ_p*·ζ)e^{iφ_s}/(1 + |ζ_p|²) in place
  // of (ζ + 1/ζ_p*)/|ζ_p + 1/ζ_p*| (equal for ζ_p on the sun's side of the zenith), so that the
  // field stays continuous as Babinet passes over the zenith (a high sun).
  std::complex<double> w(const Vec3& v) const;

  struct Polarization {
    double w_abs = 0;  // |w| = sin α·sin β ∈ [0, 1]
    Vec3 e_vector{};   // unit, tangent to the sky at v; zero at a neutral point or the nadir
  };
  Polarization at(const Vec3& v) const;

  // Unit vectors (ENU) of Babinet, Brewster, Arago (Brewster's antipode) and the fourth point
  // (Babinet's antipode).
  std::array<Vec3, 4> neutral_points() const { return points_; }

 private:
  std::complex<double> zeta_Ba_, zeta_Br_;
  double norm_ = 1;  // 1/((1 + |ζ_Ba|²)(1 + |ζ_Br|²))
  std::array<Vec3, 4> points_;
};

// Berry's DoP: P_max·|w|/(2 − |w|), single scattering's P_max·sin²γ/(1 + cos²γ) when the neutral
// points meet at the sun (Berry's paper leaves the scale free: docs/physics.md §22).
double berry_dop(double w_abs, double P_max);

}  // namespace polrig
