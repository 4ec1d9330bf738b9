#pragma once
// The sun from a unit-array polarization compass (Z21 §3.2.1, Eqs. 3–8; spec sky-and-compasses.md
// §4.2; docs/physics.md §19): the E-vectors of the two units with the highest DoP, crossed. The
// units as plain numbers (their readings and their frames in the body); what reads them is
// calib/unit_array.h, their layout device/unit_array.h (compass/ includes neither).
//
// Frames: n = ENU, b = RFU (X_b right, Y_b forward, Z_b up). Unit i's frame m_i: Z_m along its
// view v, X_m its zero direction, Y_m = Z_m × X_m; C_mi^b by its columns (vec3.h's Axes3).
//
// Sense of a unit's angle (spec §0, §1.3): φ_i is the six-photodiode sensor's polarization angle,
// anticlockwise seen looking into the source from the sensor: a right-hand rotation about the
// propagation direction k = −v = −Z_m, from X_m. So φ_i runs from X_m towards k × X_m = −Y_m, and
//   E_i^m = [cos φ_i, −sin φ_i, 0]ᵀ                                         (Z21 Eq. 3, this sense)
// (Z21 prints [cos φ, sin φ, 0], which is this for an angle right-handed about the view).
//   E_i^b = C_mi^b·E_i^m                                                     (Eq. 5)
//   s^b = ±(E_i^b × E_j^b)/|E_i^b × E_j^b|, the sign with s_z^b > 0          (Eq. 6, body-frame norm)
//   A^b = atan2(s_y^b, s_x^b) (from X_b towards Y_b), H^b = asin(s_z^b)      (Eqs. 7–8)
//   s^n = C_b^n·s^b, H^n = asin(s_z^n)                                       (spec §4.2, "transforming")
#include <span>
#include <string_view>

#include "polrig/vec3.h"

namespace polrig {

// What one unit reports.
struct UnitReading {
  double aop_rad = 0;  // φ_i in its own frame m_i, the sensor's sense (the header): axial, mod π
  double dop = 0;      // degree of linear polarization
};

// A unit's frame in the body: C_mi^b by its columns (X_m, Y_m, Z_m written in b).
struct UnitMount {
  Axes3 C_mb{Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{0, 0, 1}};
};

// E^m = [cos φ, −sin φ, 0]: the E-vector of a reading in its unit's frame (the header's sense).
Vec3 unit_e_vector(double aop_rad);
// The inverse for an E-vector e in the unit's plane (e·Z_m ≈ 0): φ = atan2(−e_y, e_x) in [0, π).
double unit_aop_rad(const Vec3& e_m);

enum class UnitSunStatus {
  Ok,
  Degenerate,  // the two E-vectors within min_angle of parallel: both views in one scattering plane
  TooFewUnits  // fewer than two readings with a finite angle and a DoP > 0
};
std::string_view unit_sun_status_name(UnitSunStatus s);  // "ok", "degenerate", "too-few-units"

struct UnitSunSettings {
  // The smallest angle between the two E-vectors (axial: in [0°, 90°]) that fixes the sun; below it
  // the cross product is dominated by noise [C: 1°].
  double min_angle_deg = 1.0;
};

struct UnitSun {
  UnitSunStatus status = UnitSunStatus::TooFewUnits;
  int i = -1, j = -1;       // the units used: the highest DoP, then the next (ties: the lower index)
  Vec3 E_i{}, E_j{};        // their E-vectors in b
  double angle_rad = 0;     // the angle between them, axial, [0, π/2]: asin|E_i × E_j| (conditioning)
  Vec3 s_b{};               // the sun in b (zero unless Ok)
  double azimuth_rad = 0;   // A^b = atan2(s_y, s_x): from X_b towards Y_b (Z21 Eq. 7)
  double elevation_rad = 0; // H^b = asin(s_z^b)
};

// Eqs. 3–8 over the readings and their units' frames (the same length; else std::invalid_argument).
UnitSun sun_from_units(std::span<const UnitReading> readings, std::span<const UnitMount> mounts,
                       const UnitSunSettings& settings = {});

// The sun in n: s^n = C_b^n·s^b, H^n = asin(s_z^n). C_bn: the body's axes in ENU (compass/heading.h's
// C_b^n = Rz(−H)·Rx(λ)·Ry(γ), body_axes_enu).
struct UnitSunNav {
  Vec3 s_n{};
  double elevation_rad = 0;
};
UnitSunNav sun_in_nav(const Vec3& s_b, const Axes3& C_bn);

// C_b^n by its columns for a heading (clockwise from north), roll and pitch (compass/heading.h's Tilt
// as two numbers, degrees).
Axes3 body_axes_enu(double heading_deg, double roll_deg, double pitch_deg);

// The sun's body azimuth clockwise seen from above, from Y_b (forward) towards X_b (right), in
// [0, 2π): atan2(s_x, s_y); the sense of a heading (spec §0). Level, it is A_s − H.
double body_azimuth_clockwise_rad(const Vec3& s_b);

}  // namespace polrig
