#include "polrig/ins/earth.h"

#include <GeographicLib/Constants.hpp>
#include <GeographicLib/NormalGravity.hpp>

#include <cmath>

#include "polrig/units.h"

namespace polrig {

EarthRadii earth_radii(double lat_rad) {
  const double a = GeographicLib::Constants::WGS84_a();
  const double f = GeographicLib::Constants::WGS84_f();
  const double e2 = f * (2.0 - f);
  const double s = std::sin(lat_rad);
  const double w2 = 1.0 - e2 * s * s;
  const double w = std::sqrt(w2);
  return {a * (1.0 - e2) / (w2 * w), a / w};
}

double normal_gravity(double lat_rad, double h_m) {
  double gamma_y = 0, gamma_z = 0;
  GeographicLib::NormalGravity::WGS84().Gravity(rad2deg(lat_rad), h_m, gamma_y, gamma_z);
  return -gamma_z;
}

Eigen::Vector3d gravity_n(double lat_rad, double h_m) {
  return {0.0, 0.0, -normal_gravity(lat_rad, h_m)};
}

GravityGradient gravity_gradient(double lat_rad, double h_m) {
  const double dL = 1e-4, dh = 10.0;
  return {(normal_gravity(lat_rad + dL, h_m) - normal_gravity(lat_rad - dL, h_m)) / (2 * dL),
          (normal_gravity(lat_rad, h_m + dh) - normal_gravity(lat_rad, h_m - dh)) / (2 * dh)};
}

Eigen::Vector3d omega_ie_n(double lat_rad) {
  return {0.0, kEarthRate * std::cos(lat_rad), kEarthRate * std::sin(lat_rad)};
}

Eigen::Vector3d omega_en_n(const Eigen::Vector3d& v_n, double lat_rad, double h_m) {
  const EarthRadii r = earth_radii(lat_rad);
  const double RNh = r.R_N + h_m;
  return {-v_n.y() / (r.R_M + h_m), v_n.x() / RNh, v_n.x() * std::tan(lat_rad) / RNh};
}

}  // namespace polrig
