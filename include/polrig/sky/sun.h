#pragma once
// The apparent position of the sun for an observer on the Earth (spec sky-and-compasses.md §1.1),
// from ERFA (the IAU SOFA library): precession-nutation, annual aberration, light deflection,
// Earth rotation and, when asked for, refraction.
//
// Frames and senses (spec §0): the n-frame is ENU (x east, y north, z up); the azimuth A_s is
// geographic, from north towards east (clockwise seen from above); hour angles run westwards.
#include <string>
#include <string_view>

#include "polrig/vec3.h"

namespace polrig {

// An instant on the UTC time scale, as seconds since 1970-01-01T00:00:00Z not counting leap
// seconds (POSIX time). A double keeps 0.2 µs at today's dates, far below the 1 ms that moves the
// sun by 4e-6°.
struct UtcTime {
  double unix_s = 0;
  UtcTime plus_seconds(double s) const { return {unix_s + s}; }
  auto operator<=>(const UtcTime&) const = default;
};

// "2018-11-16T08:09:40Z" or with fractional seconds "…:40.25Z"; a trailing 'Z' (UTC) is
// required. Throws std::invalid_argument naming the text on anything else (no local times,
// no offsets, out-of-range fields such as month 13 or 24:00).
UtcTime parse_utc(std::string_view iso8601);
// ISO 8601 with a 'Z', milliseconds shown only when not whole seconds.
std::string format_utc(UtcTime t);

struct Site {
  double lat_deg = 38.879167;   // φ_g, north positive (Dalian, W19: 38°52′45″N)
  double lon_deg = 121.543889;  // λ_g, east positive (121°32′38″E)
  double height_m = 0;          // above the WGS-84 ellipsoid
};

struct SunSettings {
  double delta_T_s = 69.0;      // ΔT = TT − UT1 (≈ 69 s for 2015–2021)
  double ut1_minus_utc_s = 0;   // |UT1 − UTC| < 0.9 s
  bool refraction = false;      // geometric sun by default (spec §1.1 [C])
  double pressure_hPa = 1013.25;
  double temperature_C = 10;
  double relative_humidity = 0.5;
  double wavelength_um = 0.55;
};

struct SunPosition {
  double azimuth_deg = 0;      // A_s, from north towards east, [0°, 360°)
  double elevation_deg = 0;    // h_s (refracted when SunSettings::refraction)
  double zenith_deg = 0;       // θ_s = 90° − h_s
  double declination_deg = 0;  // δ, apparent (true equator and equinox of date)
  double gha_deg = 0;          // Greenwich hour angle, westwards, [0°, 360°)
  double lha_deg = 0;          // local hour angle = GHA + λ_g, [0°, 360°)
};

// The full-accuracy apparent position (ERFA).
SunPosition sun_position(UtcTime t, const Site& site, const SunSettings& settings = {});

// The unit vector to the sun in ENU: (cos h·sin A, cos h·cos A, sin h).
Vec3 sun_direction_enu(const SunPosition& sun);

}  // namespace polrig
