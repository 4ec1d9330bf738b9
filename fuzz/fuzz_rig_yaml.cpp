// Rig files: any text ends as a Rig or a RigError; any other exception, a crash, a hang or a
// leak is a finding. The origin's folder does not exist, so a relative device.truth_from or
// source.scene (rigs/ use ../scenes/…) names no file and the target reads nothing.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "polrig/io/rig_yaml.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    polrig::parse_rig(text, "/nonexistent/polrig-fuzz/rigs/rig.yaml");
  } catch (const polrig::RigError&) {
  }
  return 0;
}
