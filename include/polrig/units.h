#pragma once
// Units: millimetres, degrees at every interface (radians inside), volts.
#include <cmath>
#include <limits>
#include <numbers>

namespace polrig {

// π and one degree in radians, for formulas written with them (one copy for every file).
inline constexpr double kPi = std::numbers::pi;
// A value that is not defined (a PNS reading without a fix, a skipped update): formats.md's nan.
inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kDeg = std::numbers::pi / 180.0;

constexpr double deg2rad(double deg) { return deg * (std::numbers::pi / 180.0); }
constexpr double rad2deg(double rad) { return rad * (180.0 / std::numbers::pi); }

// Wraps an axial angle (a polarization angle, defined modulo 180°) into [0°, 180°).
inline double wrap_axis_deg(double deg) {
  double w = std::fmod(deg, 180.0);
  if (w < 0.0) w += 180.0;
  if (w >= 180.0) w -= 180.0;
  return w;
}

// Difference a − b of two axial angles, wrapped into [−90°, 90°).
inline double axis_difference_deg(double a, double b) {
  double d = std::fmod(a - b, 180.0);
  if (d < -90.0) d += 180.0;
  if (d >= 90.0) d -= 180.0;
  return d;
}

}  // namespace polrig
