#include "polrig/sky/sun_rows.h"

#include "polrig/sky/vector_rt_sky.h"

#include <stdexcept>
#include <string>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <optional>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace polrig {

InputRange sky_query_range(std::string_view field) {
  if (field == "lat_deg") return {-90, 90, "degrees, north positive"};
  if (field == "lon_deg") return {-180, 180, "degrees, east positive"};
  if (field == "view_az_deg") return {-360, 360, "degrees, from north towards east"};
  if (field == "view_el_deg") return {-90, 90, "degrees above the horizon"};
  if (field == "sun_az_deg") return {-360, 360, "degrees, from north towards east"};
  if (field == "sun_el_deg") return {-90, 90, "degrees above the horizon"};
  throw std::invalid_argument("sky_query_range: no input '" + std::string(field) + "'");
}

namespace {
constexpr double kTrackNodeSpacing_s = 1800;  // SunTrack's default
}  // namespace

std::vector<SunPosition> sun_positions(std::span<const SunRow> rows, const SunSettings& settings,
                                       const Progress& progress) {
  for (std::size_t i = 0; i < rows.size(); ++i) {
    try {
      check_sun_inputs(rows[i].utc, rows[i].site, settings);
    } catch (const std::invalid_argument& e) {
      throw SunRowError(e.what(), i);
    }
  }
  // The rows of each site (in order of first appearance) and their time span.
  struct Group {
    Site site;
    std::size_t rows = 0;
    UtcTime begin, end;
    std::optional<SunTrack> track;
  };
  std::map<std::array<double, 3>, std::size_t> index;
  std::vector<Group> groups;
  std::vector<std::size_t> group_of(rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Site& s = rows[i].site;
    const auto [it, added] = index.try_emplace({s.lat_deg, s.lon_deg, s.height_m}, groups.size());
    if (added) groups.push_back({s, 0, rows[i].utc, rows[i].utc, std::nullopt});
    Group& g = groups[it->second];
    ++g.rows;
    g.begin = std::min(g.begin, rows[i].utc);
    g.end = std::max(g.end, rows[i].utc);
    group_of[i] = it->second;
  }
  for (Group& g : groups) {
    const double nodes = std::ceil((g.end.unix_s - g.begin.unix_s) / kTrackNodeSpacing_s) + 4;
    if (static_cast<double>(g.rows) >= static_cast<double>(kRowsPerTrackNode) * nodes)
      g.track.emplace(g.begin, g.end, g.site, settings, kTrackNodeSpacing_s);
  }
  std::vector<SunPosition> out(rows.size());
  progress.begin("sun positions", static_cast<long long>(rows.size()));
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rows.size(), 256),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        const Group& g = groups[group_of[i]];
                        out[i] = g.track ? g.track->at(rows[i].utc)
                                         : sun_position(rows[i].utc, rows[i].site, settings);
                      }
                      progress.advance(static_cast<long long>(r.size()));
                    });
  progress.finish();
  return out;
}

SunPosition fixed_sun(double azimuth_deg, double elevation_deg) {
  return {azimuth_deg, elevation_deg, 90 - elevation_deg, 0, 0, 0};
}

namespace {
// The viewing direction as a "position" on the sky, so that at the zenith the frame is the
// limit along view_az_deg (cos 90° ≠ 0 in doubles).
Vec3 view_toward(double view_az_deg, double view_el_deg) {
  return sun_direction_enu(fixed_sun(view_az_deg, view_el_deg));
}
}  // namespace

SkyLight sky_light_toward(const SunPosition& sun, double view_az_deg, double view_el_deg,
                          const SkyModel& model) {
  return sky_light(sun_direction_enu(sun), view_toward(view_az_deg, view_el_deg), model);
}

std::vector<SkyLight> sky_light_toward(const SunPosition& sun, std::span<const double> view_az_deg,
                                       std::span<const double> view_el_deg, const SkyModel& model) {
  if (view_az_deg.size() != view_el_deg.size())
    throw std::invalid_argument("sky_light_toward: one elevation per azimuth");
  const SunSky sky(sun_direction_enu(sun), model);
  std::vector<SkyLight> out(view_az_deg.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, out.size(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i)
                        out[i] = sky_light(sky, view_toward(view_az_deg[i], view_el_deg[i]));
                    });
  return out;
}

std::vector<SkySample> sky_along(std::span<const SkyQuery> queries, const SkyModel& model,
                                 const SunSettings& settings, const Progress& progress) {
  std::vector<SunRow> at;
  std::vector<std::size_t> by_ephemeris;
  for (std::size_t i = 0; i < queries.size(); ++i)
    if (!queries[i].sun) at.push_back(queries[i].at), by_ephemeris.push_back(i);
  std::vector<SunPosition> sun(queries.size());
  try {
    const std::vector<SunPosition> found = sun_positions(at, settings, progress);
    for (std::size_t k = 0; k < found.size(); ++k) sun[by_ephemeris[k]] = found[k];
  } catch (const SunRowError& e) {
    throw SunRowError(e.what(), by_ephemeris[e.row]);
  }
  for (std::size_t i = 0; i < queries.size(); ++i)
    if (queries[i].sun) sun[i] = *queries[i].sun;
  // The distinct suns, in order of first appearance; each sky is made once, in parallel.
  std::map<std::pair<double, double>, std::size_t> index;
  std::vector<std::size_t> sky_of(queries.size()), first_row;
  for (std::size_t i = 0; i < queries.size(); ++i) {
    const auto [it, added] = index.try_emplace({sun[i].azimuth_deg, sun[i].elevation_deg}, first_row.size());
    if (added) first_row.push_back(i);
    sky_of[i] = it->second;
  }
  std::vector<std::unique_ptr<const SunSky>> skies(first_row.size());
  for (std::size_t k = 0; k < first_row.size(); ++k)  // the first refused sun, by row
    if (!(sun[first_row[k]].elevation_deg >= min_sun_elevation_deg(model))) {
      try {
        (void)SunSky(sun_direction_enu(sun[first_row[k]]), model);
      } catch (const std::invalid_argument& e) {
        throw SunRowError(e.what(), first_row[k]);
      }
    }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, skies.size(), 16),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t k = r.begin(); k != r.end(); ++k)
                        skies[k] = std::make_unique<const SunSky>(sun_direction_enu(sun[first_row[k]]), model);
                    });
  std::vector<SkySample> out(queries.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, queries.size(), 1024),
                    [&](const tbb::blocked_range<std::size_t>& r) {
                      for (std::size_t i = r.begin(); i != r.end(); ++i) {
                        const SunSky& sky = *skies[sky_of[i]];
                        const Vec3 v = view_toward(queries[i].view_az_deg, queries[i].view_el_deg);
                        out[i] = {sun[i], sky_light(sky, v), sky.absolute_stokes(v)};
                      }
                    });
  return out;
}

}  // namespace polrig
