#include "polrig/io/sweep_state.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "polrig/io/csv.h"
#include "polrig/io/measured.h"
#include "yaml_load.h"

namespace polrig {
namespace fs = std::filesystem;

void sync_to_disk(const fs::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0 || ::fsync(fd) != 0) {
    const int err = errno;
    if (fd >= 0) ::close(fd);
    throw std::runtime_error(fmt::format("{}: cannot sync to disk: {}", path.string(), std::strerror(err)));
  }
  ::close(fd);
}

std::optional<SweepState> read_sweep_state(const fs::path& dir) {
  const fs::path path = dir / kSweepStateFile;
  std::error_code ec;
  if (!fs::exists(path, ec)) return std::nullopt;
  const YAML::Node n = load_yaml<DataError>(read_yaml_file<DataError>(path, "sweep's progress record"), path.string(),
                                            "a progress record nests 2 levels", kMaxYamlBytes);
  try {
    SweepState s;
    s.points_done = n["points_done"].as<std::size_t>();
    s.csv_bytes = n["csv_bytes"].as<std::uint64_t>();
    if (const YAML::Node f = n["h5_fingerprint"]) s.h5_fingerprint = f.as<std::string>();
    if (const YAML::Node f = n["csv_fingerprint"]) s.csv_fingerprint = f.as<std::string>();
    s.command = n["command"].as<std::string>();
    s.working_directory = n["working_directory"].as<std::string>();
    for (const auto& kv : n["inputs"]) s.inputs.emplace_back(kv.first.as<std::string>(), kv.second.as<std::string>());
    return s;
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(fmt::format("{}: not a sweep's progress record: {}", path.string(), e.what()));
  }
}

void write_sweep_state(const fs::path& dir, const SweepState& s) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "points_done" << YAML::Value << s.points_done;
  out << YAML::Key << "csv_bytes" << YAML::Value << s.csv_bytes;
  out << YAML::Key << "h5_fingerprint" << YAML::Value << YAML::DoubleQuoted << s.h5_fingerprint;
  out << YAML::Key << "csv_fingerprint" << YAML::Value << YAML::DoubleQuoted << s.csv_fingerprint;
  out << YAML::Key << "command" << YAML::Value << YAML::DoubleQuoted << s.command;
  out << YAML::Key << "working_directory" << YAML::Value << YAML::DoubleQuoted << s.working_directory;
  out << YAML::Key << "inputs" << YAML::Value << YAML::BeginMap;
  for (const auto& [name, value] : s.inputs) out << YAML::Key << name << YAML::Value << YAML::DoubleQuoted << value;
  out << YAML::EndMap << YAML::EndMap;
  const fs::path path = dir / kSweepStateFile, temp = dir / (std::string(kSweepStateFile) + ".tmp");
  write_text_file(temp, std::string(out.c_str(), out.size()) + "\n");
  sync_to_disk(temp);
  std::error_code ec;
  fs::rename(temp, path, ec);
  if (ec) throw std::runtime_error(fmt::format("{}: cannot write the progress record: {}", path.string(), ec.message()));
  sync_to_disk(dir);
}

std::vector<std::string> differing_inputs(const SweepState& saved,
                                          const std::vector<std::pair<std::string, std::string>>& now) {
  std::vector<std::string> names;
  for (const auto& [name, value] : now) {
    bool same = false;
    for (const auto& [n, v] : saved.inputs) same |= n == name && v == value;
    if (!same) names.push_back(name);
  }
  for (const auto& [n, v] : saved.inputs) {
    bool known = false;
    for (const auto& [name, value] : now) known |= n == name;
    if (!known) names.push_back(n);
  }
  return names;
}

}  // namespace polrig
