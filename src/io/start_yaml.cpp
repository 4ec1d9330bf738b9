#include "polrig/io/start_yaml.h"

#include <array>
#include <cmath>
#include <filesystem>
#include <numbers>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "polrig/ins/attitude.h"
#include "polrig/units.h"
#include "yaml_load.h"

namespace polrig {
namespace {

struct Range {
  double lo, hi;
  bool lo_open = false;
  std::string_view why;
};

double scalar_in(const std::filesystem::path& file, const YAML::Node& map, const std::string& key, const Range& r,
                 const std::string& name) {
  const YAML::Node n = map[key];
  if (!n) refuse_key(file, map, name, "missing (start.yaml states every key: docs/formats.md §6.17)");
  if (!n.IsScalar()) refuse_key(file, n, name, "expected a number");
  const double v = number_at(file, n, name);
  if (!(r.lo_open ? v > r.lo : v >= r.lo) || !(v <= r.hi))
    refuse_key(file, n, name,
               fmt::format("expected {}{}, {}] ({}), got {}", r.lo_open ? "(" : "[", r.lo, r.hi, r.why, quoted_value(n.Scalar())));
  return v;
}

Eigen::Vector3d triple_in(const std::filesystem::path& file, const YAML::Node& map, const std::string& key,
                          const std::array<Range, 3>& r, const std::string& name, std::string_view what) {
  const YAML::Node n = map[key];
  if (!n) refuse_key(file, map, name, fmt::format("missing: expected {} (docs/formats.md §6.17)", what));
  if (!n.IsSequence() || n.size() != 3) refuse_key(file, n, name, fmt::format("expected a list of three: {}", what));
  Eigen::Vector3d out;
  for (std::size_t i = 0; i < 3; ++i) {
    const double v = number_at(file, n[i], fmt::format("{}[{}]", name, i));
    if (!(r[i].lo_open ? v > r[i].lo : v >= r[i].lo) || !(v <= r[i].hi))
      refuse_key(file, n[i], fmt::format("{}[{}]", name, i),
                 fmt::format("expected {}{}, {}] ({}), got {}", r[i].lo_open ? "(" : "[", r[i].lo, r[i].hi, r[i].why,
                             quoted_value(n[i].Scalar())));
    out[static_cast<Eigen::Index>(i)] = v;
  }
  return out;
}

}  // namespace

StatedStart parse_start_yaml(const std::string& text, std::string_view file_name) {
  const std::filesystem::path file(file_name);
  const YAML::Node root = load_yaml<DataError>(text, file_name, "start.yaml nests 2 levels", kMaxYamlBytes);
  refuse_duplicate_keys<DataError>(root, file_name);
  if (!root.IsMap())
    throw DataError(fmt::format("{}: expected a map of keys (lat_deg, lon_deg, h_m, v_enu_mps, attitude_deg, sigma)",
                                file.string()));
  refuse_unknown_keys(file, root, {"lat_deg", "lon_deg", "h_m", "v_enu_mps", "attitude_deg", "sigma"}, "",
                      "lat_deg, lon_deg, h_m, v_enu_mps, attitude_deg, sigma");
  const Range lat{-kInsMaxLatitudeDeg, kInsMaxLatitudeDeg, false, "the INS's latitudes: its mechanization is singular at the poles"};
  const Range lon{-180, 360, false, "a longitude, east positive"};
  const Range h{-500, 20000, false, "from the Dead Sea shore to an airliner's ceiling, metres above WGS-84"};
  const Range v{-300, 300, false, "m/s: a road or air vehicle"};
  StatedStart s;
  s.state.t_s = 0;
  s.state.lat_rad = deg2rad(scalar_in(file, root, "lat_deg", lat, "lat_deg"));
  s.state.lon_rad = std::remainder(deg2rad(scalar_in(file, root, "lon_deg", lon, "lon_deg")), 2 * std::numbers::pi);
  s.state.h_m = scalar_in(file, root, "h_m", h, "h_m");
  s.state.v_n = triple_in(file, root, "v_enu_mps", {v, v, v}, "v_enu_mps", "east, north and up in m/s");
  const Eigen::Vector3d rph = triple_in(
      file, root, "attitude_deg",
      {Range{-180, 180, true, "roll, right side down positive"}, Range{-90, 90, false, "pitch, nose up positive"},
       Range{-360, 360, false, "heading, clockwise from north"}},
      "attitude_deg", "roll, pitch and heading in degrees");
  s.state.q_bn = Eigen::Quaterniond(C_bn_from_euler({deg2rad(rph[0]), deg2rad(rph[1]), deg2rad(rph[2])}));

  const YAML::Node sigma = root["sigma"];
  if (!sigma) refuse_key(file, root, "sigma", "missing: expected the start's standard deviations (attitude_deg, v_enu_mps, position_m)");
  if (!sigma.IsMap()) refuse_key(file, sigma, "sigma", "expected a map (attitude_deg, v_enu_mps, position_m)");
  refuse_unknown_keys(file, sigma, {"attitude_deg", "v_enu_mps", "position_m"}, "sigma.", "attitude_deg, v_enu_mps, position_m");
  const Range sa{0, 30, true, "degrees, positive; 30° is no alignment at all"};
  const Range sv{0, 100, true, "m/s, positive; 100 m/s is no velocity at all"};
  const Range sp{0, 1e6, true, "metres, positive; 1000 km is a continent"};
  s.sigma.attitude_rad = triple_in(file, sigma, "attitude_deg", {sa, sa, sa}, "sigma.attitude_deg",
                                   "φ_E, φ_N, φ_U in degrees") * (std::numbers::pi / 180);
  s.sigma.velocity_mps = triple_in(file, sigma, "v_enu_mps", {sv, sv, sv}, "sigma.v_enu_mps", "east, north and up in m/s");
  s.sigma.position_m = triple_in(file, sigma, "position_m", {sp, sp, sp}, "sigma.position_m", "north, east and up in metres");
  return s;
}

}  // namespace polrig
