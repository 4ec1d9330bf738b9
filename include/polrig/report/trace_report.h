#pragma once
// `polrig trace`: the sphere solve of a scene and the light below its port, written as EXR maps,
// CSV tables and PNG previews.
#include <filesystem>
#include <vector>

#include "polrig/io/manifest.h"
#include "polrig/progress.h"
#include "polrig/source/scene.h"

namespace polrig {

// Reports the sphere solve and the plane map to `progress`.
std::vector<DatasetFile> trace_scene(const std::filesystem::path& dir, const SceneSpec& scene,
                                     bool plots, const Progress& progress = {});

}  // namespace polrig
