#include "polrig/io/manifest.h"

#include <stdexcept>

#include <fmt/format.h>
#include <yaml-cpp/binary.h>
#include <yaml-cpp/yaml.h>

#include "polrig/io/csv.h"
#include "polrig/version.h"

namespace polrig {

namespace {
// A YAML literal block reproduces a text exactly only if it ends in one newline, has no
// carriage returns or tabs, and its first line is not indented; otherwise quote it.
bool literal_block_is_exact(const std::string& t) {
  if (t.empty() || t.back() != '\n') return false;
  if (t.size() >= 2 && t[t.size() - 2] == '\n') return false;
  if (t.front() == ' ' || t.front() == '\n') return false;
  return t.find_first_of("\r\t") == std::string::npos;
}

// True if `text`, written as a YAML string in `style`, reads back byte for byte. It does not for
// bytes that are not UTF-8 (the emitter replaces them with U+FFFD), nor for a NUL in a literal
// block (a double-quoted string holds it as "\x00").
bool reads_back_exactly(const std::string& text, YAML::EMITTER_MANIP style) {
  YAML::Emitter out;
  out << YAML::BeginMap << YAML::Key << "t" << YAML::Value << style << text << YAML::EndMap;
  if (!out.good()) return false;
  try {
    return YAML::Load(std::string(out.c_str(), out.size()))["t"].as<std::string>() == text;
  } catch (const YAML::Exception&) {
    return false;
  }
}

// The rig file's text exactly as read: a literal block when that reproduces it, else a
// double-quoted string when that does (tabs, carriage returns, a NUL), else (invalid UTF-8) its
// bytes in base64 under rig_text_base64.
void emit_rig_text(YAML::Emitter& out, const std::string& text) {
  if (literal_block_is_exact(text) && reads_back_exactly(text, YAML::Literal)) {
    out << YAML::Key << "rig_text" << YAML::Value << YAML::Literal << text;
  } else if (reads_back_exactly(text, YAML::DoubleQuoted)) {
    out << YAML::Key << "rig_text" << YAML::Value << YAML::DoubleQuoted << text;
  } else {
    out << YAML::Key << "rig_text_base64" << YAML::Value
        << YAML::EncodeBase64(reinterpret_cast<const unsigned char*>(text.data()), text.size());
  }
}
// How the light's expensive part was made: the sphere solved or loaded, and its cache file.
void emit_light(YAML::Emitter& out, const Manifest& m) {
  std::optional<LightOrigin> light = m.light;
  if (!light && m.rig && m.rig->rig.light) light = m.rig->rig.light->origin();
  if (!light) return;
  out << YAML::Key << "light" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "sphere" << YAML::Value << light->sphere;
  out << YAML::Key << "cache_file" << YAML::Value << (light->cache_file.empty() ? "none" : light->cache_file);
  out << YAML::EndMap;
}
// UTF-8 without NUL: what an HDF5 UTF-8 string holds exactly.
bool is_utf8_text(const std::string& t) {
  return t.find('\0') == std::string::npos && reads_back_exactly(t, YAML::DoubleQuoted);
}
}  // namespace

std::string manifest_working_directory(const Manifest& m) {
  if (m.working_directory) return *m.working_directory;
  std::error_code ec;
  const std::filesystem::path cwd = std::filesystem::current_path(ec);
  return ec ? "(unavailable: " + ec.message() + ")" : cwd.string();
}

std::vector<std::pair<std::string, std::string>> manifest_fields(const Manifest& m) {
  std::vector<std::pair<std::string, std::string>> f{
      {"manifest_schema", "1"}, {"program", "polrig"}, {"version", POLRIG_VERSION},
      {"git_revision", POLRIG_GIT_REVISION}, {"command", m.command},
      {"working_directory", manifest_working_directory(m)}};
  const auto lines = [](const std::vector<std::string>& items) {
    std::string t;
    for (const std::string& i : items) t += i + "\n";
    return t;
  };
  if (!m.inputs.empty()) f.emplace_back("inputs", lines(m.inputs));
  if (m.rig) {
    f.emplace_back("seed", fmt::format("{}", m.rig->rig.seed));
    f.emplace_back("rig_file", m.rig->origin);
    f.emplace_back("instrument", std::string(m.rig->rig.instrument().kind()));
    std::vector<std::string> overrides;
    for (const RigOverride& o : m.rig->overrides) overrides.push_back(o.path + "=" + o.value);
    f.emplace_back("overrides", lines(overrides));
    if (is_utf8_text(m.rig->text))
      f.emplace_back("rig_text", m.rig->text);
    else
      f.emplace_back("rig_text_base64", YAML::EncodeBase64(reinterpret_cast<const unsigned char*>(m.rig->text.data()),
                                                           m.rig->text.size()));
    f.emplace_back("rig_resolved", rig_to_yaml(m.rig->rig));
  }
  return f;
}

void write_manifest(const std::filesystem::path& dir, const Manifest& m) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "manifest_schema" << YAML::Value << 1;
  out << YAML::Key << "program" << YAML::Value << "polrig";
  out << YAML::Key << "version" << YAML::Value << POLRIG_VERSION;
  out << YAML::Key << "git_revision" << YAML::Value << POLRIG_GIT_REVISION;
  out << YAML::Key << "command" << YAML::Value << m.command;
  out << YAML::Key << "working_directory" << YAML::Value << manifest_working_directory(m);
  if (!m.inputs.empty()) {
    out << YAML::Key << "inputs" << YAML::Value << YAML::BeginSeq;
    for (const std::string& in : m.inputs) out << in;
    out << YAML::EndSeq;
  }
  std::string resolved;
  if (m.rig) {
    resolved = rig_to_yaml(m.rig->rig);
    out << YAML::Key << "seed" << YAML::Value << m.rig->rig.seed;
    out << YAML::Key << "rig_file" << YAML::Value << m.rig->origin;
    out << YAML::Key << "instrument" << YAML::Value << std::string(m.rig->rig.instrument().kind());
    out << YAML::Key << "overrides" << YAML::Value << YAML::BeginSeq;
    for (const RigOverride& o : m.rig->overrides) out << o.path + "=" + o.value;
    out << YAML::EndSeq;
  }
  emit_light(out, m);
  out << YAML::Key << "files" << YAML::Value << YAML::BeginMap;
  std::vector<DatasetFile> files = m.files;
  if (std::filesystem::exists(dir / "plots.gp"))
    files.push_back({"plots.gp", 1, "the gnuplot script that drew the PNGs from the CSVs"});
  for (const DatasetFile& f : files) {
    out << YAML::Key << f.name << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "schema" << YAML::Value << f.schema;
    out << YAML::Key << "description" << YAML::Value << f.description;
    out << YAML::EndMap;
  }
  if (m.rig) {
    out << YAML::Key << "rig.yaml" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "schema" << YAML::Value << 1;
    out << YAML::Key << "description" << YAML::Value
        << "the effective rig (file + overrides + defaults); loads back to the same rig";
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  if (m.rig) {
    emit_rig_text(out, m.rig->text);
    out << YAML::Key << "rig_resolved" << YAML::Value << YAML::Literal << resolved;
  }
  out << YAML::EndMap;
  if (!out.good())
    throw std::runtime_error(fmt::format("{}: cannot write the manifest: {}",
                                         (dir / "manifest.yaml").string(), out.GetLastError()));
  write_text_file(dir / "manifest.yaml", std::string(out.c_str(), out.size()) + "\n");
  if (m.rig) write_text_file(dir / "rig.yaml", resolved);
}

}  // namespace polrig
