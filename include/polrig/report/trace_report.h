#pragma once
// `polrig trace`: the sphere solve of a scene and the light below its port, written as EXR maps,
// CSV tables and PNG previews.
#include <filesystem>
#include <vector>

#include "polrig/io/manifest.h"
#include "polrig/progress.h"
#include "polrig/source/scene.h"

namespace polrig {

// Reports the sphere solve and the plane map to `progress`. The sphere is always solved, and
// kept in the installed sphere cache (source/sphere_cache.h) for the studies of the same scene;
// `origin`, when given, says so and names the cache file.
std::vector<DatasetFile> trace_scene(const std::filesystem::path& dir, const SceneSpec& scene,
                                     bool plots, const Progress& progress = {},
                                     LightOrigin* origin = nullptr);

}  // namespace polrig
