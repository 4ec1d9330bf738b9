#pragma once
// Parsing YAML text for the rig and scene readers (private to io/): every yaml-cpp error becomes
// a RigError "FILE:LINE:COLUMN: …". Nesting deeper than yaml-cpp's depth guard (which protects
// the stack) is named as such instead of yaml-cpp's "bad file".
#include <string>
#include <string_view>

#include <fmt/format.h>
#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/yaml.h>

#include "polrig/io/rig_yaml.h"

namespace polrig {

// `needs` says how deep a valid file nests, for the message: "a rig file nests 3 levels".
inline YAML::Node load_yaml(const std::string& text, std::string_view file, std::string_view needs) {
  try {
    return YAML::Load(text);
  } catch (const YAML::DeepRecursion& e) {
    // The mark is where the scanner had got to, which may be past the too-deep place: the line
    // only.
    throw RigError(fmt::format("{}:{}: the YAML nests deeper than the reader's limit of {} levels "
                               "({})", file, e.mark.line + 1, e.depth(), needs));
  } catch (const YAML::Exception& e) {
    throw RigError(fmt::format("{}:{}:{}: YAML syntax error: {}", file, e.mark.line + 1,
                               e.mark.column + 1, e.msg));
  }
}

}  // namespace polrig
