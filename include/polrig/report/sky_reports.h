#pragma once
// The PNG previews of `polrig sky` (docs/formats.md §6.11): plotting, above io/.
#include <filesystem>
#include <vector>

#include "polrig/io/manifest.h"
#include "polrig/sky/sky.h"
#include "polrig/sky/sky_map.h"

namespace polrig {

// DIR/aop.png and DIR/dop.png (gnuplot, from DIR/aop.f32 and DIR/dop.f32, with DIR/aop.gp and DIR/dop.gp), the
// sun marked; maps wider than 512 px are sampled every ceil(size/512)-th pixel.
std::vector<DatasetFile> report_sky_previews(const std::filesystem::path& dir, const SkyMap& map,
                                             const Sky& sky);

}  // namespace polrig
