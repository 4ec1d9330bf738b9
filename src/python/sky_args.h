#pragma once
// Arguments of the sky and navigation bindings, checked with the ranges and words of the CLI's
// options (src/cli/common.cpp's finite_range and parse_site, the CSV readers' column ranges).
#include <cmath>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "convert.h"
#include "polrig/sky/rayleigh.h"
#include "polrig/sky/sun.h"
#include "polrig/sky/sun_rows.h"

namespace polrig::python {

// A scalar option: a finite number in [lo, hi] (the CLI's finite_range), else ValueError
// "p_max: expected a finite number in [1e-06, 1], got 2".
inline void check_option(double v, const char* name, double lo, double hi, const char* unit) {
  if (!std::isfinite(v) || v < lo || v > hi)
    throw py::value_error(fmt::format("{}: expected a finite number in [{}, {}]{}{}, got {}", name, lo,
                                      hi, *unit ? " " : "", unit, v));
}

// Every element in [lo, hi], else ValueError naming the argument, the flat index and the value.
inline void check_range(std::span<const double> v, const char* name, double lo, double hi,
                        const char* what) {
  for (std::size_t i = 0; i < v.size(); ++i)
    if (v[i] < lo || v[i] > hi)
      throw py::value_error(fmt::format("{}: element {} is {}, outside [{}, {}] ({})", name, i,
                                        v[i], lo, hi, what));
}

// check_range with the library's range of a row input (sky_query_range, heading_query_range).
inline void check_input(std::span<const double> v, const char* name, const InputRange& range,
                        const char* what = nullptr) {
  check_range(v, name, range.lo, range.hi, what ? what : range.what);
}

// (lat_deg, lon_deg) or (lat_deg, lon_deg, height_m) with the CLI's --site checks.
inline Site site_of(const py::handle& obj, const char* name) {
  const DoubleArray a = as_array(obj, name, 1);
  if (a.size() != 2 && a.size() != 3)
    throw py::value_error(fmt::format("{}: expected (lat_deg, lon_deg) or (lat_deg, lon_deg, "
                                      "height_m), got {} values", name, a.size()));
  const std::vector<double> v = finite_values(a, name);
  const Site s{v[0], v[1], v.size() == 3 ? v[2] : 0.0};
  if (const auto problem = site_problem(s)) throw py::value_error(fmt::format("{}: {}", name, *problem));
  return s;
}

// Sites as arrays of shape (..., 2) or (..., 3): latitude, longitude and height (0 when absent)
// as arrays of the leading shape.
struct SiteArrays {
  py::object lat, lon, height;
};
inline SiteArrays site_arrays(const py::handle& obj, const char* name) {
  const DoubleArray a = as_array(obj, name, 0);
  if (a.ndim() < 1 || (a.shape(a.ndim() - 1) != 2 && a.shape(a.ndim() - 1) != 3))
    throw py::value_error(fmt::format("{}: expected (lat_deg, lon_deg[, height_m]) or an array "
                                      "of shape (..., 2) or (..., 3)", name));
  const auto column = [&](int k) {
    return a.attr("__getitem__")(py::make_tuple(py::ellipsis(), k));
  };
  const py::module_ np = py::module_::import("numpy");
  return {column(0), column(1),
          a.shape(a.ndim() - 1) == 3 ? column(2) : np.attr("zeros_like")(column(0))};
}

// Sites as broadcast rows (latitude, longitude, height): each through the library's site_problem,
// else ValueError "site[..., 2] (height_m): element 3: height 2e+05 m is outside ...".
inline void check_site_rows(std::span<const double> lat, std::span<const double> lon,
                            std::span<const double> height, const char* name) {
  for (std::size_t i = 0; i < lat.size(); ++i) {
    const Site s{lat[i], lon[i], height[i]};
    if (const auto problem = site_problem(s)) {
      const int k = !site_problem({s.lat_deg, 0, 0}) ? (!site_problem({0, s.lon_deg, 0}) ? 2 : 1) : 0;
      const char* column[] = {"lat_deg", "lon_deg", "height_m"};
      throw py::value_error(fmt::format("{}[..., {}] ({}): element {}: {}", name, k, column[k], i, *problem));
    }
  }
}

// The radiance model by the CLI's --radiance name.
inline SkyRadiance radiance_of(const std::string& name) {
  if (const auto r = parse_sky_radiance(name)) return *r;
  throw py::value_error(fmt::format("radiance '{}': expected one of uniform, rayleigh, cie-clear", name));
}

// None, or an (N, 2) array of (sun elevation in degrees, P_max) rows.
inline std::vector<std::pair<double, double>> p_max_table_of(const py::handle& obj) {
  std::vector<std::pair<double, double>> table;
  if (obj.is_none()) return table;
  const std::vector<double> v = finite_values(as_array(obj, "p_max_table", 2, 2), "p_max_table");
  for (std::size_t i = 0; i + 1 < v.size(); i += 2) table.emplace_back(v[i], v[i + 1]);
  return table;
}

// sun_positions with a row the ephemeris refuses reported as ValueError naming `name` and the
// (flat) element.
inline std::vector<SunPosition> sun_rows_or_error(std::span<const SunRow> rows,
                                                  const SunSettings& settings, const Progress& p,
                                                  const char* name) {
  try {
    return sun_positions(rows, settings, p);
  } catch (const SunRowError& e) {
    throw py::value_error(fmt::format("{} (element {}): {}", name, e.row, e.what()));
  }
}

}  // namespace polrig::python
