#pragma once
// All-sky maps: the Rayleigh sky of a `Sky` at its first stop, as an equidistant fisheye.
//
// Projection: seen from below, looking up (as an all-sky camera pointing at the zenith sees it):
// the zenith at the centre, the horizon on the rim (radius size/2 pixels), north at the top and
// east on the LEFT; the image radius is proportional to the zenith angle, r = (θ/90°)·size/2.
// Pixel (i, j): column i from the left, row j from the top, centre at (i + ½, j + ½).
#include <vector>

#include "polrig/sky/sky.h"
#include "polrig/vec3.h"

namespace polrig {

struct SkyMap {
  int size = 0;         // width = height, pixels
  UtcTime time;
  SunPosition sun;
  // Row-major, top row first; outside the horizon circle every layer is 0 and `inside` is 0.
  // Stokes reference axis e_θ of each pixel's direction; AoP χ in degrees, [0°, 180°).
  std::vector<float> S0, S1, S2, aop_deg, dop, inside;
};

// The map at sky.first_stop, size × size pixels (size in [2, 8192]); rows computed in parallel,
// each pixel a pure function of its indices (bit-identical for any thread count).
SkyMap sky_map(const Sky& sky, int size);

// Image position (pixels, from the top-left corner) of an ENU direction at or above the
// horizon, and back: false outside the horizon circle.
void sky_map_pixel(int size, const Vec3& v, double& x, double& y);
bool sky_map_direction(int size, double x, double y, Vec3& v);

}  // namespace polrig
