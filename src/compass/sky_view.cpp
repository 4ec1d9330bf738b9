// The forward model of compass/heading.h through the sky model (kept apart from the solver, which
// needs no sky).
#include <cmath>
#include <limits>

#include "polrig/compass/heading.h"

namespace polrig {

BodySkyView sky_view_body(const Vec3& sun_enu, double heading_deg, const Tilt& tilt,
                          const SkyModel& model) {
  check_sun_enu(sun_enu);
  const Vec3 v = body_to_enu({0.0, 0.0, 1.0}, heading_deg, tilt);
  const SkyLight light = sky_light(sun_enu, v, model);
  if (vec3::norm(light.e_vector) == 0.0)
    return {std::numeric_limits<double>::quiet_NaN(), light.dop};
  return {aop_body_deg(light.e_vector, heading_deg, tilt), light.dop};
}

}  // namespace polrig
