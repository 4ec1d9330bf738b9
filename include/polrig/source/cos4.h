#pragma once
// The analytic integrating-sphere source: a port of uniform radiance whose off-axis irradiance
// on a plane L_o below it falls off as E = E_0·cos⁴φ, tan φ = L/L_o (the sphere manual's law;
// Wang et al. 2019 §3.1). L is the distance from the port axis.
#include "polrig/geometry/geometry.h"

namespace polrig {

struct Cos4Source {
  double L_o = 20.0;  // port plane to photosensitive plane, mm
  double E_0 = 10.0;  // on-axis irradiance, W/m²

  // cos⁴φ = (L_o² / (L_o² + L²))², written without trigonometry.
  double falloff(double L_squared) const {
    const double c2 = L_o * L_o / (L_o * L_o + L_squared);
    return c2 * c2;
  }
  double irradiance(const Point2& p, const Point2& port) const {
    return E_0 * falloff((p - port).squaredNorm());
  }
};

}  // namespace polrig
