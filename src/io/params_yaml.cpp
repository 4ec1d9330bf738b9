#include "polrig/io/params_yaml.h"

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "polrig/io/measured.h"

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
  out << YAML::Key << "observations" << YAML::Value << r.fit.observations;
  out << YAML::Key << "residual_rms_mV" << YAML::Value << fmt::format("{}", r.fit.residual_rms_V * 1e3);
  out << YAML::Key << "iterations" << YAML::Value << r.fit.iterations;
  out << YAML::Key << "evaluations" << YAML::Value << r.fit.evaluations;
  out << YAML::EndMap;
  out << YAML::Key << "accuracy_deg" << YAML::Value << YAML::BeginMap;
  const char* names[4] = {"theta12", "theta13", "theta23", "theta_sec"};
  for (int k = 0; k < 4; ++k)
    out << YAML::Key << names[k] << YAML::Value << fmt::format("{}", r.accuracy[k].accuracy_deg());
  out << YAML::EndMap;
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

LoadedParams read_params_yaml(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw DataError(fmt::format("{}: cannot read the parameter file: no such file", path.string()));
  std::ifstream in(path, std::ios::binary);
  std::stringstream buf;
  buf << in.rdbuf();
  return parse_params_yaml(buf.str(), path.string());
}

LoadedParams parse_params_yaml(std::string_view text, std::string_view origin) {
  const std::string file(origin);
  YAML::Node root;
  try {
    root = YAML::Load(std::string(text));
  } catch (const YAML::Exception& e) {
    throw DataError(fmt::format("{}:{}:{}: YAML syntax error: {}", file, e.mark.line + 1,
                                e.mark.column + 1, e.msg));
  }
  if (!root.IsMap())
    throw DataError(fmt::format("{}: expected a mapping with alpha_deg, k_mV, kv, kd and d_a", file));
  static const std::set<std::string> known = {"params_schema", "method", "d_a", "d_a_source",
                                              "volts_per_decade", "alpha_deg", "k_mV", "kv", "kd",
                                              "standard_error", "fit", "accuracy_deg"};
  for (auto it = root.begin(); it != root.end(); ++it) {
    const std::string key = it->first.IsScalar() ? it->first.Scalar() : "?";
    if (!known.count(key))
      throw DataError(fmt::format("{}:{}: key '{}': unknown key", file, it->first.Mark().line + 1, key));
  }
  const auto where = [&](const char* key) {
    const YAML::Node n = root[key];
    return fmt::format("{}:{}: key '{}'", file, n ? n.Mark().line + 1 : 0, key);
  };
  const auto number = [&](const YAML::Node& n, const char* key) {
    double v = 0;
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      throw DataError(fmt::format("{}: expected a number", where(key)));
    }
    if (!std::isfinite(v)) throw DataError(fmt::format("{}: expected a finite number", where(key)));
    return v;
  };
  const auto list = [&](const char* key, auto& dst) {
    const YAML::Node n = root[key];
    if (!n) throw DataError(fmt::format("{}: missing key '{}'", file, key));
    if (!n.IsSequence() || n.size() != dst.size())
      throw DataError(fmt::format("{}: expected a list of {} numbers", where(key), dst.size()));
    for (std::size_t i = 0; i < dst.size(); ++i) dst[i] = number(n[i], key);
  };
  LoadedParams p;
  list("alpha_deg", p.params.alpha_deg);
  list("k_mV", p.params.k_mV);
  list("kv", p.params.kv);
  list("kd", p.params.kd);
  if (!root["d_a"]) throw DataError(fmt::format("{}: missing key 'd_a'", file));
  p.d_a = number(root["d_a"], "d_a");
  if (!(p.d_a > 0 && p.d_a < 1)) throw DataError(fmt::format("{}: expected d_a in (0, 1)", where("d_a")));
  if (root["volts_per_decade"]) {
    p.volts_per_decade = number(root["volts_per_decade"], "volts_per_decade");
    if (!(p.volts_per_decade > 0))
      throw DataError(fmt::format("{}: expected a gain > 0", where("volts_per_decade")));
  }
  for (double kv : p.params.kv)
    if (!(kv > 0)) throw DataError(fmt::format("{}: expected gains > 0", where("kv")));
  for (double kd : p.params.kd)
    if (!(kd > -1)) throw DataError(fmt::format("{}: expected values > −1", where("kd")));
  return p;
}

}  // namespace polrig
