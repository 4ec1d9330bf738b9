#pragma once
// Single-scattering Rayleigh sky (spec sky-and-compasses.md §1.2): the E-vector, degree and angle
// of linear polarization, and the radiance models, for a viewing direction v and the sun s, both
// unit vectors in ENU (x east, y north, z up).
#include <memory>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include "polrig/optics/polarizer.h"
#include "polrig/vec3.h"

namespace polrig {

// Radiance models, each relative to the zenith's radiance (L = 1 there):
//   uniform:   L = 1;
//   rayleigh:  L = (1 + cos²γ)/(1 + cos²θ_s);
//   cie-clear: CIE standard general sky type 12 (ISO 15469 / CIE S 011/E:2003, "CIE standard clear
//              sky, low luminance turbidity": gradation group 5, a = −1, b = −0.32; indicatrix
//              group 4, c = 10, d = −3, e = 0.45): L = f(γ)·φ(Z)/(f(Z_s)·φ(0)) with
//              φ(Z) = 1 + a·exp(b/cos Z), f(γ) = 1 + c·(exp(dγ) − exp(dπ/2)) + e·cos²γ, Z the
//              view's zenith angle (φ = 1 at and below the horizon), Z_s the sun's.
enum class SkyRadiance { Uniform, Rayleigh, CieClear };
// The names of the rig key sky.radiance, the CLI's --radiance and Python's radiance=:
// "uniform", "rayleigh", "cie-clear".
std::string_view sky_radiance_name(SkyRadiance r);
std::optional<SkyRadiance> parse_sky_radiance(std::string_view name);

// P_max: a constant, or a table P_max(h_s) over the sun's elevation (degrees), interpolated
// linearly and held constant beyond its ends.
struct MaxDegree {
  double constant = 0.70;
  std::vector<std::pair<double, double>> table;  // (h_s in degrees, P_max), rising h_s
  double at(double sun_elevation_deg) const;
};


// What the sky is made of (the rig key sky.model): single scattering with one P_max and a
// radiance model (this file); the exact polarized Rayleigh sky of a plane-parallel atmosphere
// (sky/vector_rt_sky.h), whose radiance, DoP and AoP all come from the solution; or Berry's sky
// (sky/berry.h): its E-vector pattern with four neutral points, its DoP P_max·|w|/(2 − |w|) and
// single scattering's radiance models.
enum class SkyKind { SingleScattering, VectorRt, Berry };
// "single-scattering", "vector-rt", "berry".
std::string_view sky_kind_name(SkyKind k);
std::optional<SkyKind> parse_sky_kind(std::string_view name);

class VectorRtSky;
class SunField;
class BerryField;
class BerryFit;

// Berry's two distances (degrees along the solar meridian): each a number, or empty for the fit
// to the vector-RT sky at the sun's elevation (`fit`: sky/berry_fit.h).
struct BerrySkySettings {
  std::optional<double> babinet_deg, brewster_deg;
  std::shared_ptr<const BerryFit> fit;  // set when either distance is fitted
};

struct SkyModel {
  MaxDegree P_max;                            // single scattering
  SkyRadiance radiance = SkyRadiance::Uniform;  // single scattering
  SkyKind kind = SkyKind::SingleScattering;
  std::shared_ptr<const VectorRtSky> vector_rt;  // kind VectorRt: the solved sky (vector_rt_sky())
  BerrySkySettings berry;                        // kind Berry (with P_max and radiance)
};

// The lowest sun the model takes, degrees: VectorRtSky::kMinSunElevationDeg for the vector-RT sky
// and for Berry's sky with a fitted distance, −90° otherwise.
double min_sun_elevation_deg(const SkyModel& model);

// Throws std::invalid_argument naming the value: P_max outside (0, 1], a table not rising in h_s,
// or a non-finite entry.
void check_sky_model(const SkyModel& model);

// What the sky sends along −v (light arriving from direction v).
struct SkyLight {
  double radiance = 1;   // relative: 1 for `uniform`, the model's value otherwise
  double dop = 0;        // P(γ) = P_max·sin²γ/(1 + cos²γ)
  double aop_deg = 0;    // χ, in the local meridian frame of v (from e_θ towards e_φ), [0°, 180°)
  Vec3 e_vector{};       // e = (s × v)/|s × v|, ENU; zero where undefined (γ = 0° or 180°)
  double S0() const { return radiance; }
};

// s: unit vector to the sun; v: unit viewing direction, both ENU. The sun's elevation for
// P_max(h_s) is asin(s_z). The sun below the horizon still defines DoP and AoP.
SkyLight sky_light(const Vec3& s, const Vec3& v, const SkyModel& model);

// What the sky sends along −v without the angle χ (which needs v's meridian frame): what a camera
// pixel needs, that takes the E-vector into its own frame.
struct SkyRay {
  double radiance = 1;
  double dop = 0;
  Vec3 e_vector{};        // zero where undefined (sin γ = 0)
  double sin_gamma = 0;   // |s × v|
};

// One sun's sky along many views: P_max(h_s), or the vector-RT sky's field for this sun, found
// once. Each ray's radiance, dop and e_vector are sky_light's bit for bit (sky_light is built on
// it). Under the vector-RT sky the radiance is relative to the zenith's diffuse radiance (as every
// radiance model's is), views below the horizon see the horizon's light, and a sun below
// VectorRtSky::kMinSunElevationDeg throws std::invalid_argument. Under Berry's sky the DoP is
// berry_dop(|w|, P_max(h_s)) and the E-vector Berry's; its fitted distances refuse the same suns.
class SunSky {
 public:
  SunSky(const Vec3& s, const SkyModel& model);
  SkyRay along(const Vec3& v) const;
  // The diffuse radiance L/E₀ (sr⁻¹, per unit irradiance normal to the sun's beam) and Q, U in v's
  // meridian frame (polrig's χ): the vector-RT sky's absolute Stokes vector; empty for a
  // single-scattering sky, which has no absolute scale.
  std::optional<Stokes> absolute_stokes(const Vec3& v) const;

 private:
  Vec3 s_;
  double P_max_;
  SkyRadiance radiance_;
  std::shared_ptr<const SunField> field_;  // the vector-RT sky for this sun
  std::shared_ptr<const BerryField> berry_;  // Berry's sky for this sun
  std::pair<double, double> sun_azimuth_{1, 0};  // cos, sin of the sun's math azimuth
};

// The same for many views under one sun (what a map or a table of views calls).
SkyLight sky_light(const SunSky& sky, const Vec3& v);

// The local meridian frame of v = (sin θ cos φ, sin θ sin φ, cos θ), φ the math azimuth
// (anticlockwise from east seen from above, φ = 90° − A): e_θ = ∂v/∂θ points down the meridian
// (towards the horizon), e_φ = ẑ × v/|ẑ × v| along the almucantar towards rising φ. At the zenith,
// where φ is undefined, φ = 0: e_θ = east, e_φ = north, so there χ is the E-vector's math angle.
void meridian_frame(const Vec3& v, Vec3& e_theta, Vec3& e_phi);

// The Stokes vector (S0, S1, S2, 0) with reference axis e_θ, angles from e_θ towards e_φ:
// S1 = L·P·cos 2χ, S2 = L·P·sin 2χ (spec §1.2).
Stokes sky_stokes(const SkyLight& light);

}  // namespace polrig
