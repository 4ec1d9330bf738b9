#include "polrig/device/unit_array.h"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "polrig/random.h"
#include "polrig/units.h"

namespace polrig {

std::vector<UnitPlacement> unit_placements(const UnitArraySpec& spec) {
  std::vector<UnitPlacement> out;
  if (!spec.tilt_deg.empty() || !spec.azimuth_deg.empty()) {
    for (std::size_t i = 0; i < spec.tilt_deg.size() && i < spec.azimuth_deg.size(); ++i)
      out.push_back({spec.tilt_deg[i], spec.azimuth_deg[i], i < spec.roll_deg.size() ? spec.roll_deg[i] : 0.0});
    return out;
  }
  if (spec.zenith_unit) out.push_back({0.0, 0.0, 0.0});
  for (double a : spec.ring_azimuths_deg) out.push_back({spec.ring_tilt_deg, a, 0.0});
  return out;
}

std::optional<UnitArrayProblem> unit_array_problem(const UnitArraySpec& spec) {
  const bool explicit_layout = !spec.tilt_deg.empty() || !spec.azimuth_deg.empty() || !spec.roll_deg.empty();
  if (explicit_layout) {
    if (spec.tilt_deg.size() != spec.azimuth_deg.size())
      return UnitArrayProblem{"device.units.azimuth_deg",
                              fmt::format("expected one azimuth per tilt of device.units.tilt_deg ({}), got {}",
                                          spec.tilt_deg.size(), spec.azimuth_deg.size())};
    if (!spec.roll_deg.empty() && spec.roll_deg.size() != spec.tilt_deg.size())
      return UnitArrayProblem{"device.units.roll_deg",
                              fmt::format("expected one roll per tilt of device.units.tilt_deg ({}), got {}",
                                          spec.tilt_deg.size(), spec.roll_deg.size())};
  }
  const std::size_t n = unit_placements(spec).size();
  if (n == 0)
    return UnitArrayProblem{"device.units.ring_azimuths_deg",
                            "expected at least one unit (device.units.zenith, the ring or an explicit layout)"};
  for (const auto& [path, list] : {std::pair{"device.units.mount_error_x_deg", &spec.mount_error_x_deg},
                                   {"device.units.mount_error_y_deg", &spec.mount_error_y_deg},
                                   {"device.units.mount_error_z_deg", &spec.mount_error_z_deg}})
    if (!list->empty() && list->size() != n)
      return UnitArrayProblem{path, fmt::format("expected one error per unit ({}), got {}", n, list->size())};
  return std::nullopt;
}

Axes3 rotation_x(double deg) {
  const double c = std::cos(deg2rad(deg)), s = std::sin(deg2rad(deg));
  return {Vec3{1, 0, 0}, Vec3{0, c, s}, Vec3{0, -s, c}};
}
Axes3 rotation_y(double deg) {
  const double c = std::cos(deg2rad(deg)), s = std::sin(deg2rad(deg));
  return {Vec3{c, 0, -s}, Vec3{0, 1, 0}, Vec3{s, 0, c}};
}
Axes3 rotation_z(double deg) {
  const double c = std::cos(deg2rad(deg)), s = std::sin(deg2rad(deg));
  return {Vec3{c, s, 0}, Vec3{-s, c, 0}, Vec3{0, 0, 1}};
}
Axes3 rotation_xyz(double x_deg, double y_deg, double z_deg) {
  return vec3::compose(rotation_x(x_deg), vec3::compose(rotation_y(y_deg), rotation_z(z_deg)));
}

Axes3 unit_axes(const UnitPlacement& p) {
  return vec3::compose(rotation_z(p.azimuth_deg), vec3::compose(rotation_y(p.tilt_deg), rotation_z(p.roll_deg)));
}

UnitArrayTruth unit_array_truth(const UnitArraySpec& spec, std::uint64_t seed) {
  if (auto problem = unit_array_problem(spec))
    throw std::invalid_argument(fmt::format("{}: {}", problem->path, problem->message));
  UnitArrayTruth t;
  t.placements = unit_placements(spec);
  t.misalignment_deg = spec.misalignment_deg;
  const Axes3 M = rotation_xyz(spec.misalignment_deg[0], spec.misalignment_deg[1], spec.misalignment_deg[2]);
  constexpr std::uint64_t kStream = 0x554E4954;  // "UNIT"
  for (std::size_t i = 0; i < t.placements.size(); ++i) {
    std::array<double, 3> d{};
    const std::array<const std::vector<double>*, 3> given{&spec.mount_error_x_deg, &spec.mount_error_y_deg,
                                                          &spec.mount_error_z_deg};
    for (std::size_t a = 0; a < 3; ++a)
      d[a] = !given[a]->empty() ? (*given[a])[i]
                                : spec.mount_error_sd_deg * standard_normal(seed, kStream, i, a);
    t.mount_error_deg.push_back(d);
    const Axes3 C = unit_axes(t.placements[i]);
    t.nominal.push_back(C);
    t.actual.push_back(vec3::compose(M, vec3::compose(C, rotation_xyz(d[0], d[1], d[2]))));
  }
  return t;
}

}  // namespace polrig
