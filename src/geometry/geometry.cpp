#include "polrig/geometry/geometry.h"

#include <cmath>

#include "polrig/units.h"

namespace polrig {

TableRotation TableRotation::at_deg(double theta_R_deg) {
  const double t = deg2rad(theta_R_deg);
  return {std::cos(t), std::sin(t)};
}

Point2 port_centre(const Eccentricity& e) {
  const double a = deg2rad(e.alpha_IS);
  return {e.L_IS * std::cos(a), e.L_IS * std::sin(a)};
}

Point2 sensor_centre(const Eccentricity& e, double theta_R_deg) {
  const double a = deg2rad(e.alpha_S);
  return TableRotation::at_deg(theta_R_deg) * Point2{e.L_S * std::cos(a), e.L_S * std::sin(a)};
}

std::array<Point2, 6> photodiode_positions(const PhotodiodeRing& ring, const Eccentricity& e,
                                           double theta_R_deg) {
  const Point2 o_s = sensor_centre(e, 0.0);
  const TableRotation rot = TableRotation::at_deg(theta_R_deg);
  std::array<Point2, 6> p;
  for (int m = 0; m < 6; ++m) {
    const double b = deg2rad(ring.beta_deg[m]);
    p[m] = rot * (o_s + ring.L_photo * Point2{std::cos(b), std::sin(b)});
  }
  return p;
}

}  // namespace polrig

namespace polrig {
double sensor_polarization_angle_deg(double theta_R_deg, double polarizer_deg) {
  return wrap_axis_deg(theta_R_deg - polarizer_deg);
}
}  // namespace polrig
