#include "polrig/report/sky_reports.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <future>

#include <fmt/format.h>

#include "polrig/io/csv.h"
#include "polrig/io/plot.h"
#include "polrig/sky/sky_map.h"

namespace polrig {

namespace fs = std::filesystem;

namespace {

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

// Beside a sky that is not single scattering: its AoP less single scattering's, wrapped to
// (−90°, 90°], and its DoP over single scattering's with P_max = 1, sin²γ/(1 + cos²γ) (the
// P_max single scattering would need at each point; spec skies.md §1).
std::vector<DatasetFile> report_sky_differences(const fs::path& dir, const SkyMap& map, const Sky& sky) {
  Sky single = sky;
  single.model = SkyModel{};
  single.model.P_max.constant = 1;
  const SkyMap ss = sky_map(single, map.size);
  std::vector<float> d_aop(map.aop_deg.size()), ratio(map.dop.size());
  for (std::size_t k = 0; k < d_aop.size(); ++k) {
    d_aop[k] = static_cast<float>(std::remainder(double(map.aop_deg[k]) - double(ss.aop_deg[k]), 180.0));
    ratio[k] = ss.dop[k] > 1e-6f ? map.dop[k] / ss.dop[k] : 0.0f;
  }
  write_f32(dir / "aop_difference.f32", map, d_aop);
  write_f32(dir / "dop_ratio.f32", map, ratio);
  // −1 marks the outside in the f32 files: the AoP difference's plot shows everything above −90.
  auto aop = std::async(std::launch::async, [&] {
    std::string script = preview_script(map, sky, "aop_difference.f32", "aop_difference.png",
                                        "AoP less single scattering's (deg, meridian frame)", -10, 10,
                                        "set palette defined (0 '#2166ac', 0.5 '#f7f7f7', 1 '#b2182b')");
    const std::string mask = "using ($1 < 0 ? NaN : $1)";
    script.replace(script.find(mask), mask.size(), "using ($1 <= -90 ? NaN : $1)");
    run_gnuplot(dir, "aop_difference.gp", script, {"aop_difference.png"});
  });
  run_gnuplot(dir, "dop_ratio.gp",
              preview_script(map, sky, "dop_ratio.f32", "dop_ratio.png",
                             "DoP over single scattering's sin^2(g)/(1 + cos^2(g))", 0, 1,
                             "set palette defined (0 '#000004', 0.25 '#51127c', 0.5 '#b73779', 0.75 '#fc8961', 1 '#fcfdbf')"),
              {"dop_ratio.png"});
  aop.get();
  return {{"aop_difference.png", 1, "AoP less the single-scattering sky's, deg (colour range ±10°)"},
          {"dop_ratio.png", 1, "DoP over sin²γ/(1 + cos²γ): the P_max single scattering would need"}};
}

}  // namespace

std::vector<DatasetFile> report_sky_previews(const fs::path& dir, const SkyMap& map, const Sky& sky) {
  write_f32(dir / "aop.f32", map, map.aop_deg);
  write_f32(dir / "dop.f32", map, map.dop);
  const double top = sky.model.kind == SkyKind::SingleScattering
                         ? sky.model.P_max.at(map.sun.elevation_deg)
                         : *std::max_element(map.dop.begin(), map.dop.end());
  const double p_hi = std::max(0.05, std::ceil(top * 20) / 20);
  // Two gnuplot processes at once: each preview takes ~0.3 s of gnuplot's single thread.
  auto aop = std::async(std::launch::async, [&] {
    run_gnuplot(dir, "aop.gp",
                preview_script(map, sky, "aop.f32", "aop.png",
                               "Angle of polarization χ (deg, meridian frame)", 0, 180,
                               "set palette model HSV defined (0 0 1 1, 1 1 1 1)"),
                {"aop.png"});
  });
  run_gnuplot(dir, "dop.gp",
              preview_script(map, sky, "dop.f32", "dop.png", "Degree of linear polarization", 0,
                             p_hi, "set palette defined (0 '#000004', 0.25 '#51127c', 0.5 "
                                   "'#b73779', 0.75 '#fc8961', 1 '#fcfdbf')"),
              {"dop.png"});
  aop.get();
  std::vector<DatasetFile> files{{"aop.f32", 1, "AoP for the preview (every ceil(size/512)-th pixel): float32, row-major, top row first, -1 outside"},
          {"dop.f32", 1, "DoP for the preview (every ceil(size/512)-th pixel): float32, row-major, top row first, -1 outside"},
          {"aop.png", 1, "AoP preview with the sun marked"},
          {"dop.png", 1, "DoP preview with the sun marked"}};
  if (sky.model.kind != SkyKind::SingleScattering)
    for (DatasetFile& f : report_sky_differences(dir, map, sky)) files.push_back(std::move(f));
  return files;
}

}  // namespace polrig
