#pragma once
// The Astronomical Almanac's low-precision sun (spec sky-and-compasses.md §1.1; Michalsky 1988),
// good to ~0.01° absolute and far better in its change over a minute: the tests' reference,
// written independently of polrig's ERFA route (sky/sun).
#include <cmath>
#include <numbers>

namespace polrig::test {

struct AlmanacSun {
  double azimuth_deg;  // A_s, clockwise from north, [0°, 360°)
  double zenith_deg;   // θ_s
  double elevation_rad, azimuth_rad;
};

// The almanac's apparent declination δ and Greenwich hour angle GHA = GMST − α (radians): the
// inputs of Z21's Eq. 9 (ins/filter.h), and of almanac_sun's local hour angle below.
struct AlmanacHourAngle {
  double dec_rad, gha_rad;
};

inline AlmanacHourAngle almanac_dec_gha(double unix_s) {
  constexpr double kDeg = std::numbers::pi / 180.0;
  const double n = unix_s / 86400.0 + 2440587.5 - 2451545.0;
  const double ut_h = std::fmod(unix_s, 86400.0) / 3600.0;
  const double L = 280.460 + 0.9856474 * n, g = (357.528 + 0.9856003 * n) * kDeg;
  const double lam = (L + 1.915 * std::sin(g) + 0.020 * std::sin(2 * g)) * kDeg;
  const double eps = (23.439 - 0.0000004 * n) * kDeg;
  const double ra = std::atan2(std::cos(eps) * std::sin(lam), std::cos(lam));
  const double gmst_h = 6.697375 + 0.0657098242 * n + ut_h;
  return {std::asin(std::sin(eps) * std::sin(lam)), 15.0 * gmst_h * kDeg - ra};
}

inline AlmanacSun almanac_sun(double unix_s, double lat_deg, double lon_deg) {
  constexpr double kDeg = std::numbers::pi / 180.0;
  const AlmanacHourAngle a = almanac_dec_gha(unix_s);
  const double dec = a.dec_rad, lha = a.gha_rad + lon_deg * kDeg;
  const double phi = lat_deg * kDeg;
  const double sin_h = std::sin(phi) * std::sin(dec) + std::cos(phi) * std::cos(dec) * std::cos(lha);
  const double A = std::atan2(-std::sin(lha) * std::cos(dec),
                              std::cos(phi) * std::sin(dec) - std::sin(phi) * std::cos(dec) * std::cos(lha));
  const double A_deg = A / kDeg;
  return {A_deg < 0 ? A_deg + 360.0 : A_deg, 90.0 - std::asin(sin_h) / kDeg, std::asin(sin_h), A};
}

}  // namespace polrig::test
