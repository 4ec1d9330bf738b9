#include "polrig/io/params_yaml.h"
#include "polrig/quoted.h"

#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "polrig/io/measured.h"
#include "yaml_load.h"

namespace polrig {

namespace {
template <std::size_t N>
void emit_list(YAML::Emitter& out, const char* key, const std::array<double, N>& v) {
  out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (double x : v) out << fmt::format("{}", x);
  out << YAML::EndSeq;
}
}  // namespace

std::string params_to_yaml(const CalibrationResult& r, double v_dec) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "params_schema" << YAML::Value << 1;
  out << YAML::Key << "method" << YAML::Value << std::string(method_name(r.method));
  out << YAML::Key << "d_a" << YAML::Value << fmt::format("{}", r.d_a);
  out << YAML::Key << "d_a_source" << YAML::Value << r.d_a_source;
  if (!r.drift.empty()) out << YAML::Key << "drift" << YAML::Value << r.drift;
  out << YAML::Key << "volts_per_decade" << YAML::Value << fmt::format("{}", v_dec);
  emit_list(out, "alpha_deg", r.params.alpha_deg);
  emit_list(out, "k_mV", r.params.k_mV);
  emit_list(out, "kv", r.params.kv);
  emit_list(out, "kd", r.params.kd);
  out << YAML::Key << "standard_error" << YAML::Value << YAML::BeginMap;
  emit_list(out, "alpha_deg", r.standard_error.alpha_deg);
  emit_list(out, "k_mV", r.standard_error.k_mV);
  emit_list(out, "kv", r.standard_error.kv);
  emit_list(out, "kd", r.standard_error.kd);
  out << YAML::EndMap;
  out << YAML::Key << "fit" << YAML::Value << YAML::BeginMap;
  const FitSummary& f = r.fit.summary;
  out << YAML::Key << "observations" << YAML::Value << f.observations;
  out << YAML::Key << "residual_rms_mV" << YAML::Value << fmt::format("{}", r.fit.residual_rms_V * 1e3);
  out << YAML::Key << "iterations" << YAML::Value << f.iterations;
  out << YAML::Key << "evaluations" << YAML::Value << f.evaluations;
  out << YAML::Key << "termination" << YAML::Value << std::string(termination_name(f.termination));
  out << YAML::Key << "usable" << YAML::Value << f.usable();
  out << YAML::Key << "solver_status" << YAML::Value << f.solver_status;
  out << YAML::Key << "message" << YAML::Value << f.message;
  out << YAML::Key << "initial_cost_V2" << YAML::Value << fmt::format("{}", f.initial_cost);
  out << YAML::Key << "final_cost_V2" << YAML::Value << fmt::format("{}", f.final_cost);
  out << YAML::Key << "brief_report" << YAML::Value << f.brief_report();
  out << YAML::EndMap;
  out << YAML::Key << "accuracy_deg" << YAML::Value << YAML::BeginMap;
  const char* names[4] = {"theta12", "theta13", "theta23", "theta_sec"};
  for (int k = 0; k < 4; ++k)
    out << YAML::Key << names[k] << YAML::Value << fmt::format("{}", r.accuracy[k].accuracy_deg());
  out << YAML::EndMap;
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

namespace {

// The physical range of each value, as the rig's device.truth and electronics keys have them.
struct ParamRange {
  double lo, hi;
  bool lo_open, hi_open;
  const char* why;
  bool contains(double v) const {
    return (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
  }
  std::string text() const {
    return fmt::format("{}{}, {}{}", lo_open ? "(" : "[", lo, hi, hi_open ? ")" : "]");
  }
};
constexpr ParamRange kAlphaRange{-720, 720, false, false, "doubled angles: one turn of the film either way"};
constexpr ParamRange kOffsetRange{-1000, 1000, false, false, "beyond ±1 V an offset exceeds a log amplifier's output"};
constexpr ParamRange kGainRange{0.5, 2, false, false, "a factor of 2 either way is another amplifier"};
constexpr ParamRange kPolarizerRange{-1, 1, true, true, "kd = −1 is a film that does not polarize"};
constexpr ParamRange kDegreeRange{0, 1, true, true, "a degree of polarization"};
constexpr ParamRange kScaleRange{0.01, 10, false, false, "log amplifiers give tens to thousands of mV per decade"};

}  // namespace

LoadedParams read_params_yaml(const std::filesystem::path& path) {
  return parse_params_yaml(read_yaml_file<DataError>(path, "parameter file"), path.string());
}

LoadedParams parse_params_yaml(std::string_view text, std::string_view origin) {
  const std::string file(origin);
  const YAML::Node root = load_yaml<DataError>(std::string(text), file, "a params.yaml nests 2 levels", kMaxYamlBytes);
  if (!root.IsMap())
    throw DataError(fmt::format("{}: expected a mapping with alpha_deg, k_mV, kv, kd and d_a", file));
  refuse_duplicate_keys<DataError>(root, file);
  static const std::set<std::string> known = {"params_schema", "method", "d_a", "d_a_source", "drift",
                                              "volts_per_decade", "alpha_deg", "k_mV", "kv", "kd",
                                              "standard_error", "fit", "accuracy_deg"};
  for (auto it = root.begin(); it != root.end(); ++it) {
    const std::string key = it->first.IsScalar() ? it->first.Scalar() : "?";
    if (!known.count(key))
      throw DataError(fmt::format("{}:{}: key '{}': unknown key", file, it->first.Mark().line + 1, quoted_value(key)));
  }
  const auto where = [&](const YAML::Node& n, const char* key) {
    return fmt::format("{}:{}: key '{}'", file, n.Mark().line + 1, key);
  };
  const auto number = [&](const YAML::Node& n, const char* key, const ParamRange& range) {
    double v = 0;
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      throw DataError(fmt::format("{}: expected a number, got '{}'", where(n, key),
                                  n.IsScalar() ? quoted_value(n.Scalar()) : "?"));
    }
    if (!std::isfinite(v) || !range.contains(v))
      throw DataError(fmt::format("{}: expected a value in {} ({}), got {}", where(n, key),
                                  range.text(), range.why, quoted_value(n.Scalar())));
    return v;
  };
  const auto list = [&](const char* key, auto& dst, const ParamRange& range) {
    const YAML::Node n = root[key];
    if (!n) throw DataError(fmt::format("{}: missing key '{}'", file, key));
    if (!n.IsSequence() || n.size() != dst.size())
      throw DataError(fmt::format("{}: expected a list of {} numbers", where(n, key), dst.size()));
    for (std::size_t i = 0; i < dst.size(); ++i) dst[i] = number(n[i], key, range);
  };
  LoadedParams p;
  list("alpha_deg", p.params.alpha_deg, kAlphaRange);
  list("k_mV", p.params.k_mV, kOffsetRange);
  list("kv", p.params.kv, kGainRange);
  list("kd", p.params.kd, kPolarizerRange);
  if (!root["d_a"]) throw DataError(fmt::format("{}: missing key 'd_a'", file));
  p.d_a = number(root["d_a"], "d_a", kDegreeRange);
  if (root["volts_per_decade"])
    p.volts_per_decade = number(root["volts_per_decade"], "volts_per_decade", kScaleRange);
  // Eq. 15's domain at cos = ±1 needs c_m = (1 + kd_m)·d_a < 1.
  for (std::size_t m = 0; m < 6; ++m)
    if (!((1.0 + p.params.kd[m]) * p.d_a < 1.0))
      throw DataError(fmt::format("{}: kd_{} = {} with d_a = {} gives (1 + kd)·d_a ≥ 1, outside "
                                  "Eq. 15's domain", where(root["kd"][m], "kd"), m + 1,
                                  p.params.kd[m], p.d_a));
  return p;
}

}  // namespace polrig
