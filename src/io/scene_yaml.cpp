#include "polrig/io/scene_yaml.h"
#include "polrig/quoted.h"

#include <cmath>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "polrig/rig/keys.h"
#include "polrig/vec3.h"
#include "yaml_load.h"

namespace polrig {
namespace {

// Reads one mapping with a fixed set of keys; every key read is remembered, and finish()
// rejects the rest. Errors: "file:line: key 'a.b': expected …, got …".
class MapReader {
 public:
  MapReader(const std::string& file, const YAML::Node& node, std::string path)
      : file_(file), node_(node), path_(std::move(path)) {
    if (node_ && !node_.IsMap() && !node_.IsNull())
      throw RigError(fmt::format("{}:{}: key '{}': expected a section (a mapping of keys)", file_,
                                 node_.Mark().line + 1, path_));
  }

  template <class Ok>
  double checked_real(const char* key, double def, Ok ok, const std::string& expects) {
    const YAML::Node n = take(key);
    if (!n) return def;
    double v = 0;
    try {
      if (!n.IsScalar()) throw YAML::Exception(n.Mark(), "");
      v = parse_finite_number(n.Scalar(), key);
    } catch (const std::exception&) {
      fail(n, key, fmt::format("expected {}, got {}", expects, shown(n)));
    }
    if (!ok(v)) fail(n, key, fmt::format("expected {}, got {}", expects, quoted_value(n.Scalar())));
    return v;
  }
  double real(const char* key, double def, bool (*ok)(double), const char* expects) {
    return checked_real(key, def, ok, expects);
  }
  // A value in a range: "expected a length in [10, 10000] mm, got …".
  double real(const char* key, double def, const RealRange& r, const char* noun, const char* unit) {
    return checked_real(key, def, [&r](double v) { return r.contains(v); },
                        fmt::format("{} in {}{}{}", noun, r.text(), *unit ? " " : "", unit));
  }
  long long integer(const char* key, long long def, long long lo, long long hi) {
    const YAML::Node n = take(key);
    if (!n) return def;
    const std::string expects = fmt::format("an integer in [{}, {}]", lo, hi);
    double v = 0;
    try {
      v = parse_finite_number(n.IsScalar() ? n.Scalar() : "", key);
    } catch (const std::exception&) {
      fail(n, key, fmt::format("expected {}, got {}", expects, shown(n)));
    }
    if (v != std::floor(v) || v < static_cast<double>(lo) || v > static_cast<double>(hi))
      fail(n, key, fmt::format("expected {}, got {}", expects, quoted_value(n.Scalar())));
    return static_cast<long long>(v);
  }
  Vec3 vec3(const char* key, Vec3 def) {
    const YAML::Node n = take(key);
    if (!n) return def;
    if (!n.IsSequence() || n.size() != 3) fail(n, key, fmt::format("expected [x, y, z] in mm, got {}", shown(n)));
    Vec3 v;
    for (std::size_t i = 0; i < 3; ++i) {
      try {
        v[i] = parse_finite_number(n[i].IsScalar() ? n[i].Scalar() : "", key);
      } catch (const std::exception&) {
        fail(n, key, "expected three finite numbers");
      }
    }
    return v;
  }
  std::string text(const char* key, std::string def, const std::set<std::string>& allowed) {
    const YAML::Node n = take(key);
    if (!n) return def;
    if (!n.IsScalar() || !allowed.count(n.Scalar())) {
      std::string list;
      for (const std::string& a : allowed) list += (list.empty() ? "" : " or ") + ("\"" + a + "\"");
      fail(n, key, fmt::format("expected {}, got {}", list, shown(n)));
    }
    return n.Scalar();
  }
  YAML::Node section(const char* key) { return take(key); }
  std::string path(const char* key) const { return path_.empty() ? key : path_ + "." + key; }
  int line_of(const char* key) const {
    const YAML::Node n = node_ ? node_[key] : YAML::Node();
    return n ? n.Mark().line + 1 : (node_ ? node_.Mark().line + 1 : 0);
  }
  [[noreturn]] void fail_key(const char* key, const std::string& message) const {
    throw RigError(fmt::format("{}:{}: key '{}': {}", file_, line_of(key), path(key), message));
  }

  void finish() const {
    if (!node_ || !node_.IsMap()) return;
    for (auto it = node_.begin(); it != node_.end(); ++it) {
      const std::string key = it->first.IsScalar() ? it->first.Scalar() : "?";
      if (!used_.count(key))
        throw RigError(fmt::format("{}:{}: key '{}': unknown key (see docs/formats.md, \"Scene "
                                   "files\")", file_, it->first.Mark().line + 1, path(key.c_str())));
    }
  }

 private:
  const std::string& file_;
  YAML::Node node_;
  std::string path_;
  std::set<std::string> used_;

  YAML::Node take(const char* key) {
    used_.insert(key);
    // An undefined node for a missing key (a default Node would be a defined null). Look up
    // through a const node: a non-const operator[] would insert the missing key.
    if (!node_ || !node_.IsMap()) return YAML::Node(YAML::NodeType::Undefined);
    const YAML::Node& map = node_;
    const YAML::Node n = map[key];
    return n ? n : YAML::Node(YAML::NodeType::Undefined);
  }
  static std::string shown(const YAML::Node& n) {
    if (n.IsScalar()) return fmt::format("'{}'", quoted_value(n.Scalar()));
    if (n.IsSequence()) return "a list";
    if (n.IsMap()) return "a mapping";
    return "nothing";
  }
  [[noreturn]] void fail(const YAML::Node& n, const char* key, const std::string& message) const {
    throw RigError(fmt::format("{}:{}: key '{}': {}", file_, n.Mark().line + 1, path(key), message));
  }
};

// Ranges of scene values: physical bounds of a laboratory sphere, inside what the tracer (Embree's
// single-precision rays, |coordinate| < 1.8e18) and the irradiance formulas can represent.
constexpr RealRange kSphereDiameter{10, 10000};  // 1 cm to 10 m
constexpr RealRange kPortDiameter{1, 10000};     // and smaller than the sphere
constexpr RealRange kReflectance{0, 0.999};      // a photon makes ~1/(1 − ρ) bounces
constexpr RealRange kTransmittance{0, 1};
constexpr RealRange kFilmTransmittance{0.01, 1};  // at 0 no light reaches the sensor
constexpr RealRange kAxisRange{-360, 360};
constexpr RealRange kLampPower{1e-3, 1e4};        // 1 mW to 10 kW
constexpr RealRange kBaffleRadius{0.1, 10000};    // its irradiance divides by its area

bool lamp_radius(double v) { return v == 0 || (v >= 0.1 && v <= 10000); }

}  // namespace

SceneSpec parse_scene(std::string_view text, std::string_view origin) {
  const std::string file(origin);
  const YAML::Node root = load_yaml(std::string(text), file, "a scene file nests 3 levels");
  if (!root.IsMap() && !root.IsNull())
    throw RigError(fmt::format("{}: expected a mapping of scene sections (sphere, port, lamps, "
                               "baffles, sensor, trace)", file));
  SceneSpec s;
  MapReader top(file, root, "");

  MapReader sphere(file, top.section("sphere"), "sphere");
  s.sphere.diameter = sphere.real("diameter", s.sphere.diameter, kSphereDiameter, "a length", "mm");
  s.sphere.reflectance = sphere.real("reflectance", s.sphere.reflectance, kReflectance, "a reflectance", "");
  sphere.finish();

  MapReader port(file, top.section("port"), "port");
  s.port.diameter = port.real("diameter", s.port.diameter, kPortDiameter, "a length", "mm");
  if (s.port.diameter >= s.sphere.diameter)
    port.fail_key("diameter", fmt::format("expected a port smaller than the sphere ({} mm), got {}",
                                          s.sphere.diameter, s.port.diameter));
  {
    MapReader film(file, port.section("polarizer"), "port.polarizer");
    s.port.polarizer.axis_deg = film.real("axis_deg", s.port.polarizer.axis_deg, kAxisRange, "an angle", "deg");
    s.port.polarizer.tau_M = film.real("tau_M", s.port.polarizer.tau_M, kFilmTransmittance, "a transmittance", "");
    s.port.polarizer.tau_m = film.real("tau_m", s.port.polarizer.tau_m, kTransmittance, "a transmittance", "");
    if (!(s.port.polarizer.tau_m < s.port.polarizer.tau_M))
      film.fail_key("tau_m", fmt::format("expected tau_m < tau_M ({}), got {}", s.port.polarizer.tau_M,
                                         s.port.polarizer.tau_m));
    film.finish();
  }
  port.finish();

  const double R = s.sphere.radius();
  // At most `most` entries: every lamp is evaluated at every point of the wall field, every baffle
  // is an Embree primitive and a tally.
  const auto read_list = [&](const char* key, std::size_t most, auto& out, auto read_one) {
    const YAML::Node n = top.section(key);
    if (!n) return;
    if (!n.IsSequence())
      throw RigError(fmt::format("{}:{}: key '{}': expected a list", file, n.Mark().line + 1, key));
    if (n.size() > most)
      throw RigError(fmt::format("{}:{}: key '{}': expected at most {} entries, got {}", file,
                                 n.Mark().line + 1, key, most, n.size()));
    out.clear();
    for (std::size_t i = 0; i < n.size(); ++i) {
      MapReader r(file, n[i], fmt::format("{}[{}]", key, i));
      out.push_back(read_one(r));
      r.finish();
    }
  };
  read_list("lamps", 100, s.lamps, [&](MapReader& r) {
    LampSpec l;
    l.position = r.vec3("position", l.position);
    l.radius = r.real("radius", l.radius, lamp_radius, "a length of 0 (a point lamp) or in [0.1, 10000] mm");
    l.power = r.real("power", l.power, kLampPower, "a power", "W");
    l.reflectance = r.real("reflectance", l.reflectance, kReflectance, "a reflectance", "");
    if (vec3::norm(l.position) + l.radius >= R)
      r.fail_key("position", fmt::format("expected a lamp inside the sphere (|position| + radius < {} mm)", R));
    return l;
  });
  if (s.lamps.empty()) throw RigError(fmt::format("{}: key 'lamps': expected at least one lamp", file));
  read_list("baffles", 1000, s.baffles, [&](MapReader& r) {
    BaffleSpec b;
    b.centre = r.vec3("centre", b.centre);
    b.normal = r.vec3("normal", b.normal);
    b.radius = r.real("radius", b.radius, kBaffleRadius, "a length", "mm");
    b.reflectance = r.real("reflectance", b.reflectance, kReflectance, "a reflectance", "");
    // Only the direction counts; the tracer normalises it, which a length outside this range
    // (0, or one whose square overflows or underflows) would turn into NaN.
    const double length = std::hypot(b.normal[0], b.normal[1], b.normal[2]);
    if (!(length >= 1e-6 && length <= 1e6))
      r.fail_key("normal", fmt::format("expected a direction of length in [1e-6, 1e6] (only its "
                                       "direction counts), got [{}, {}, {}] of length {}",
                                       b.normal[0], b.normal[1], b.normal[2], length));
    if (vec3::norm(b.centre) + b.radius >= R)
      r.fail_key("centre", fmt::format("expected a baffle inside the sphere (|centre| + radius < {} mm)", R));
    return b;
  });

  MapReader sensor(file, top.section("sensor"), "sensor");
  SensorOpticsSpec& o = s.sensor;
  o.geometry = sensor.text("geometry", o.geometry, {"bare", "lensed"});
  o.L_o = sensor.real("L_o", o.L_o, RealRange{0.1, 1000}, "a length", "mm");
  o.photodiode_size = sensor.real("photodiode_size", o.photodiode_size, RealRange{0.01, 100}, "a length", "mm");
  o.filter_transmittance = sensor.real("filter_transmittance", o.filter_transmittance, kFilmTransmittance, "a transmittance", "");
  o.top_distance = sensor.real("top_distance", o.top_distance, RealRange{0.1, 1000}, "a length", "mm");
  o.housing_height = sensor.real("housing_height", o.housing_height, RealRange{1, 1000}, "a length", "mm");
  o.film_to_lens = sensor.real("film_to_lens", o.film_to_lens, RealRange{0, 100}, "a length", "mm");
  o.lens_focal_length = sensor.real("lens_focal_length", o.lens_focal_length, RealRange{1, 1000}, "a length", "mm");
  o.lens_diameter = sensor.real("lens_diameter", o.lens_diameter, RealRange{1, 100}, "a length", "mm");
  o.lens_thickness = sensor.real("lens_thickness", o.lens_thickness, RealRange{0.1, 100}, "a length", "mm");
  o.lens_index = sensor.real("lens_index", o.lens_index, RealRange{1, 3, true, false}, "a refractive index", "");
  o.lens_to_photodiode = sensor.real("lens_to_photodiode", o.lens_to_photodiode, RealRange{0.1, 1000}, "a length", "mm");
  sensor.finish();

  MapReader trace(file, top.section("trace"), "trace");
  s.trace.photons = trace.integer("photons", s.trace.photons, 1000, 100000000000LL);
  s.trace.batches = static_cast<int>(trace.integer("batches", s.trace.batches, 2, 1024));
  s.trace.wall_bins_theta = static_cast<int>(trace.integer("wall_bins_theta", s.trace.wall_bins_theta, 2, 4096));
  s.trace.wall_bins_phi = static_cast<int>(trace.integer("wall_bins_phi", s.trace.wall_bins_phi, 1, 8192));
  s.trace.field_step_deg = trace.real("field_step_deg", s.trace.field_step_deg,
                                      [](double v) { return v >= 0.25 && v <= 15; }, "a grid step in [0.25, 15] degrees");
  s.trace.plane_samples = trace.integer("plane_samples", s.trace.plane_samples, 16, 100000000LL);
  s.trace.seed = static_cast<std::uint64_t>(trace.integer("seed", static_cast<long long>(s.trace.seed), 0, 9007199254740991LL));
  if (s.trace.photons < 100LL * s.trace.batches)
    trace.fail_key("photons", fmt::format("expected at least 100 photons per batch ({} for {} batches), got {}",
                                          100LL * s.trace.batches, s.trace.batches, s.trace.photons));
  trace.finish();
  top.finish();
  return s;
}

SceneSpec load_scene(const std::filesystem::path& file) {
  return parse_scene(read_yaml_file(file, "scene file"), file.string());
}

std::string scene_to_yaml(const SceneSpec& s) {
  const auto num = [](double v) { return fmt::format("{}", v); };
  const auto vec = [&](const Vec3& v) { return fmt::format("[{}, {}, {}]", v[0], v[1], v[2]); };
  std::string out;
  out += fmt::format("sphere:\n  diameter: {}\n  reflectance: {}\n", num(s.sphere.diameter), num(s.sphere.reflectance));
  out += fmt::format("port:\n  diameter: {}\n  polarizer:\n    axis_deg: {}\n    tau_M: {}\n    tau_m: {}\n",
                     num(s.port.diameter), num(s.port.polarizer.axis_deg), num(s.port.polarizer.tau_M),
                     num(s.port.polarizer.tau_m));
  out += "lamps:\n";
  for (const LampSpec& l : s.lamps)
    out += fmt::format("  - {{position: {}, radius: {}, power: {}, reflectance: {}}}\n", vec(l.position),
                       num(l.radius), num(l.power), num(l.reflectance));
  out += s.baffles.empty() ? "baffles: []\n" : "baffles:\n";
  for (const BaffleSpec& b : s.baffles)
    out += fmt::format("  - {{centre: {}, normal: {}, radius: {}, reflectance: {}}}\n", vec(b.centre),
                       vec(b.normal), num(b.radius), num(b.reflectance));
  const SensorOpticsSpec& o = s.sensor;
  out += fmt::format(
      "sensor:\n  geometry: {}\n  L_o: {}\n  photodiode_size: {}\n  filter_transmittance: {}\n"
      "  top_distance: {}\n  housing_height: {}\n  film_to_lens: {}\n  lens_focal_length: {}\n"
      "  lens_diameter: {}\n  lens_thickness: {}\n  lens_index: {}\n  lens_to_photodiode: {}\n",
      o.geometry, num(o.L_o), num(o.photodiode_size), num(o.filter_transmittance), num(o.top_distance),
      num(o.housing_height), num(o.film_to_lens), num(o.lens_focal_length), num(o.lens_diameter),
      num(o.lens_thickness), num(o.lens_index), num(o.lens_to_photodiode));
  out += fmt::format("trace:\n  photons: {}\n  batches: {}\n  wall_bins_theta: {}\n  wall_bins_phi: {}\n"
                     "  field_step_deg: {}\n  plane_samples: {}\n  seed: {}\n",
                     s.trace.photons, s.trace.batches, s.trace.wall_bins_theta, s.trace.wall_bins_phi,
                     num(s.trace.field_step_deg), s.trace.plane_samples, s.trace.seed);
  return out;
}

}  // namespace polrig
