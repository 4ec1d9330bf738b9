#include "polrig/geometry/geometry.h"

#include <cmath>
#include <cstring>

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

namespace {
// (cos β_m, sin β_m) of the ring's angles. A sweep asks for them at every grid point (twice) and
// rarely changes them, so each thread keeps those of the last angles it was given: the values
// std::cos and std::sin give, computed once (a cache keyed on the angles' bits, not an
// approximation).
const std::array<Point2, 6>& ring_directions(const std::array<double, 6>& beta_deg) {
  thread_local bool known = false;
  thread_local std::array<double, 6> angles;
  thread_local std::array<Point2, 6> directions;
  if (!known || std::memcmp(angles.data(), beta_deg.data(), sizeof angles) != 0) {
    for (std::size_t m = 0; m < 6; ++m) {
      const double b = deg2rad(beta_deg[m]);
      directions[m] = Point2{std::cos(b), std::sin(b)};
    }
    angles = beta_deg;
    known = true;
  }
  return directions;
}
}  // namespace

std::array<Point2, 6> photodiode_positions(const PhotodiodeRing& ring, const Eccentricity& e,
                                           double theta_R_deg) {
  const Point2 o_s = sensor_centre(e, 0.0);
  const TableRotation rot = TableRotation::at_deg(theta_R_deg);
  const std::array<Point2, 6>& direction = ring_directions(ring.beta_deg);
  std::array<Point2, 6> p;
  for (std::size_t m = 0; m < 6; ++m) p[m] = rot * (o_s + ring.L_photo * direction[m]);
  return p;
}

}  // namespace polrig

namespace polrig {
double sensor_polarization_angle_deg(double theta_R_deg, double polarizer_deg) {
  return wrap_axis_deg(theta_R_deg - polarizer_deg);
}
}  // namespace polrig
