// Scene files: any text ends as a SceneSpec or a RigError; anything else is a finding. Only the
// parser runs (no Embree scene is built).
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "polrig/io/scene_yaml.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    polrig::parse_scene(text, "fuzz/scene.yaml");
  } catch (const polrig::RigError&) {
  }
  return 0;
}
