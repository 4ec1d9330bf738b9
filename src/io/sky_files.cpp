#include "polrig/io/sky_files.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>

#include "polrig/io/csv.h"
#include "polrig/io/exr.h"
#include "polrig/io/plot.h"

namespace polrig {

namespace fs = std::filesystem;

namespace {

std::string sun_yaml(const SkyMap& map, const Sky& sky) {
  std::string y;
  y += "# The sun at the map's time (polrig sky; docs/formats.md). Angles in degrees; azimuth from\n";
  y += "# north towards east; hour angles westwards; topocentric apparent place (ERFA).\n";
  y += fmt::format("utc: {}\n", format_utc(map.time));
  y += fmt::format("site:\n  lat_deg: {}\n  lon_deg: {}\n  height_m: {}\n", sky.site.lat_deg,
                   sky.site.lon_deg, sky.site.height_m);
  y += fmt::format("refraction: {}\n", sky.sun.refraction ? "true" : "false");
  y += fmt::format("ut1_minus_utc_s: {}\n", sky.sun.ut1_minus_utc_s);
  if (sky.sun.delta_T_s) y += fmt::format("delta_T_s: {}\n", *sky.sun.delta_T_s);
  y += fmt::format("azimuth_deg: {}\nelevation_deg: {}\nzenith_deg: {}\n", map.sun.azimuth_deg,
                   map.sun.elevation_deg, map.sun.zenith_deg);
  y += fmt::format("declination_deg: {}\ngha_deg: {}\nlha_deg: {}\n", map.sun.declination_deg,
                   map.sun.gha_deg, map.sun.lha_deg);
  return y;
}

// The previews need no more than 512 pixels across (the PNG's disc is ~550 px): larger maps are
// sampled every `stride` pixels (nearest, so that AoP is never averaged across its 0/180 seam).
int preview_stride(int size) { return (size + 511) / 512; }

// A float layer for gnuplot, −1 outside the horizon (drawn as background).
void write_f32(const fs::path& path, const SkyMap& map, const std::vector<float>& layer) {
  const int stride = preview_stride(map.size), m = (map.size + stride - 1) / stride;
  std::string bytes(static_cast<std::size_t>(m) * static_cast<std::size_t>(m) * sizeof(float), '\0');
  std::size_t out = 0;
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < m; ++i) {
      const std::size_t k = static_cast<std::size_t>(std::min(j * stride + stride / 2, map.size - 1)) *
                                static_cast<std::size_t>(map.size) +
                            static_cast<std::size_t>(std::min(i * stride + stride / 2, map.size - 1));
      const float v = map.inside[k] > 0 ? layer[k] : -1.0f;
      std::memcpy(bytes.data() + out, &v, sizeof(float));
      out += sizeof(float);
    }
  write_text_file(path, bytes);
}

std::string preview_script(const SkyMap& map, const Sky& sky, const std::string& layer,
                           const std::string& png, const std::string& title, double lo, double hi,
                           const std::string& palette) {
  const int n = map.size;
  double sx, sy;
  sky_map_pixel(n, sun_direction_enu(map.sun), sx, sy);
  const double h = n / 2.0;
  std::string s;
  s += fmt::format("set terminal pngcairo size {},{} font ',11'\nset output '{}'\n", 760, 800, png);
  s += fmt::format("set title \"{}\\n{} at {:.4f}°N {:.4f}°E; sun A_s {:.3f}°, h_s {:.3f}°\" noenhanced\n",
                   title, format_utc(map.time), sky.site.lat_deg, sky.site.lon_deg,
                   map.sun.azimuth_deg, map.sun.elevation_deg);
  s += "set size square\nunset xtics\nunset ytics\nunset key\nset border 0\n";
  s += fmt::format("set xrange [-0.06*{0}:1.06*{0}]\nset yrange [1.06*{0}:-0.06*{0}]\n", n);
  s += fmt::format("set cbrange [{}:{}]\n{}\n", lo, hi, palette);
  // Seen from below looking up: N top, E left (sky_map.h).
  s += fmt::format("set label 'N' at {},{} center font ',16' front\n", h, -0.03 * n);
  s += fmt::format("set label 'S' at {},{} center font ',16' front\n", h, 1.03 * n);
  s += fmt::format("set label 'E' at {},{} center font ',16' front\n", -0.03 * n, h);
  s += fmt::format("set label 'W' at {},{} center font ',16' front\n", 1.03 * n, h);
  s += fmt::format("set label 'seen from below, looking up' at {},{} left font ',9' front\n",
                   -0.05 * n, 1.055 * n);
  for (double el : {0.0, 30.0, 60.0})
    s += fmt::format("set object circle at {0},{0} size {1} front fs empty border rgb 'gray40' lw 1\n",
                     h, h * (90 - el) / 90);
  if (map.sun.elevation_deg >= 0)
    s += fmt::format("set object circle at {},{} size {} front fs solid border rgb 'black' fc rgb 'white' lw 2\n",
                     sx, sy, 0.018 * n);
  else
    s += fmt::format("set label 'sun {:.2f}° below the horizon, A_s {:.2f}°' at {},{} left font ',10' front\n",
                     -map.sun.elevation_deg, map.sun.azimuth_deg, -0.05 * n, -0.055 * n);
  const int stride = preview_stride(n), m = (n + stride - 1) / stride;
  s += fmt::format("plot '{}' binary array=({},{}) dx={} dy={} origin=({},{}) format='%float' "
                   "using ($1 < 0 ? NaN : $1) with image\n",
                   layer, m, m, stride, stride, stride / 2 + 0.5, stride / 2 + 0.5);
  return s;
}

}  // namespace

std::vector<DatasetFile> write_sky_map(const fs::path& dir, const SkyMap& map, const Sky& sky,
                                       bool plots) {
  std::vector<DatasetFile> files;
  write_exr(dir / "sky.exr", map.size, map.size,
            {{"S0", map.S0}, {"S1", map.S1}, {"S2", map.S2}, {"AoP", map.aop_deg}, {"DoP", map.dop},
             {"A", map.inside}});
  files.push_back({"sky.exr", 1,
                   "all-sky equidistant fisheye seen from below (N up, E left): S0 S1 S2 (reference "
                   "axis e_theta), AoP (deg, [0,180)), DoP, A (1 inside the horizon)"});
  write_text_file(dir / "sun.yaml", sun_yaml(map, sky));
  files.push_back({"sun.yaml", 1, "the sun: azimuth, elevation, declination, hour angles, site, UTC"});
  if (plots) {
    write_f32(dir / "aop.f32", map, map.aop_deg);
    write_f32(dir / "dop.f32", map, map.dop);
    const double p_hi = std::max(0.05, std::ceil(sky.model.P_max.at(map.sun.elevation_deg) * 20) / 20);
    const std::string script =
        preview_script(map, sky, "aop.f32", "aop.png", "Angle of polarization χ (deg, meridian frame)",
                       0, 180, "set palette model HSV defined (0 0 1 1, 1 1 1 1)") +
        "reset session\n" +
        preview_script(map, sky, "dop.f32", "dop.png", "Degree of linear polarization", 0, p_hi,
                       "set palette defined (0 '#000004', 0.25 '#51127c', 0.5 '#b73779', 0.75 '#fc8961', 1 '#fcfdbf')");
    run_gnuplot(dir, "sky.gp", script, {"aop.png", "dop.png"});
    files.push_back({"aop.f32", 1, "AoP for the preview (every ceil(size/512)-th pixel): float32, row-major, top row first, -1 outside"});
    files.push_back({"dop.f32", 1, "DoP for the preview (every ceil(size/512)-th pixel): float32, row-major, top row first, -1 outside"});
    files.push_back({"aop.png", 1, "AoP preview with the sun marked"});
    files.push_back({"dop.png", 1, "DoP preview with the sun marked"});
  }
  return files;
}

std::string sky_table_csv(const CsvFile& in, const SkyModel& model, const SunSettings& sun) {
  constexpr std::string_view section = "6.12 polrig sky table";
  const std::size_t c_utc = in.column("utc", section), c_lat = in.column("lat_deg", section),
                    c_lon = in.column("lon_deg", section), c_az = in.column("view_az_deg", section),
                    c_el = in.column("view_el_deg", section);
  auto ranged = [&](std::size_t row, std::size_t col, double lo, double hi) {
    const double v = in.number(row, col);
    if (v < lo || v > hi)
      throw DataError(fmt::format("{}:{}: column '{}': {} is outside [{}, {}]", in.origin, in.line[row],
                                  in.header[col], in.rows[row][col], lo, hi));
    return v;
  };
  std::string out = "utc,lat_deg,lon_deg,view_az_deg,view_el_deg,sun_az_deg,sun_el_deg,dop,aop_deg\n";
  for (std::size_t r = 0; r < in.rows.size(); ++r) {
    UtcTime t;
    try {
      t = parse_utc(in.rows[r][c_utc]);
    } catch (const std::invalid_argument& e) {
      throw DataError(fmt::format("{}:{}: column 'utc': {}", in.origin, in.line[r], e.what()));
    }
    const Site site{ranged(r, c_lat, -90, 90), ranged(r, c_lon, -180, 180), 0};
    const double az = ranged(r, c_az, -360, 360), el = ranged(r, c_el, -90, 90);
    const SunPosition s = sun_position(t, site, sun);
    const SunPosition view{az, el, 90 - el, 0, 0, 0};
    const SkyLight light = sky_light(sun_direction_enu(s), sun_direction_enu(view), model);
    for (double v : {s.azimuth_deg, s.elevation_deg, light.dop, light.aop_deg})
      if (!std::isfinite(v))
        throw std::runtime_error(fmt::format("{}:{}: a non-finite result (a bug)", in.origin, in.line[r]));
    out += fmt::format("{},{},{},{},{},{},{},{},{}\n", format_utc(t), site.lat_deg, site.lon_deg, az, el,
                       s.azimuth_deg, s.elevation_deg, light.dop, light.aop_deg);
  }
  return out;
}

}  // namespace polrig
