#include "polrig/io/rig_yaml.h"
#include "polrig/quoted.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "polrig/io/measured.h"
#include "polrig/io/params_yaml.h"
#include "polrig/io/scene_yaml.h"
#include "polrig/rig/keys.h"
#include "polrig/sky/sun.h"
#include "polrig/suggest.h"
#include "yaml_load.h"

namespace polrig {
namespace {

// Where a value came from: a line of the rig file, or a --set argument.
struct Origin {
  std::string where;  // "rigs/x.yaml:12" or "--set a.b=1"
};

class RigParser {
 public:
  RigParser(std::string_view origin, const std::vector<RigOverride>& overrides, RigUse use = RigUse::Run)
      : file_(origin), overrides_(overrides), use_(use) {}

  const std::set<std::string>& given() const { return present_; }

  Rig parse(std::string_view text) {
    YAML::Node root = load_yaml(std::string(text), file_, "a rig file nests 4 levels");
    if (!root.IsMap() && !root.IsNull())
      throw RigError(fmt::format("{}: expected a mapping of rig sections (device, source, "
                                 "eccentricity, schedule, electronics, seed)", file_));
    if (root.IsNull()) root = YAML::Node(YAML::NodeType::Map);
    for (const RigOverride& o : overrides_) apply_override(root, o);

    Rig rig;
    walk(root, "", rig);
    make_instrument_of(rig);
    check_schedule_form();
    load_truth_from(rig);
    make_light(rig);
    if (auto problem = check_rig(rig, use_)) {
      std::string also;
      if (!problem->related_path.empty())
        also = fmt::format(" ('{}' from {})", problem->related_path, where(problem->related_path));
      throw RigError(fmt::format("{}: key '{}': {}{}", where(problem->path), problem->path,
                                 problem->message, also));
    }
    check_sky_time(rig, rig.schedule.stop_times_s().back());
    return rig;
  }

 private:
  std::string file_;
  const std::vector<RigOverride>& overrides_;
  RigUse use_ = RigUse::Run;
  std::map<std::string, int> line_of_;  // key path → 1-based line in the file
  std::set<std::string> present_;

  const RigOverride* override_for(const std::string& path) const {
    for (auto it = overrides_.rbegin(); it != overrides_.rend(); ++it)
      if (it->path == path || it->path.starts_with(path + ".")) return &*it;
    return nullptr;
  }

  std::string where(const std::string& path) const {
    if (const RigOverride* o = override_for(path)) return o->text();
    auto it = line_of_.find(path);
    if (it != line_of_.end()) return fmt::format("{}:{}", file_, it->second);
    return fmt::format("{} (default value)", file_);
  }

  [[noreturn]] void fail(const std::string& path, const std::string& message) const {
    throw RigError(fmt::format("{}: key '{}': {}", where(path), quoted_value(path), message));
  }

  // " (did you mean 'eccentricity.L_IS'?)" for a path near a rig key.
  static std::string key_suggestion(std::string_view path) {
    std::vector<std::string> paths;
    for (const RigKey& k : rig_keys()) paths.emplace_back(k.path);
    return did_you_mean(path, paths);
  }

  static bool is_section(std::string_view path) {
    for (const RigKey& k : rig_keys())
      if (k.path.size() > path.size() && k.path.starts_with(path) && k.path[path.size()] == '.')
        return true;
    return false;
  }

  void apply_override(YAML::Node& root, const RigOverride& o) {
    if (!find_rig_key(o.path))
      throw RigError(fmt::format("{}: unknown key '{}'{} (see docs/formats.md for the rig's "
                                 "keys)", quoted_value(o.text()), quoted_value(o.path), key_suggestion(o.path)));
    YAML::Node value;
    try {
      value = load_yaml(o.value, "value", "a rig value nests at most 1 level");
    } catch (const RigError& e) {  // "value:1:2: YAML syntax error: why" → "why"
      std::string_view why = e.what();
      why.remove_prefix(why.find(": ") + 2);
      if (why.starts_with("YAML syntax error: ")) why.remove_prefix(19);
      throw RigError(fmt::format("{}: key '{}': the value is not valid YAML: {}", o.text(),
                                 o.path, why));
    }
    std::vector<std::string> parts;
    std::stringstream ss(o.path);
    for (std::string part; std::getline(ss, part, '.');) parts.push_back(part);
    // yaml-cpp nodes are handles: rebinding with reset() walks down without copying.
    YAML::Node node;
    node.reset(root);
    std::string prefix;
    for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
      prefix += (i ? "." : "") + parts[i];
      YAML::Node child = node[parts[i]];
      if (!child.IsDefined() || child.IsNull()) {
        node[parts[i]] = YAML::Node(YAML::NodeType::Map);
        child = node[parts[i]];
      } else if (!child.IsMap()) {
        throw RigError(fmt::format("{}: key '{}': the file gives it a value, expected a "
                                   "section", o.text(), prefix));
      }
      node.reset(child);
    }
    node[parts.back()] = value;
  }

  void walk(const YAML::Node& map, const std::string& prefix, Rig& rig) {
    std::set<std::string> seen;
    for (auto it = map.begin(); it != map.end(); ++it) {
      if (!it->first.IsScalar())
        throw RigError(fmt::format("{}:{}: expected a key name under '{}', got {}", file_,
                                   it->first.Mark().line + 1, prefix.empty() ? "(top)" : prefix,
                                   shown(it->first)));
      const std::string key = it->first.Scalar();
      const std::string path = prefix.empty() ? key : prefix + "." + key;
      if (it->first.Mark().line >= 0 && !override_for(path))
        line_of_[path] = it->first.Mark().line + 1;
      if (!seen.insert(key).second) fail(path, "duplicate key");
      if (const RigKey* k = find_rig_key(path)) {
        read_leaf(*k, path, it->second, rig);
        present_.insert(path);
      } else if (is_section(path)) {
        if (!it->second.IsMap()) fail(path, "expected a section (a mapping of keys)");
        walk(it->second, path, rig);
      } else {
        fail(path, "unknown key" + key_suggestion(path) + " (see docs/formats.md for the rig's keys)");
      }
    }
  }

  static std::string shown(const YAML::Node& n) {
    if (n.IsScalar()) return fmt::format("'{}'", quoted_value(n.Scalar()));
    if (n.IsSequence()) return "a list";
    if (n.IsMap()) return "a mapping";
    return "nothing";
  }

  double read_real(const RigKey& k, const std::string& path, const YAML::Node& n) const {
    if (!n.IsScalar()) fail(path, fmt::format("expected {}, got {}", k.expects, shown(n)));
    double v = 0.0;
    try {
      v = parse_finite_number(n.Scalar(), "value");
    } catch (const RigError&) {
      fail(path, fmt::format("expected {}, got {}", k.expects, shown(n)));
    }
    if (k.valid_real && !k.valid_real(v))
      fail(path, fmt::format("expected {}, got {}", k.expects, quoted_value(n.Scalar())));
    return v;
  }

  void read_leaf(const RigKey& k, const std::string& path, const YAML::Node& n, Rig& rig) {
    using K = RigKey::Kind;
    switch (k.kind) {
      case K::Real:
        k.real(rig) = read_real(k, path, n);
        return;
      case K::Integer: {
        long long v = 0;
        if (!n.IsScalar() || !parse_integer(n.Scalar(), v))
          fail(path, fmt::format("expected {}, got {}", k.expects, shown(n)));
        if (k.valid_integer && !k.valid_integer(v))
          fail(path, fmt::format("expected {}, got {}", k.expects, quoted_value(n.Scalar())));
        k.integer(rig) = static_cast<int>(v);
        return;
      }
      case K::Seed: {
        std::uint64_t v = 0;
        const std::string s = n.IsScalar() ? n.Scalar() : "";
        auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
        if (s.empty() || ec != std::errc() || end != s.data() + s.size())
          fail(path, fmt::format("expected {}, got {}", k.expects, shown(n)));
        k.seed(rig) = v;
        return;
      }
      case K::Text:
        if (!n.IsScalar() || (k.valid_text && !k.valid_text(n.Scalar())))
          fail(path, fmt::format("expected {}, got {}", k.expects, shown(n)));
        k.text(rig) = n.Scalar();
        return;
      case K::RealArray: {
        std::span<double> dst = k.array(rig);
        if (!n.IsSequence() || n.size() != dst.size())
          fail(path, fmt::format("expected a list of {}, got {}", k.expects,
                                 n.IsSequence() ? fmt::format("{} values", n.size())
                                                : shown(n)));
        for (std::size_t i = 0; i < dst.size(); ++i) dst[i] = read_real(k, path, n[i]);
        return;
      }
      case K::Bool:
        if (!n.IsScalar() || (n.Scalar() != "true" && n.Scalar() != "false"))
          fail(path, fmt::format("expected {}, got {}", k.expects, shown(n)));
        k.boolean(rig) = n.Scalar() == "true";
        return;
      case K::RealList: {
        if (!n.IsSequence() || n.size() == 0 || (k.max_items && n.size() > k.max_items))
          fail(path, fmt::format("expected {}, got {}", k.expects,
                                 !n.IsSequence()  ? shown(n)
                                 : n.size() == 0 ? std::string("an empty list")
                                                 : fmt::format("{} entries", n.size())));
        std::vector<double>& dst = k.list(rig);
        dst.clear();
        for (std::size_t i = 0; i < n.size(); ++i) dst.push_back(read_real(k, path, n[i]));
        return;
      }
    }
  }

  static bool parse_integer(const std::string& s, long long& v) {
    auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    return !s.empty() && ec == std::errc() && end == s.data() + s.size();
  }

  // device.truth_from: the true parameters come from a calibration's params.yaml.
  void load_truth_from(Rig& rig) const {
    if (rig.device.truth_from.empty()) return;
    for (const std::string& p : present_)
      if (p.starts_with("device.truth."))
        fail("device.truth_from", fmt::format("expected either device.truth_from or "
                                              "device.truth.* keys, not both ('{}' is also given)", p));
    std::filesystem::path params = rig.device.truth_from;
    if (params.is_relative() && !std::filesystem::path(file_).parent_path().empty() &&
        !override_for("device.truth_from"))
      params = std::filesystem::path(file_).parent_path() / params;
    try {
      rig.device.truth = read_params_yaml(params).params;
    } catch (const DataError& e) {
      fail("device.truth_from", fmt::format("cannot load the parameters: {}", e.what()));
    }
    // The loaded values must pass the same checks as device.truth.* in a rig file, so that the
    // effective rig (rig.yaml) loads back.
    for (const RigKey& k : rig_keys()) {
      if (!k.path.starts_with("device.truth.") || k.kind != RigKey::Kind::RealArray) continue;
      for (double v : k.array(rig))
        if (k.valid_real && !k.valid_real(v))
          fail("device.truth_from",
               fmt::format("{} gives {} = {}, expected {} (as for '{}')", params.string(),
                           k.path.substr(std::string_view("device.truth.").size()), v, k.expects,
                           k.path));
    }
    rig.device.truth_from.clear();
  }

  // The instrument: device.kind must be a kind make_instrument knows (Rig::instrument() is its);
  // keys it does not read are refused (RigKey::instruments), as keys the source model does not read are.
  void make_instrument_of(Rig& rig) const {
    for (const RigKey& k : rig_keys())
      if (present_.count(std::string(k.path)) && !k.read_by_instrument(rig.device_kind))
        fail(std::string(k.path), fmt::format("expected no value with device.kind {} (only device.kind {} "
                                              "reads it)", rig.device_kind, k.instruments));
    try {
      (void)make_instrument(rig.device_kind);  // rig.instrument() is this kind's
    } catch (const std::invalid_argument& e) {
      fail("device.kind", e.what());
    }
  }

  // The light: make_source builds the rig's model; a scene it names is read relative to the rig
  // file and kept as an absolute path, so that a dataset's rig.yaml finds it from anywhere.
  // Keys the model does not read are refused (RigKey::sources).
  void make_light(Rig& rig) const {
    for (const RigKey& k : rig_keys())
      if (present_.count(std::string(k.path)) && !k.read_by_source(rig.source.model))
        fail(std::string(k.path), fmt::format("expected no value with source.model {} (only source.model {} "
                                              "reads it)", rig.source.model, k.sources));
    // An override of sky.model sets aside the file's keys of the other sky (a shipped rig's
    // sky.p_max under --set sky.model=vector-rt); a file or an override that gives both is refused.
    const bool model_overridden = override_for("sky.model") != nullptr;
    for (const RigKey& k : rig_keys())
      if (present_.count(std::string(k.path)) && rig.source.model == "sky" && !k.read_by_sky_model(rig.source.sky.model) &&
          !(model_overridden && !override_for(std::string(k.path)))) {
        std::string models;  // "single-scattering berry" → "single-scattering or berry"
        for (char c : k.sky_models) models += c == ' ' ? std::string(" or ") : std::string(1, c);
        fail(std::string(k.path), fmt::format("expected no value with sky.model {} (only sky.model {} reads it)",
                                              rig.source.sky.model, models));
      }
    resolve_aerosol_phase_matrix(rig);
    const SceneLoader load = [&](const std::string& path) {
      std::filesystem::path scene = path;
      if (scene.is_relative() && !override_for("source.scene") &&
          !std::filesystem::path(file_).parent_path().empty())
        scene = std::filesystem::path(file_).parent_path() / scene;
      scene = std::filesystem::absolute(scene).lexically_normal();
      try {
        SceneSpec spec = load_scene(scene);
        rig.source.scene = scene.string();
        return spec;
      } catch (const RigError& e) {
        fail("source.scene", fmt::format("cannot load the scene: {}", e.what()));
      }
    };
    try {
      rig.light = make_source(rig.source, load);
    } catch (const SourceSettingError& e) {
      fail(e.key, e.what());
    }
    check_sky_time(rig, 0);
    // A source that sets the light's d itself (the traced port film; the sky's at the first
    // stop): it is the rig's d, for decoupling and the rig's checks; a device.d in the file must
    // agree.
    if (const std::optional<double> d = rig.light->rig_degree_of_polarization(rig.source_view())) {
      if (present_.count("device.d") && std::abs(rig.device.d - *d) > 1e-12)
        fail("device.d", fmt::format("expected the source's d = {} with source.model {} (or leave "
                                     "device.d out), got {}", *d, rig.source.model, rig.device.d));
      rig.device.d = *d;
    }
  }

  // sky.rt.aerosol.phase_matrix is read relative to the rig file, as a scene is, and kept absolute.
  void resolve_aerosol_phase_matrix(Rig& rig) const {
    std::string& path = rig.source.sky.aerosol_phase_matrix;
    if (path.empty()) return;
    std::filesystem::path p = path;
    if (p.is_relative() && !override_for("sky.rt.aerosol.phase_matrix") &&
        !std::filesystem::path(file_).parent_path().empty())
      p = std::filesystem::path(file_).parent_path() / p;
    path = std::filesystem::absolute(p).lexically_normal().string();
  }

  // A sky's run must lie where the ephemeris holds (1900–2100), its clock offset included: say so
  // when the rig loads, naming the key, rather than at a stop of the simulation. The first stop is
  // checked before the sky's d there is derived (make_light), the last once the schedule has
  // passed check_rig.
  void check_sky_time(const Rig& rig, double t_k) const {
    if (!rig.light->has(Source::kTimeDependent)) return;
    const Sky sky = rig.source.sky.resolved_sky();
    try {
      check_sun_inputs(sky.first_stop.plus_seconds(t_k + rig.source.sky.mount.time_offset_s),
                       sky.site, sky.sun);
    } catch (const std::invalid_argument& e) {
      fail("sky.first_stop_utc",
           fmt::format("the run's stop at t = {} s (with sky.time_offset_s = {} s): {}", t_k,
                       rig.source.sky.mount.time_offset_s, e.what()));
    }
  }

  void check_schedule_form() const {
    if (!present_.count("schedule.angles_deg")) return;
    // `--set schedule.angles_deg=[…]` replaces a file's start/step/stop; within one source
    // (the file, or the overrides) only one form may be given.
    const bool list_overridden = override_for("schedule.angles_deg") != nullptr;
    for (const char* p : {"schedule.start_deg", "schedule.step_deg", "schedule.stop_deg"})
      if (present_.count(p) && !(list_overridden && override_for(p) == nullptr))
        fail("schedule.angles_deg",
             fmt::format("expected either an explicit list or start/step/stop, not both "
                         "('{}' is also given)", p));
  }
};

std::string number_text(double v) { return fmt::format("{}", v); }

}  // namespace

RigOverride RigOverride::parse(std::string_view arg) {
  const auto eq = arg.find('=');
  if (eq == std::string_view::npos || eq == 0)
    throw RigError(fmt::format("--set {}: expected key.path=value", arg));
  return {std::string(arg.substr(0, eq)), std::string(arg.substr(eq + 1))};
}

LoadedRig parse_rig(std::string_view text, std::string_view origin,
                    const std::vector<RigOverride>& overrides, RigUse use) {
  RigParser parser(origin, overrides, use);
  Rig rig = parser.parse(text);
  return {std::move(rig), std::string(origin), std::string(text), overrides, parser.given()};
}

LoadedRig load_rig(const std::filesystem::path& file, const std::vector<RigOverride>& overrides, RigUse use) {
  return parse_rig(read_yaml_file(file, "rig file", kMaxRigYamlBytes), file.string(), overrides, use);
}

std::string rig_to_yaml(const Rig& rig_in) {
  Rig rig = rig_in;  // accessors hand out references into a mutable Rig
  YAML::Node root(YAML::NodeType::Map);
  for (const RigKey& k : rig_keys()) {
    if (!written_for(k, rig)) continue;
    YAML::Node value;
    using K = RigKey::Kind;
    switch (k.kind) {
      case K::Real: value = number_text(k.real(rig)); break;
      case K::Integer: value = k.integer(rig); break;
      case K::Seed: value = k.seed(rig); break;
      case K::Text: value = k.text(rig); break;
      case K::Bool: value = k.boolean(rig); break;
      case K::RealArray:
      case K::RealList: {
        std::span<const double> src =
            k.kind == K::RealArray ? std::span<const double>(k.array(rig))
                                   : std::span<const double>(k.list(rig));
        value = YAML::Node(YAML::NodeType::Sequence);
        for (double v : src) value.push_back(number_text(v));
        value.SetStyle(YAML::EmitterStyle::Flow);
        break;
      }
    }
    std::stringstream ss{std::string(k.path)};
    std::vector<std::string> parts;
    for (std::string part; std::getline(ss, part, '.');) parts.push_back(part);
    YAML::Node node;
    node.reset(root);
    for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
      if (!node[parts[i]]) node[parts[i]] = YAML::Node(YAML::NodeType::Map);
      YAML::Node child = node[parts[i]];
      node.reset(child);
    }
    node[parts.back()] = value;
  }
  YAML::Emitter out;
  out << root;
  return std::string(out.c_str()) + "\n";
}

}  // namespace polrig
