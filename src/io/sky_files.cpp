#include "polrig/io/sky_files.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string_view>

#include <fmt/format.h>

#include "polrig/io/csv.h"
#include "polrig/io/exr.h"

namespace polrig {

namespace fs = std::filesystem;

std::string sun_yaml(std::string_view what, UtcTime t, const Sky& sky, const SunPosition& sun) {
  std::string y;
  y += fmt::format("# The sun {}; docs/formats.md. Angles in degrees; azimuth from\n", what);
  y += "# north towards east; hour angles westwards; topocentric apparent place (ERFA).\n";
  y += fmt::format("utc: {}\n", format_utc(t));
  y += fmt::format("site:\n  lat_deg: {}\n  lon_deg: {}\n  height_m: {}\n", sky.site.lat_deg,
                   sky.site.lon_deg, sky.site.height_m);
  y += fmt::format("refraction: {}\n", sky.sun.refraction ? "true" : "false");
  y += fmt::format("ut1_minus_utc_s: {}\n", sky.sun.ut1_minus_utc_s);
  if (sky.sun.delta_T_s) y += fmt::format("delta_T_s: {}\n", *sky.sun.delta_T_s);
  y += fmt::format("azimuth_deg: {}\nelevation_deg: {}\nzenith_deg: {}\n", sun.azimuth_deg,
                   sun.elevation_deg, sun.zenith_deg);
  y += fmt::format("declination_deg: {}\ngha_deg: {}\nlha_deg: {}\n", sun.declination_deg,
                   sun.gha_deg, sun.lha_deg);
  return y;
}

std::vector<DatasetFile> write_sky_map(const fs::path& dir, const SkyMap& map, const Sky& sky,
                                       ExrCompression compression) {
  std::vector<DatasetFile> files;
  write_exr(dir / "sky.exr", map.size, map.size,
            {{"S0", map.S0}, {"S1", map.S1}, {"S2", map.S2}, {"AoP", map.aop_deg}, {"DoP", map.dop},
             {"A", map.inside}},
            compression);
  files.push_back({"sky.exr", 1,
                   "all-sky equidistant fisheye seen from below (N up, E left): S0 S1 S2 (reference "
                   "axis e_theta), AoP (deg, [0,180)), DoP, A (1 inside the horizon)"});
  write_text_file(dir / "sun.yaml", sun_yaml("at the map's time (polrig sky)", map.time, sky, map.sun));
  files.push_back({"sun.yaml", 1, "the sun: azimuth, elevation, declination, hour angles, site, UTC"});
  return files;
}

const std::vector<std::string>& sky_table_added_columns() {
  static const std::vector<std::string> added{"sun_az_deg", "sun_el_deg", "dop", "aop_deg", "I_sr", "Q_sr", "U_sr"};
  return added;
}

bool sky_table_fixed_sun(const CsvFile& in) { return in.find_column("sun_az_deg") || in.find_column("sun_el_deg"); }

std::vector<SkyQuery> read_sky_table_input(const CsvFile& in) {
  constexpr std::string_view section = "6.12 polrig sky table";
  const bool fixed = sky_table_fixed_sun(in);
  for (const std::string& added : sky_table_added_columns())
    if (in.find_column(added) && !(fixed && (added == "sun_az_deg" || added == "sun_el_deg")))
      throw DataError(fmt::format("{}:{}: column '{}' is one sky table writes: rename it",
                                  in.origin, in.header_line, added));
  std::size_t c_utc = 0, c_lat = 0, c_lon = 0, c_sun_az = 0, c_sun_el = 0;
  if (fixed) {
    c_sun_az = in.column("sun_az_deg", section), c_sun_el = in.column("sun_el_deg", section);
  } else {
    c_utc = in.column("utc", section), c_lat = in.column("lat_deg", section), c_lon = in.column("lon_deg", section);
  }
  const std::size_t c_az = in.column("view_az_deg", section), c_el = in.column("view_el_deg", section);
  if (in.rows.empty()) throw DataError(fmt::format("{}: no data rows after the header", in.origin));
  auto ranged = [&](std::size_t row, std::size_t col, std::string_view field) {
    const double v = in.number(row, col);
    const InputRange range = sky_query_range(field);
    if (v < range.lo || v > range.hi)
      throw DataError(fmt::format("{}:{}: column '{}': {} is outside [{}, {}]", in.origin, in.line[row],
                                  in.header[col], in.rows[row][col], range.lo, range.hi));
    return v;
  };
  std::vector<SkyQuery> queries(in.rows.size());
  for (std::size_t r = 0; r < in.rows.size(); ++r) {
    SkyQuery& q = queries[r];
    if (fixed) {
      q.sun = fixed_sun(ranged(r, c_sun_az, "sun_az_deg"), ranged(r, c_sun_el, "sun_el_deg"));
    } else {
      try {
        q.at.utc = parse_utc(in.rows[r][c_utc]);
      } catch (const std::invalid_argument& e) {
        throw DataError(fmt::format("{}:{}: column 'utc': {}", in.origin, in.line[r], e.what()));
      }
      q.at.site = {ranged(r, c_lat, "lat_deg"), ranged(r, c_lon, "lon_deg"), 0};
    }
    q.view_az_deg = ranged(r, c_az, "view_az_deg");
    q.view_el_deg = ranged(r, c_el, "view_el_deg");
  }
  return queries;
}

std::string sky_table_csv(const CsvFile& in, std::span<const SkySample> samples) {
  if (samples.size() != in.rows.size())
    throw std::logic_error("sky_table_csv: one sample per input row expected");
  const bool fixed = sky_table_fixed_sun(in);
  const bool absolute = !samples.empty() && samples.front().absolute.has_value();
  std::vector<std::string> columns;
  for (const std::string& c : sky_table_added_columns())
    if (!(fixed && (c == "sun_az_deg" || c == "sun_el_deg")) && (absolute || !c.ends_with("_sr")))
      columns.push_back(c);
  std::string out;
  for (const std::string& h : in.header) out += h + ",";
  for (std::size_t k = 0; k < columns.size(); ++k) out += columns[k] + (k + 1 < columns.size() ? "," : "\n");
  for (std::size_t r = 0; r < in.rows.size(); ++r) {
    const SkySample& s = samples[r];
    for (const std::string& v : in.rows[r]) out += v + ",";  // as written in the input
    std::vector<double> values;
    if (!fixed) values = {s.sun.azimuth_deg, s.sun.elevation_deg};
    values.insert(values.end(), {s.light.dop, s.light.aop_deg});
    if (absolute) {
      if (!s.absolute) throw std::logic_error("sky_table_csv: every sample or none has an absolute radiance");
      values.insert(values.end(), {(*s.absolute)(0), (*s.absolute)(1), (*s.absolute)(2)});
    }
    for (std::size_t k = 0; k < values.size(); ++k) {
      if (!std::isfinite(values[k]))
        throw std::runtime_error(fmt::format("{}:{}: column '{}' is {}, not finite (a bug); "
                                             "nothing was written", in.origin, in.line[r], columns[k], values[k]));
      out += fmt::format("{}", values[k]);
      out += k + 1 < values.size() ? ',' : '\n';
    }
  }
  return out;
}

}  // namespace polrig
