#pragma once
// The apparent position of the sun for an observer on the Earth (spec sky-and-compasses.md §1.1),
// from ERFA (the IAU SOFA library): precession-nutation, annual aberration, light deflection,
// Earth rotation and, when asked for, refraction.
//
// Frames and senses (spec §0): the n-frame is ENU (x east, y north, z up); the azimuth A_s is
// geographic, from north towards east (clockwise seen from above); hour angles run westwards.
#include <cstdint>
#include <memory>
#include <optional>
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
// no offsets, out-of-range fields such as month 13 or 24:00, years outside 1900–2100, the
// range of ERFA's Earth ephemeris).
UtcTime parse_utc(std::string_view iso8601);
// The instant `seconds` + `nanoseconds`·10⁻⁹ s after 1970-01-01T00:00:00Z (POSIX; nanoseconds in
// [0, 10⁹)), rounded exactly as parse_utc rounds the same instant written with nine decimals, so
// that a time given as numbers (numpy.datetime64 in Python) and its ISO text are the same double.
UtcTime utc_from_unix_ns(std::int64_t seconds, std::int32_t nanoseconds);
// ISO 8601 with a 'Z', milliseconds shown only when not whole seconds.
std::string format_utc(UtcTime t);

struct Site {
  double lat_deg = 38.879167;   // φ_g, north positive (Dalian, W19: 38°52′45″N)
  double lon_deg = 121.543889;  // λ_g, east positive (121°32′38″E)
  double height_m = 0;          // above the WGS-84 ellipsoid
};

// Time scales: UT1 = UTC + ut1_minus_utc_s turns the Earth. TT (the ephemeris and nutation
// argument) comes by default from UTC through ERFA's leap-second table, TT = UTC + ΔAT + 32.184 s,
// so that ΔT = TT − UT1 = ΔAT + 32.184 s − (UT1 − UTC) follows and needs no setting. delta_T_s
// overrides it (TT = UT1 + ΔT), e.g. to reproduce NREL SPA's test case (ΔT = 67 s) or for dates
// beyond the leap-second table; 1 s of ΔT moves the sun by only 1.1e-5°. Times are refused
// (std::invalid_argument) outside 1900–2100 (eraEpv00's range) and, without delta_T_s, outside
// 1960 to the leap-second table's last valid year (ERFA's release year + 5; 2026 for ERFA 2.0),
// where ERFA would only warn of a "dubious year".
struct SunSettings {
  std::optional<double> delta_T_s;  // ΔT = TT − UT1 in s; empty: from leap seconds (above)
  double ut1_minus_utc_s = 0;       // |UT1 − UTC| < 0.9 s; 1 s is 0.0042° of hour angle
  // Refraction (raises h_s only): Sæmundsson's formula scaled by pressure and temperature, as
  // NREL SPA does, applied while the sun's upper limb can be seen (h_s ≥ −0.8334°).
  bool refraction = false;          // geometric sun by default (spec §1.1 [C])
  double pressure_hPa = 1010;       // for refraction only
  double temperature_C = 10;
};

struct SunPosition {
  double azimuth_deg = 0;      // A_s, from north towards east, [0°, 360°)
  double elevation_deg = 0;    // h_s (refracted when SunSettings::refraction)
  double zenith_deg = 0;       // θ_s = 90° − h_s
  double declination_deg = 0;  // δ, apparent, topocentric (true equator of date)
  double gha_deg = 0;          // Greenwich hour angle, westwards, [0°, 360°)
  double lha_deg = 0;          // local hour angle = GHA + λ_g, [0°, 360°)
};

// The full-accuracy apparent topocentric position (ERFA). Declination and hour angles are
// topocentric too (parallax and diurnal aberration in), so that with refraction off
// sin h_s = sin φ_g·sin δ + cos φ_g·cos δ·cos LHA holds exactly (φ_g geodetic).
// Throws std::invalid_argument naming the value for a latitude outside [−90°, 90°], a
// non-finite input, or a date ERFA cannot handle.
SunPosition sun_position(UtcTime t, const Site& site, const SunSettings& settings = {});
// The checks alone: throws what sun_position would throw for these inputs, computes nothing.
void check_sun_inputs(UtcTime t, const Site& site, const SunSettings& settings = {});
// What is wrong with an observer's latitude, longitude and height as given by a user (--site, a
// Python site=): "latitude 95 is outside [-90, 90] (degrees, north positive)", or nothing. Stricter
// than check_sun_inputs, which accepts any longitude in [-360, 360]; the height's range is its.
std::optional<std::string> site_problem(const Site& site);

// The fast path: exact apparent places at nodes `node_spacing_s` apart over [begin, end], and
// between them 4-point Lagrange interpolation of the sun's apparent direction in CIRS (the
// equator of date, which turns ~1° a day). The Earth's rotation and refraction are then applied
// exactly for each time, so the result differs from sun_position by < 1e-6° (tests/test_sky.cpp).
class SunTrack {
 public:
  SunTrack(UtcTime begin, UtcTime end, const Site& site, const SunSettings& settings = {},
           double node_spacing_s = 1800);
  // Throws std::out_of_range naming the time when t is outside [begin, end].
  SunPosition at(UtcTime t) const;
  // The sun's topocentric declination δ and Greenwich hour angle GHA at t, as at() gives them
  // (declination_deg, gha_deg: the same interpolated direction and Earth rotation angle), as
  // sines and cosines and without the horizon transformation: for a fit that evaluates
  // cos θ_s = sin φ·sin δ + cos φ·cos δ·cos(GHA + λ) at many times (compass/positioning.h).
  // Throws as at().
  struct HourAngle {
    double sin_dec = 0, cos_dec = 1, sin_gha = 0, cos_gha = 1;
  };
  HourAngle hour_angle_at(UtcTime t) const;
  UtcTime begin() const { return begin_; }
  UtcTime end() const { return end_; }

 private:
  struct Nodes;
  std::shared_ptr<const Nodes> nodes_;
  UtcTime begin_, end_;
};

// The unit vector to the sun in ENU: (cos h·sin A, cos h·cos A, sin h).
Vec3 sun_direction_enu(const SunPosition& sun);

}  // namespace polrig
