#pragma once
// Reading scene files (scenes/*.yaml). The same rules as rig files: unknown keys, wrong types and
// unphysical values (reflectance ≥ 1, negative lengths, a port larger than the sphere, lamps
// outside it…) are errors naming the file, the line and the key; every key has a default
// (docs/formats.md, "Scene files").
#include <filesystem>
#include <string>
#include <string_view>

#include "polrig/io/rig_yaml.h"  // RigError: scene errors are input errors of the same kind
#include "polrig/source/scene.h"

namespace polrig {

SceneSpec parse_scene(std::string_view text, std::string_view origin);
SceneSpec load_scene(const std::filesystem::path& file);
std::string scene_to_yaml(const SceneSpec& scene);

}  // namespace polrig
