#include "polrig/sky/sky_map.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <tbb/parallel_for.h>

namespace polrig {

void sky_map_pixel(int size, const Vec3& v, double& x, double& y) {
  const double half = size / 2.0;
  const double theta = std::acos(std::max(-1.0, std::min(1.0, v[2])));
  const double r = theta / (M_PI / 2) * half, rho = std::hypot(v[0], v[1]);
  // Looking up: north (+y) at the top, east (+x) on the left.
  const double sx = rho > 0 ? v[0] / rho : 0, sy = rho > 0 ? v[1] / rho : 0;
  x = half - r * sx;
  y = half - r * sy;
}

bool sky_map_direction(int size, double x, double y, Vec3& v) {
  const double half = size / 2.0;
  const double east = (half - x) / half, north = (half - y) / half;
  const double r = std::hypot(east, north);
  if (r > 1) return false;
  const double theta = r * (M_PI / 2);
  const double s = r > 0 ? std::sin(theta) / r : 0;
  v = {east * s, north * s, std::cos(theta)};
  return true;
}

SkyMap sky_map(const Sky& sky, int size) {
  if (size < 2 || size > 8192)
    throw std::invalid_argument("sky map: size " + std::to_string(size) + " is outside [2, 8192]");
  check_sky_model(sky.model);
  SkyMap map;
  map.size = size;
  map.time = sky.first_stop;
  map.sun = sun_position(sky.first_stop, sky.site, sky.sun);
  const SunSky sun_sky(sun_direction_enu(map.sun), sky.model);  // one sun: its sky found once
  const std::size_t n = static_cast<std::size_t>(size) * static_cast<std::size_t>(size);
  for (auto* layer : {&map.S0, &map.S1, &map.S2, &map.aop_deg, &map.dop, &map.inside})
    layer->assign(n, 0.0f);
  tbb::parallel_for(0, size, [&](int j) {
    for (int i = 0; i < size; ++i) {
      Vec3 v;
      if (!sky_map_direction(size, i + 0.5, j + 0.5, v)) continue;
      const SkyLight light = sky_light(sun_sky, v);
      const Stokes st = sky_stokes(light);
      const std::size_t k = static_cast<std::size_t>(j) * static_cast<std::size_t>(size) +
                            static_cast<std::size_t>(i);
      map.S0[k] = static_cast<float>(st(0));
      map.S1[k] = static_cast<float>(st(1));
      map.S2[k] = static_cast<float>(st(2));
      const float chi = static_cast<float>(light.aop_deg);
      map.aop_deg[k] = chi < 180.0f ? chi : 0.0f;  // 179.9999999 rounds up in float
      map.dop[k] = static_cast<float>(light.dop);
      map.inside[k] = 1;
    }
  });
  return map;
}

}  // namespace polrig
