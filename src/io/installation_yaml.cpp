// The unit-array installation calibration's reader (include/polrig/io/installation_yaml.h).
#include "polrig/io/installation_yaml.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <string>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "polrig/io/measured.h"
#include "polrig/compass/unit_installation.h"
#include "polrig/quoted.h"
#include "polrig/units.h"
#include "yaml_load.h"

namespace polrig {

namespace {

// The unit's `unit:` number, 1 … n.
std::size_t unit_number(const std::filesystem::path& file, const YAML::Node& entry, std::size_t i, std::size_t n) {
  const YAML::Node u = entry["unit"];
  const std::string key = fmt::format("units[{}].unit", i);
  if (!u || !u.IsScalar()) refuse_key(file, entry, key, "expected the unit's number");
  const double v = number_at(file, u, key);
  if (v != std::floor(v) || v < 1 || v > static_cast<double>(n))
    refuse_key(file, u, key, fmt::format("expected a unit number 1 … {} (the dataset's layout), got {}", n,
                                         quoted_value(u.Scalar())));
  return static_cast<std::size_t>(v);
}

// The layout the fit was made for against the dataset's: the largest angle between like axes.
void check_layout(const std::filesystem::path& file, const YAML::Node& entry, const std::string& key,
                  const Axes3& nominal, std::size_t unit) {
  const YAML::Node a = entry["nominal_axes_b"];
  if (!a)
    refuse_key(file, entry, key,
               "missing: the file does not say which layout it was fitted for (written by a polrig before "
               "it recorded it); run polrig calibrate --method unit-array again");
  if (!a.IsSequence() || a.size() != 3) refuse_key(file, a, key, "expected the unit's X, Y, Z axes in the body frame, three triples");
  double worst = 0;
  for (std::size_t c = 0; c < 3; ++c) {
    if (!a[c].IsSequence() || a[c].size() != 3) refuse_key(file, a[c], key, "expected a triple per axis");
    Vec3 v{};
    for (std::size_t k = 0; k < 3; ++k) v[k] = number_at(file, a[c][k], key);
    if (!(vec3::norm(v) > 0.5 && vec3::norm(v) < 1.5)) refuse_key(file, a[c], key, "expected a unit vector per axis");
    const double cos = std::clamp(vec3::dot(v, nominal[c]) / (vec3::norm(v) * vec3::norm(nominal[c])), -1.0, 1.0);
    worst = std::max(worst, std::acos(cos));
  }
  if (!(worst <= 1e-6 * kDeg))
    refuse_key(file, a, key,
               fmt::format("unit {} was fitted for another layout: its nominal axes are {:.4g}° from the dataset's "
                           "unit {} (the rig's device.units); calibrate this layout's dataset instead",
                           unit, rad2deg(worst), unit));
}

}  // namespace

std::vector<UnitMount> read_installation(const std::filesystem::path& file, const std::vector<UnitMount>& nominal) {
  const YAML::Node root = load_yaml<DataError>(read_yaml_file<DataError>(file, "calibration file"), file.string(),
                                               "a unit-array calibration.yaml nests 4 levels", kMaxYamlBytes);
  refuse_duplicate_keys<DataError>(root, file.string());
  if (!root.IsMap()) throw DataError(fmt::format("{}: expected a map of keys (units, elevation_error_deg)", file.string()));
  refuse_unknown_keys(file, root, {"units", "elevation_error_deg"}, "", "units, elevation_error_deg");
  const YAML::Node units = root["units"];
  if (!units || !units.IsSequence()) refuse_key(file, root, "units", "expected a list of units (polrig calibrate --method unit-array)");
  const std::size_t n = nominal.size();
  if (units.size() != n)
    refuse_key(file, units, "units", fmt::format("expected {} units (the dataset's layout), got {}", n, units.size()));
  std::vector<UnitMount> out(n);
  std::vector<int> seen_at(n, -1);
  for (std::size_t i = 0; i < n; ++i) {
    const YAML::Node entry = units[i];
    if (!entry.IsMap()) refuse_key(file, entry, fmt::format("units[{}]", i), "expected a map (unit, error_deg, converged, ...)");
    refuse_unknown_keys(file, entry,
                        {"unit", "error_deg", "standard_error_deg", "rms_before_deg", "rms_after_deg", "used",
                         "iterations", "termination", "converged", "nominal_axes_b"},
                        fmt::format("units[{}].", i), "unit, error_deg, converged, nominal_axes_b, ...");
    const std::size_t u = unit_number(file, entry, i, n);
    if (seen_at[u - 1] >= 0)
      refuse_key(file, entry["unit"], fmt::format("units[{}].unit", i),
                 fmt::format("unit {} is given twice (first as units[{}])", u, seen_at[u - 1]));
    seen_at[u - 1] = static_cast<int>(i);
    const UnitMount& nominal_u = nominal[u - 1];
    check_layout(file, entry, fmt::format("units[{}].nominal_axes_b (unit {})", i, u), nominal_u.C_mb, u);
    // A unit its fit did not determine (converged: false) keeps its nominal frame, as
    // InstallationRun::mounts() does.
    const YAML::Node converged = entry["converged"];
    if (!converged || !converged.IsScalar() || (converged.Scalar() != "true" && converged.Scalar() != "false"))
      refuse_key(file, entry, fmt::format("units[{}].converged (unit {})", i, u), "expected true or false");
    if (converged.Scalar() == "false") {
      out[u - 1] = nominal_u;
      continue;
    }
    const YAML::Node e = entry["error_deg"];
    const std::string key = fmt::format("units[{}].error_deg (unit {})", i, u);
    if (!e || !e.IsSequence() || e.size() != 3) refuse_key(file, entry, key, "expected three angles in degrees");
    std::array<double, 3> d{};
    for (std::size_t a = 0; a < 3; ++a) {
      d[a] = number_at(file, e[a], key);
      if (!(std::abs(d[a]) <= 10))
        refuse_key(file, e[a], key, fmt::format("expected a mounting error within ±10°, got {}", quoted_value(e[a].Scalar())));
    }
    out[u - 1] = {installed_frame(nominal_u.C_mb, d)};
  }
  return out;
}

}  // namespace polrig
