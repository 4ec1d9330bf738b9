#pragma once
// The sun and the sky for many rows of (time, site): the tables of `polrig sky table` and
// `polrig heading`. Values only; reading and writing the files is io/'s.
#include <cstddef>
#include <optional>
#include <span>
#include <string_view>
#include <stdexcept>
#include <string>
#include <vector>

#include "polrig/progress.h"
#include "polrig/sky/rayleigh.h"
#include "polrig/sky/sun.h"

namespace polrig {

// A row the ephemeris refuses: `row` is its 0-based index, what() sun_position's message.
class SunRowError : public std::invalid_argument {
 public:
  SunRowError(const std::string& what, std::size_t row) : std::invalid_argument(what), row(row) {}
  std::size_t row;
};

struct SunRow {
  UtcTime utc;
  Site site;
};

// sun_position for every row, in the rows' order. Every row is checked first (SunRowError
// naming the first bad one). The rows of one site are interpolated along a SunTrack over their
// time span (< 1e-6°, tests/test_sky.cpp) when they outnumber the track's nodes (one per 30 min
// of the span, each an exact position) by kRowsPerTrackNode or more; otherwise, and for few
// rows, each is exact. The choice depends on the rows alone, and the rows are computed in
// parallel (TBB), each into its own slot: the result is the same for any thread count.
inline constexpr std::size_t kRowsPerTrackNode = 8;
std::vector<SunPosition> sun_positions(std::span<const SunRow> rows,
                                       const SunSettings& settings = {},
                                       const Progress& progress = {});

// A direction on the sky at a time and place: geographic azimuth (from north towards east) and
// elevation of the viewing direction, degrees.
// With `sun` set the row's sun is given (no ephemeris: `at` is not read).
struct SkyQuery {
  SunRow at;
  double view_az_deg = 0, view_el_deg = 90;
  std::optional<SunPosition> sun;
};
// A sun given by its geographic azimuth and elevation, degrees (zenith 90° − elevation; no hour
// angles).
SunPosition fixed_sun(double azimuth_deg, double elevation_deg);
// The range of one input of a row (a CSV column, a Python argument): [lo, hi] and what it is.
struct InputRange {
  double lo, hi;
  const char* what;
};
// The ranges of `polrig sky table`'s inputs (its CSV columns, polrig.sky_table's arguments):
// lat_deg, lon_deg, view_az_deg, view_el_deg, sun_az_deg, sun_el_deg; std::invalid_argument for
// another name.
InputRange sky_query_range(std::string_view field);

struct SkySample {
  SunPosition sun;
  SkyLight light;  // along the viewing direction; χ in its local meridian frame (at the zenith,
                   // the limit along view_az_deg)
  std::optional<Stokes> absolute;  // the vector-RT sky's L/E₀, Q, U (SunSky::absolute_stokes)
};
// The single-scattering sky (sky_light) of one sun along a viewing direction given by its
// geographic azimuth (from north towards east) and elevation, degrees: what sky_along computes per
// query. The view is formed as sun_direction_enu forms the sun's, so that at the zenith the
// meridian frame is the limit along view_az_deg.
SkyLight sky_light_toward(const SunPosition& sun, double view_az_deg, double view_el_deg,
                          const SkyModel& model);
// The same for many directions (view_az_deg[i], view_el_deg[i]), in parallel (TBB), each into its
// own slot. Throws std::invalid_argument when the sizes differ.
std::vector<SkyLight> sky_light_toward(const SunPosition& sun, std::span<const double> view_az_deg,
                                       std::span<const double> view_el_deg, const SkyModel& model);

// The sun (sun_positions, or the row's own) and the sky (sky_light) for every query, in order.
// The sky of each distinct sun is found once (SunSky), so that the vector-RT sky interpolates its
// field once per sun, not per row. A row whose sun the sky refuses (the vector-RT sky's low-sun
// limit) throws SunRowError naming the first such row.
std::vector<SkySample> sky_along(std::span<const SkyQuery> queries, const SkyModel& model,
                                 const SunSettings& settings = {},
                                 const Progress& progress = {});

}  // namespace polrig
