#pragma once
// Reading and writing rig files (YAML). Every key is described in polrig/rig/keys.h and in
// docs/formats.md. Errors name the file, the line, the key and what was expected.
#include <cstdint>
#include <filesystem>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "polrig/rig/error.h"  // RigError, parse_finite_number
#include "polrig/rig/keys.h"
#include "polrig/rig/rig.h"

namespace polrig {

// The largest rig file a reader takes (32 MiB: a million-stop schedule).
inline constexpr std::uintmax_t kMaxRigYamlBytes = 32u << 20;


// One `--set key.path=value`; the value is read as YAML ("3", "[1, 2, 3]", "cos4").
struct RigOverride {
  std::string path;
  std::string value;
  static RigOverride parse(std::string_view arg);  // throws RigError without '='
  std::string text() const { return "--set " + path + "=" + value; }
};

struct LoadedRig {
  Rig rig;
  std::string origin;  // file path, as given
  std::string text;    // the file's full text, before overrides
  std::vector<RigOverride> overrides;
  std::set<std::string> given;  // the key paths the file or an override sets (the rest: defaults)
};

// Parses rig text; `origin` names it in error messages.
// `use`: what the rig is loaded for (rig/keys.h, check_rig): RigUse::ReadDataset passes over a
// simulated run's own rules (navigate and calibrate --method unit-array of a measured log).
LoadedRig parse_rig(std::string_view text, std::string_view origin,
                    const std::vector<RigOverride>& overrides = {}, RigUse use = RigUse::Run);
LoadedRig load_rig(const std::filesystem::path& file,
                   const std::vector<RigOverride>& overrides = {}, RigUse use = RigUse::Run);

// The complete effective rig, every key written: a file that loads back to the same Rig.
std::string rig_to_yaml(const Rig& rig);

}  // namespace polrig
