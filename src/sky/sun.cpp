// The sun's apparent topocentric place with ERFA (the IAU SOFA library).
//
// Route (docs/physics.md, "The sun"): ERFA's astrometry context for the observer (eraApco: the
// Earth's barycentric and heliocentric position from eraEpv00, the IAU 2006/2000A CIP X, Y and
// CIO locator s from eraXys06a, the Earth rotation angle from UT1, the observer's geodetic
// position and velocity), then the sun's direction from the observer, −eh (eh is the unit vector
// Sun → observer, so the 8.8″ parallax and the observer's height are in), then annual plus
// diurnal aberration (eraAb with the observer's barycentric velocity), then the bias-precession-
// nutation matrix to CIRS, then eraAtioq: the Earth's rotation to the horizon. Refraction, when
// asked for, is Sæmundsson's formula as in NREL SPA (ERFA's A·tan z + B·tan³z model is 1′ low
// at 4° elevation, where the outdoor runs are). Light deflection is zero for the sun's own light (it travels radially from
// the deflecting body), and the sun's barycentric motion during the 8.3 min light time (≈ 6 km)
// moves it by 3e-6°: both are left out.
#include "polrig/sky/sun.h"
#include "polrig/units.h"

#include <erfa.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

namespace polrig {
namespace {

constexpr double kUnixEpochJd = 2440587.5;
constexpr double kDay = 86400;
constexpr int kFirstYear = 1900, kLastYear = 2100;  // eraEpv00's range; parse_utc's years

// Howard Hinnant's days_from_civil / civil_from_days (proleptic Gregorian).
long long days_from_civil(long long y, unsigned m, unsigned d) {
  y -= m <= 2;
  const long long era = (y >= 0 ? y : y - 399) / 400;
  const unsigned yoe = static_cast<unsigned>(y - era * 400);
  const unsigned doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + static_cast<long long>(doe) - 719468;
}

struct Civil {
  long long y;
  unsigned m, d;
};
Civil civil_from_days(long long z) {
  z += 719468;
  const long long era = (z >= 0 ? z : z - 146096) / 146097;
  const unsigned doe = static_cast<unsigned>(z - era * 146097);
  const unsigned yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const unsigned doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const unsigned mp = (5 * doy + 2) / 153;
  const unsigned d = doy - (153 * mp + 2) / 5 + 1;
  const unsigned m = mp < 10 ? mp + 3 : mp - 9;
  return {static_cast<long long>(yoe) + era * 400 + (m <= 2), m, d};
}

bool leap_year(long long y) { return (y % 4 == 0 && y % 100 != 0) || y % 400 == 0; }
unsigned days_in_month(long long y, unsigned m) {
  static constexpr std::array<unsigned, 12> kDays{31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  return m == 2 && leap_year(y) ? 29 : kDays[m - 1];
}

// A continuous time scale offset from POSIX time (UT1 = UTC + dut1) as an ERFA two-part JD.
void two_part_jd(double unix_s, double& jd1, double& jd2) {
  const double days = std::floor(unix_s / kDay);
  jd1 = kUnixEpochJd + days;
  jd2 = (unix_s - days * kDay) / kDay;
}

void check_inputs(UtcTime t, const Site& site, const SunSettings& s) {
  auto bad = [](const std::string& what) { throw std::invalid_argument("sun position: " + what); };
  if (!std::isfinite(t.unix_s)) bad(fmt::format("time {} is not finite", t.unix_s));
  // eraEpv00 (the Earth's ephemeris) is valid over 1900–2100 only (status 1 outside).
  const long long day = static_cast<long long>(std::floor(t.unix_s / kDay));
  const Civil c = civil_from_days(day);
  if (c.y < kFirstYear || c.y > kLastYear)
    bad(fmt::format("{} is outside {}-{}, the range of ERFA's Earth ephemeris (eraEpv00)",
                    format_utc(t), kFirstYear, kLastYear));
  // Without ΔT, outside the leap-second table (before 1960, after its release year + 5) ERFA
  // guesses TT − UTC (status +1, accepted): TT only moves the sun along its orbit, 1.14e-5°/s,
  // so tens of seconds of error stay below 1e-3° (docs/physics.md §9.2, "Range").
  if (!(std::abs(site.lat_deg) <= 90)) bad(fmt::format("latitude {}° is outside [-90°, 90°]", site.lat_deg));
  if (!(std::abs(site.lon_deg) <= 360)) bad(fmt::format("longitude {}° is outside [-360°, 360°]", site.lon_deg));
  if (!(std::abs(site.height_m) <= 1e5)) bad(fmt::format("height {} m is outside [-1e5, 1e5] m", site.height_m));
  if (!(std::abs(s.ut1_minus_utc_s) <= 1)) bad(fmt::format("UT1 - UTC {} s is outside [-1, 1] s", s.ut1_minus_utc_s));
  if (s.delta_T_s && !(std::abs(*s.delta_T_s) <= 1e5)) bad(fmt::format("delta T {} s is outside [-1e5, 1e5] s", *s.delta_T_s));
  if (!s.refraction) return;
  if (!(s.pressure_hPa >= 0 && s.pressure_hPa <= 1200)) bad(fmt::format("pressure {} hPa is outside [0, 1200] hPa", s.pressure_hPa));
  if (!(s.temperature_C >= -150 && s.temperature_C <= 200)) bad(fmt::format("temperature {} °C is outside [-150, 200] °C", s.temperature_C));
}

// The sun's apparent direction in CIRS (topocentric) and the observer's ERFA context at t.
struct Apparent {
  Vec3 cirs;
  eraASTROM astrom;
  double era;  // Earth rotation angle, radians
};

Apparent apparent_sun(UtcTime t, const Site& site, const SunSettings& s) {
  double ut11, ut12;
  two_part_jd(t.unix_s + s.ut1_minus_utc_s, ut11, ut12);
  double tt1, tt2;
  if (s.delta_T_s) {
    tt1 = ut11;
    tt2 = ut12 + *s.delta_T_s / kDay;
  } else {
    const double days = std::floor(t.unix_s / kDay);
    const Civil c = civil_from_days(static_cast<long long>(days));
    const double sod = t.unix_s - days * kDay;
    const int hh = static_cast<int>(sod / 3600), mm = static_cast<int>((sod - hh * 3600) / 60);
    double u1, u2, tai1, tai2;
    if (eraDtf2d("UTC", static_cast<int>(c.y), static_cast<int>(c.m), static_cast<int>(c.d), hh, mm,
                 sod - hh * 3600 - mm * 60, &u1, &u2) < 0 ||
        eraUtctai(u1, u2, &tai1, &tai2) < 0 || eraTaitt(tai1, tai2, &tt1, &tt2) != 0)
      throw std::invalid_argument("sun position: ERFA cannot convert the UTC time " + format_utc(t));
  }
  double ehpv[2][3], ebpv[2][3];
  eraEpv00(tt1, tt2, ehpv, ebpv);  // status 1 (outside 1900–2100): refused by check_inputs, but
                                   // for a track's nodes up to 2 h past the range's ends
  double x, y, cio_s;
  eraXys06a(tt1, tt2, &x, &y, &cio_s);
  const double era = eraEra00(ut11, ut12);
  Apparent a{};
  eraApco(tt1, tt2, ebpv, ehpv[0], x, y, cio_s, era, site.lon_deg * kDeg, site.lat_deg * kDeg,
          site.height_m, 0, 0, eraSp00(tt1, tt2), 0, 0, &a.astrom);
  double natural[3], aberrated[3], cirs[3];
  for (int i = 0; i < 3; ++i) natural[i] = -a.astrom.eh[i];
  eraAb(natural, a.astrom.v, a.astrom.em, a.astrom.bm1, aberrated);
  eraRxp(a.astrom.bpn, aberrated, cirs);
  a.cirs = {cirs[0], cirs[1], cirs[2]};
  a.era = era;
  return a;
}

// Sæmundsson (Sky & Telescope 72:70, 1986; Meeus ch. 16) from the true elevation, scaled by
// P/1010 hPa·283 K/T as in NREL SPA (Reda & Andreas 2008, Eq. 42), where it is applied only while
// the upper limb is visible: h ≥ −(0.26667° + 0.5667°).
double refraction_deg(double h_deg, const SunSettings& s) {
  if (h_deg < -(0.26667 + 0.5667)) return 0;
  return s.pressure_hPa / 1010 * 283 / (273 + s.temperature_C) * 1.02 /
         (60 * std::tan((h_deg + 10.3 / (h_deg + 5.11)) * kDeg));
}

// The Earth's rotation (ERA) and refraction applied to a CIRS direction.
SunPosition observe(const Vec3& cirs, double era, eraASTROM& astrom, double lon_deg,
                    const SunSettings& settings) {
  double p[3] = {cirs[0], cirs[1], cirs[2]};
  double ri, di;
  eraC2s(p, &ri, &di);
  ri = eraAnp(ri);
  eraAper(era, &astrom);
  double aob, zob, hob, dob, rob;
  eraAtioq(ri, di, &astrom, &aob, &zob, &hob, &dob, &rob);
  SunPosition sun;
  sun.azimuth_deg = eraAnp(aob) / kDeg;
  sun.elevation_deg = 90 - zob / kDeg;
  if (settings.refraction) sun.elevation_deg += refraction_deg(sun.elevation_deg, settings);
  sun.zenith_deg = 90 - sun.elevation_deg;
  sun.declination_deg = di / kDeg;
  sun.gha_deg = eraAnp(era - ri) / kDeg;
  sun.lha_deg = eraAnp(era - ri + lon_deg * kDeg) / kDeg;
  if (sun.azimuth_deg >= 360) sun.azimuth_deg = 0;
  if (sun.gha_deg >= 360) sun.gha_deg = 0;
  if (sun.lha_deg >= 360) sun.lha_deg = 0;
  return sun;
}

[[noreturn]] void bad_utc(std::string_view text, const std::string& why) {
  throw std::invalid_argument(fmt::format(
      "invalid UTC time \"{}\": {} (expected ISO 8601 with a Z, like 2018-11-16T08:09:40Z or "
      "2018-11-16T08:09:40.25Z)",
      text, why));
}

// The decimal fraction 0.d1d2d3… as parse_utc accumulates it, digit by digit.
double decimal_fraction(std::string_view digits) {
  double fraction = 0, scale = 0.1;
  for (const char c : digits) {
    fraction += (c - '0') * scale;
    scale /= 10;
  }
  return fraction;
}

}  // namespace

UtcTime parse_utc(std::string_view text) {
  // YYYY-MM-DDTHH:MM:SS[.fraction]Z
  const std::string_view pattern = "dddd-dd-ddTdd:dd:dd";
  if (text.size() < pattern.size() + 1) bad_utc(text, "too short");
  for (std::size_t i = 0; i < pattern.size(); ++i) {
    const char c = text[i];
    if (pattern[i] == 'd' ? !(c >= '0' && c <= '9') : c != pattern[i])
      bad_utc(text, fmt::format("character {} should be {}", i + 1,
                                pattern[i] == 'd' ? "a digit" : fmt::format("'{}'", pattern[i])));
  }
  auto num = [&](std::size_t pos, std::size_t n) {
    int v = 0;
    for (std::size_t i = 0; i < n; ++i) v = v * 10 + (text[pos + i] - '0');
    return v;
  };
  const int year = num(0, 4), month = num(5, 2), day = num(8, 2);
  if (year < kFirstYear || year > kLastYear)
    bad_utc(text, fmt::format("year {} is outside {}-{}, the range of the sun's ephemeris", year,
                              kFirstYear, kLastYear));
  const int hour = num(11, 2), minute = num(14, 2), second = num(17, 2);
  std::size_t pos = pattern.size();
  double fraction = 0;
  if (text[pos] == '.') {
    ++pos;
    const std::size_t first = pos;
    while (pos < text.size() && text[pos] >= '0' && text[pos] <= '9') ++pos;
    if (pos == first) bad_utc(text, "no digits after the decimal point");
    fraction = decimal_fraction(text.substr(first, pos - first));
  }
  if (pos >= text.size() || text[pos] != 'Z')
    bad_utc(text, "the time must end in Z (UTC); offsets and local times are not accepted");
  if (pos + 1 != text.size()) bad_utc(text, "text after the Z");
  if (month < 1 || month > 12) bad_utc(text, fmt::format("month {} is outside 1-12", month));
  if (day < 1 || static_cast<unsigned>(day) > days_in_month(year, static_cast<unsigned>(month)))
    bad_utc(text, fmt::format("day {} does not exist in {:04}-{:02}", day, year, month));
  if (hour > 23) bad_utc(text, fmt::format("hour {} is outside 0-23", hour));
  if (minute > 59) bad_utc(text, fmt::format("minute {} is outside 0-59", minute));
  if (second == 60) bad_utc(text, "a leap second (:60) has no POSIX time");
  if (second > 59) bad_utc(text, fmt::format("second {} is outside 0-59", second));
  const long long days = days_from_civil(year, static_cast<unsigned>(month), static_cast<unsigned>(day));
  return {static_cast<double>(days) * kDay + hour * 3600.0 + minute * 60.0 + second + fraction};
}

UtcTime utc_from_unix_ns(std::int64_t seconds, std::int32_t nanoseconds) {
  if (nanoseconds < 0 || nanoseconds > 999999999)
    throw std::invalid_argument(fmt::format("nanoseconds {} outside [0, 999999999]", nanoseconds));
  // The nine digits parse_utc would read: the same double as the ISO text of this instant.
  return {static_cast<double>(seconds) + decimal_fraction(fmt::format("{:09}", nanoseconds))};
}

std::string format_utc(UtcTime t) {
  if (!std::isfinite(t.unix_s)) return fmt::format("{}", t.unix_s);
  const long long ms = std::llround(t.unix_s * 1000);
  long long days = ms / 86400000, rest = ms % 86400000;
  if (rest < 0) {
    rest += 86400000;
    --days;
  }
  const Civil c = civil_from_days(days);
  const long long s = rest / 1000, milli = rest % 1000;
  std::string out = fmt::format("{:04}-{:02}-{:02}T{:02}:{:02}:{:02}", c.y, c.m, c.d, s / 3600,
                                s / 60 % 60, s % 60);
  if (milli != 0) out += fmt::format(".{:03}", milli);
  return out + "Z";
}

SunPosition sun_position(UtcTime t, const Site& site, const SunSettings& settings) {
  check_inputs(t, site, settings);
  Apparent a = apparent_sun(t, site, settings);
  return observe(a.cirs, a.era, a.astrom, site.lon_deg, settings);
}

void check_sun_inputs(UtcTime t, const Site& site, const SunSettings& settings) {
  check_inputs(t, site, settings);
}

std::optional<std::string> site_problem(const Site& site) {
  if (!(std::abs(site.lat_deg) <= 90))
    return fmt::format("latitude {} is outside [-90, 90] (degrees, north positive)", site.lat_deg);
  if (!(std::abs(site.lon_deg) <= 180))
    return fmt::format("longitude {} is outside [-180, 180] (degrees, east positive)", site.lon_deg);
  if (!(std::abs(site.height_m) <= 1e5))
    return fmt::format("height {} m is outside [-1e5, 1e5] (m above the WGS-84 ellipsoid)", site.height_m);
  return std::nullopt;
}

Vec3 sun_direction_enu(const SunPosition& sun) {
  const double h = sun.elevation_deg * kDeg, A = sun.azimuth_deg * kDeg;
  return {std::cos(h) * std::sin(A), std::cos(h) * std::cos(A), std::sin(h)};
}

// ---------------------------------------------------------------------------------------------
// SunTrack
// ---------------------------------------------------------------------------------------------

struct SunTrack::Nodes {
  double t0 = 0, spacing = 0, ut1_minus_utc = 0, lon_deg = 0;
  SunSettings settings;
  std::vector<Vec3> cirs;  // at t0 + k·spacing
  eraASTROM astrom{};      // the observer's constant part (site, refraction constants)
};

SunTrack::SunTrack(UtcTime begin, UtcTime end, const Site& site, const SunSettings& settings,
                   double node_spacing_s)
    : begin_(begin), end_(end) {
  check_inputs(begin, site, settings);
  check_inputs(end, site, settings);
  if (!(end.unix_s >= begin.unix_s))
    throw std::invalid_argument(fmt::format("sun track: end {} is before begin {}", format_utc(end),
                                            format_utc(begin)));
  if (!(node_spacing_s >= 1 && node_spacing_s <= 7200))
    throw std::invalid_argument(
        fmt::format("sun track: node spacing {} s is outside [1, 7200] s", node_spacing_s));
  auto nodes = std::make_shared<Nodes>();
  nodes->spacing = node_spacing_s;
  nodes->t0 = begin.unix_s - node_spacing_s;
  nodes->ut1_minus_utc = settings.ut1_minus_utc_s;
  nodes->lon_deg = site.lon_deg;
  nodes->settings = settings;
  // One node before begin and two after end, so every time has two nodes on each side.
  const auto count = static_cast<std::size_t>(std::ceil((end.unix_s - begin.unix_s) / node_spacing_s)) + 4;
  nodes->cirs.reserve(count);
  for (std::size_t k = 0; k < count; ++k) {
    Apparent a = apparent_sun({nodes->t0 + static_cast<double>(k) * node_spacing_s}, site, settings);
    nodes->cirs.push_back(a.cirs);
    if (k == 0) nodes->astrom = a.astrom;
  }
  nodes_ = std::move(nodes);
}

namespace {
// A track's interpolated CIRS direction at t (4-point Lagrange over the nodes), not normalised.
Vec3 interpolated_cirs(const std::vector<Vec3>& cirs, double t0, double spacing, double t) {
  const double u = (t - t0) / spacing;
  const std::size_t i = std::min(static_cast<std::size_t>(u), cirs.size() - 3);  // u ≥ 1
  const double x = u - static_cast<double>(i);  // in [0, 1], nodes at −1, 0, 1, 2
  const double w[4] = {-x * (x - 1) * (x - 2) / 6, (x + 1) * (x - 1) * (x - 2) / 2,
                       -(x + 1) * x * (x - 2) / 2, (x + 1) * x * (x - 1) / 6};
  Vec3 p{0, 0, 0};
  for (int k = 0; k < 4; ++k) p = vec3::add(p, vec3::mul(cirs[i - 1 + static_cast<std::size_t>(k)], w[k]));
  return p;
}
}  // namespace

SunTrack::HourAngle SunTrack::hour_angle_at(UtcTime t) const {
  if (!(t.unix_s >= begin_.unix_s && t.unix_s <= end_.unix_s))
    throw std::out_of_range(fmt::format("sun track: {} is outside [{}, {}]", format_utc(t),
                                        format_utc(begin_), format_utc(end_)));
  const Nodes& n = *nodes_;
  const Vec3 p = vec3::unit(interpolated_cirs(n.cirs, n.t0, n.spacing, t.unix_s));
  double ut11, ut12;
  two_part_jd(t.unix_s + n.ut1_minus_utc, ut11, ut12);
  // δ = asin p_z; GHA = ERA − α with α = atan2(p_y, p_x): cos and sin by the addition theorem.
  const double era = eraEra00(ut11, ut12), ce = std::cos(era), se = std::sin(era);
  const double cd = std::hypot(p[0], p[1]);
  HourAngle h;
  h.sin_dec = p[2];
  h.cos_dec = cd;
  if (cd > 0) {
    const double ca = p[0] / cd, sa = p[1] / cd;
    h.cos_gha = ce * ca + se * sa;
    h.sin_gha = se * ca - ce * sa;
  }
  return h;
}

SunPosition SunTrack::at(UtcTime t) const {
  if (!(t.unix_s >= begin_.unix_s && t.unix_s <= end_.unix_s))
    throw std::out_of_range(fmt::format("sun track: {} is outside [{}, {}]", format_utc(t),
                                        format_utc(begin_), format_utc(end_)));
  const Nodes& n = *nodes_;
  const Vec3 p = interpolated_cirs(n.cirs, n.t0, n.spacing, t.unix_s);
  double ut11, ut12;
  two_part_jd(t.unix_s + n.ut1_minus_utc, ut11, ut12);
  eraASTROM astrom = n.astrom;
  return observe(vec3::unit(p), eraEra00(ut11, ut12), astrom, n.lon_deg, n.settings);
}

}  // namespace polrig
