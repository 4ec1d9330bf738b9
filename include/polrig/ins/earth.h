#pragma once
// The Earth the strapdown INS navigates on: WGS-84 radii of curvature, normal gravity and the
// angular rates of the ENU navigation frame (docs/physics.md §18.1).
//
// Frames (spec sky-and-compasses.md §0, §4.1): n = ENU (x east, y north, z up), latitude L and
// longitude λ geodetic in radians, north and east positive, h above the ellipsoid in metres.
// Gravity points down: g^n = (0, 0, −g). GeographicLib supplies the ellipsoid and Somigliana's
// normal gravity (src/ins/earth.cpp only).
#include <Eigen/Core>

namespace polrig {

// WGS-84's rotation rate Ω (rad/s), the value GeographicLib::Constants::WGS84_omega() holds.
inline constexpr double kEarthRate = 7.292115e-5;

// Meridian (north–south) radius R_M and prime-vertical (east–west) radius R_N at latitude L.
struct EarthRadii {
  double R_M = 0;
  double R_N = 0;
};
EarthRadii earth_radii(double lat_rad);

// WGS-84 normal gravity's magnitude g(L, h) (m/s²): gravitation plus the centrifugal term,
// GeographicLib's NormalGravity::WGS84() on the ellipsoid (SurfaceGravity: Somigliana, exact)
// carried to h by TR8350.2's series (within 1.1e-10 m/s² per metre of h of its exact Gravity()).
// The northward component off the ellipsoid (≈ 8e-9 m/s² per metre of height at 45°) is dropped:
// g^n = (0, 0, −g).
double normal_gravity(double lat_rad, double h_m);
Eigen::Vector3d gravity_n(double lat_rad, double h_m);

// ∂g/∂L (m/s² per rad) and ∂g/∂h (m/s² per m) of normal_gravity: the gravity gradient of the
// error model (PSINS etm.m's −g0·(2·5.27e-3 + …)·sin L·cos L and −3.086e-6), by central differences
// of the same normal gravity (steps 1e-4 rad and 10 m; its series is smooth, error < 1e-12).
struct GravityGradient {
  double dg_dL = 0;
  double dg_dh = 0;
};
GravityGradient gravity_gradient(double lat_rad, double h_m);

// ω_ie^n = (0, Ω cos L, Ω sin L): the Earth's rate in ENU.
Eigen::Vector3d omega_ie_n(double lat_rad);

// ω_en^n = (−v_N/(R_M + h), v_E/(R_N + h), v_E tan L/(R_N + h)): the transport rate of ENU.
Eigen::Vector3d omega_en_n(const Eigen::Vector3d& v_n, double lat_rad, double h_m);

}  // namespace polrig
