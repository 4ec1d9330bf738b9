#include "polrig/report/sky_reports.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <future>

#include <fmt/format.h>

#include "polrig/io/csv.h"
#include "polrig/io/plot.h"
#include "polrig/sky/berry_fit.h"
#include "polrig/sky/vector_rt.h"
#include "polrig/sky/sky_map.h"
#include "polrig/sky/vector_rt_sky.h"

namespace polrig {

namespace fs = std::filesystem;

namespace {

// The previews need no more than 512 pixels across (the PNG's disc is ~550 px): larger maps are
// sampled every `stride` pixels (nearest, so that AoP is never averaged across its 0/180 seam).
int preview_stride(int size) { return (size + 511) / 512; }

// A float layer for gnuplot, `outside` beyond the horizon (drawn as background): −1 for layers
// that are never negative, kSignedOutside for signed ones.
constexpr float kSignedOutside = -1000.0f;
void write_f32(const fs::path& path, const SkyMap& map, const std::vector<float>& layer, float outside = -1.0f) {
  const int stride = preview_stride(map.size), m = (map.size + stride - 1) / stride;
  std::string bytes(static_cast<std::size_t>(m) * static_cast<std::size_t>(m) * sizeof(float), '\0');
  std::size_t out = 0;
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < m; ++i) {
      const std::size_t k = static_cast<std::size_t>(std::min(j * stride + stride / 2, map.size - 1)) *
                                static_cast<std::size_t>(map.size) +
                            static_cast<std::size_t>(std::min(i * stride + stride / 2, map.size - 1));
      const float v = map.inside[k] > 0 ? layer[k] : outside;
      std::memcpy(bytes.data() + out, &v, sizeof(float));
      out += sizeof(float);
    }
  write_text_file(path, bytes);
}

// One panel's gnuplot commands: the layer as an image, seen from below with N, S, E, W, the 0°,
// 30° and 60° elevation circles and the sun; `scale` shrinks the labels for a multiplot's panels.
std::string panel_script(const SkyMap& map, const std::string& layer, const std::string& title, double lo,
                         double hi, const std::string& palette, double scale = 1) {
  const int n = map.size;
  double sx, sy;
  sky_map_pixel(n, sun_direction_enu(map.sun), sx, sy);
  const double h = n / 2.0;
  const int big = static_cast<int>(std::lround(16 * scale)), small = static_cast<int>(std::lround(9 * scale));
  std::string s = "unset object\nunset label\n";
  s += fmt::format("set title \"{}\" noenhanced\n", title);
  s += "set size square\nunset xtics\nunset ytics\nunset key\nset border 0\n";
  s += fmt::format("set xrange [-0.06*{0}:1.06*{0}]\nset yrange [1.06*{0}:-0.06*{0}]\n", n);
  s += fmt::format("set cbrange [{}:{}]\n{}\n", lo, hi, palette);
  // Seen from below looking up: N top, E left (sky_map.h).
  s += fmt::format("set label 'N' at {},{} center font ',{}' front\n", h, -0.03 * n, big);
  s += fmt::format("set label 'S' at {},{} center font ',{}' front\n", h, 1.03 * n, big);
  s += fmt::format("set label 'E' at {},{} center font ',{}' front\n", -0.03 * n, h, big);
  s += fmt::format("set label 'W' at {},{} center font ',{}' front\n", 1.03 * n, h, big);
  s += fmt::format("set label 'seen from below, looking up' at {},{} left font ',{}' front\n",
                   -0.05 * n, 1.055 * n, small);
  for (double el : {0.0, 30.0, 60.0})
    s += fmt::format("set object circle at {0},{0} size {1} front fs empty border rgb 'gray40' lw 1\n",
                     h, h * (90 - el) / 90);
  if (map.sun.elevation_deg >= 0)
    s += fmt::format("set object circle at {},{} size {} front fs solid border rgb 'black' fc rgb 'white' lw 2\n",
                     sx, sy, 0.018 * n);
  else
    s += fmt::format("set label 'sun {:.2f}° below the horizon, A_s {:.2f}°' at {},{} left font ',{}' front\n",
                     -map.sun.elevation_deg, map.sun.azimuth_deg, -0.05 * n, -0.055 * n, small + 1);
  const int stride = preview_stride(n), m = (n + stride - 1) / stride;
  s += fmt::format("plot '{}' binary array=({},{}) dx={} dy={} origin=({},{}) format='%float' "
                   "using ($1 < 0 ? NaN : $1) with image\n",
                   layer, m, m, stride, stride, stride / 2 + 0.5, stride / 2 + 0.5);
  return s;
}

std::string where_and_when(const SkyMap& map, const Sky& sky) {
  return fmt::format("{} at {:.4f}°N {:.4f}°E; sun A_s {:.3f}°, h_s {:.3f}°", format_utc(map.time), sky.site.lat_deg,
                     sky.site.lon_deg, map.sun.azimuth_deg, map.sun.elevation_deg);
}

std::string preview_script(const SkyMap& map, const Sky& sky, const std::string& layer,
                           const std::string& png, const std::string& title, double lo, double hi,
                           const std::string& palette) {
  std::string s = fmt::format("set terminal pngcairo size {},{} font ',11'\nset output '{}'\n", 760, 800, png);
  return s + panel_script(map, layer, title + "\\n" + where_and_when(map, sky), lo, hi, palette);
}

constexpr const char* kAopPalette = "set palette model HSV defined (0 0 1 1, 1 1 1 1)";
// Named colours are RGB: the model is set again, since a multiplot keeps the AoP panels' HSV.
constexpr const char* kDopPalette =
    "set palette model RGB defined (0 '#000004', 0.25 '#51127c', 0.5 '#b73779', 0.75 '#fc8961', 1 '#fcfdbf')";

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
  write_f32(dir / "aop_difference.f32", map, d_aop, kSignedOutside);
  write_f32(dir / "dop_ratio.f32", map, ratio);
  // kSignedOutside marks the outside of the AoP difference's file.
  auto aop = std::async(std::launch::async, [&] {
    std::string script = preview_script(map, sky, "aop_difference.f32", "aop_difference.png",
                                        "AoP less single scattering's (deg, meridian frame)", -10, 10,
                                        "set palette defined (0 '#2166ac', 0.5 '#f7f7f7', 1 '#b2182b')");
    const std::string mask = "using ($1 < 0 ? NaN : $1)";
    script.replace(script.find(mask), mask.size(), "using ($1 <= -999 ? NaN : $1)");
    run_gnuplot(dir, "aop_difference.gp", script, {"aop_difference.png"});
  });
  run_gnuplot(dir, "dop_ratio.gp",
              preview_script(map, sky, "dop_ratio.f32", "dop_ratio.png",
                             "DoP over single scattering's sin^2(g)/(1 + cos^2(g))", 0, 1, kDopPalette),
              {"dop_ratio.png"});
  aop.get();
  return {{"aop_difference.png", 1, "AoP less the single-scattering sky's, deg (colour range ±10°)"},
          {"dop_ratio.png", 1, "DoP over sin²γ/(1 + cos²γ): the P_max single scattering would need"}};
}

// The three skies side by side at the map's sun: single scattering (the sky's P_max and radiance
// model), Berry's fitted to the atmosphere's vector-RT sky, and that sky; AoP, DoP, and the
// first two's departures from the exact sky.
std::vector<DatasetFile> report_sky_comparison(const fs::path& dir, const Sky& sky, const VectorRtSettings& atmosphere,
                                               const SkyMap& shown) {
  if (!(shown.sun.elevation_deg >= std::max(min_sun_elevation_deg(atmosphere), VectorRtSky::kMinSunElevationDeg)))
    return {};  // Berry's fit, beside the exact sky, starts at 2°
  constexpr int kSize = 400;
  Sky single = sky, berry = sky, exact = sky;
  single.model.kind = SkyKind::SingleScattering;
  berry.model.kind = SkyKind::Berry;
  berry.model.berry = BerrySkySettings{std::nullopt, std::nullopt, berry_fit(atmosphere)};
  exact.model.kind = SkyKind::VectorRt;
  exact.model.vector_rt = vector_rt_sky(atmosphere);
  const std::array<SkyMap, 3> maps{sky_map(single, kSize), sky_map(berry, kSize), sky_map(exact, kSize)};
  const char* names[3] = {"single", "berry", "exact"};
  double top = 0;
  for (const SkyMap& m : maps) top = std::max(top, double(*std::max_element(m.dop.begin(), m.dop.end())));
  std::vector<std::string> temporary;
  const auto layer = [&](const std::string& name, const std::vector<float>& v, float outside = -1.0f) {
    write_f32(dir / name, maps[2], v, outside);
    temporary.push_back(name);
    return name;
  };
  const auto difference = [&](const std::vector<float>& a, const std::vector<float>& b, bool angle) {
    std::vector<float> d(a.size());
    for (std::size_t k = 0; k < d.size(); ++k)
      d[k] = static_cast<float>(angle ? std::remainder(double(a[k]) - double(b[k]), 180.0) : double(a[k]) - double(b[k]));
    return d;
  };
  const BerryDistances d = berry_distances(berry.model.berry, shown.sun.elevation_deg);
  const std::string titles[3] = {
      fmt::format("single scattering, P_max {:.3g}", sky.model.P_max.at(shown.sun.elevation_deg)),
      fmt::format("Berry, fitted: Babinet {:.1f}°, Brewster {:.1f}°", d.babinet_deg, d.brewster_deg),
      "vector RT, " + atmosphere_text(atmosphere)};
  const std::string diverging = "set palette model RGB defined (0 '#2166ac', 0.5 '#f7f7f7', 1 '#b2182b')";
  std::string s = "set terminal pngcairo size 1500,1530 font ',10'\nset output 'skies_compared.png'\n";
  s += fmt::format("set multiplot layout 3,3 title \"Three skies at one sun: {}\" noenhanced\n", where_and_when(shown, sky));
  for (int i = 0; i < 3; ++i)
    s += panel_script(maps[i], layer(fmt::format("cmp_aop_{}.f32", names[i]), maps[i].aop_deg),
                      "AoP (deg), " + titles[i], 0, 180, kAopPalette, 0.7);
  for (int i = 0; i < 3; ++i)
    s += panel_script(maps[i], layer(fmt::format("cmp_dop_{}.f32", names[i]), maps[i].dop), "DoP, " + titles[i], 0,
                      std::ceil(top * 20) / 20, kDopPalette, 0.7);
  const std::string mask = "using ($1 < 0 ? NaN : $1)", signed_mask = "using ($1 <= -999 ? NaN : $1)";
  for (int i = 0; i < 2; ++i) {
    std::string p = panel_script(maps[i], layer(fmt::format("cmp_daop_{}.f32", names[i]),
                                                difference(maps[i].aop_deg, maps[2].aop_deg, true), kSignedOutside),
                                 std::string("AoP less the vector-RT sky's (deg), ") + (i == 0 ? "single scattering" : "Berry"),
                                 -10, 10, diverging, 0.7);
    p.replace(p.find(mask), mask.size(), signed_mask);
    s += p;
  }
  std::string p = panel_script(maps[1], layer("cmp_ddop_berry.f32", difference(maps[1].dop, maps[2].dop, false), kSignedOutside),
                               "DoP less the vector-RT sky's, Berry", -0.3, 0.3, diverging, 0.7);
  p.replace(p.find(mask), mask.size(), signed_mask);
  s += p + "unset multiplot\n";
  run_gnuplot(dir, "skies_compared.gp", s, {"skies_compared.png"});
  for (const std::string& f : temporary) fs::remove(dir / f);
  fs::remove(dir / "skies_compared.gp");
  return {{"skies_compared.png", 1,
           "single scattering, Berry's sky fitted to the vector-RT sky, and the vector-RT sky of the rig's atmosphere "
           "(sky.rt.*) at the map's sun: AoP, DoP, and the first two's departures from the exact sky"}};
}

}  // namespace

std::vector<DatasetFile> report_sky_previews(const fs::path& dir, const SkyMap& map, const Sky& sky,
                                             const VectorRtSettings& atmosphere) {
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
                               "Angle of polarization χ (deg, meridian frame)", 0, 180, kAopPalette),
                {"aop.png"});
  });
  run_gnuplot(dir, "dop.gp",
              preview_script(map, sky, "dop.f32", "dop.png", "Degree of linear polarization", 0, p_hi, kDopPalette),
              {"dop.png"});
  aop.get();
  std::vector<DatasetFile> files{{"aop.f32", 1, "AoP for the preview (every ceil(size/512)-th pixel): float32, row-major, top row first, -1 outside"},
          {"dop.f32", 1, "DoP for the preview (every ceil(size/512)-th pixel): float32, row-major, top row first, -1 outside"},
          {"aop.png", 1, "AoP preview with the sun marked"},
          {"dop.png", 1, "DoP preview with the sun marked"}};
  if (sky.model.kind != SkyKind::SingleScattering)
    for (DatasetFile& f : report_sky_differences(dir, map, sky)) files.push_back(std::move(f));
  for (DatasetFile& f : report_sky_comparison(dir, sky, atmosphere, map)) files.push_back(std::move(f));
  return files;
}

}  // namespace polrig
