#pragma once
// The PNG previews of `polrig sky` (docs/formats.md §6.11): plotting, above io/.
#include <filesystem>
#include <vector>

#include "polrig/io/manifest.h"
#include "polrig/sky/sky.h"
#include "polrig/sky/sky_map.h"
#include "polrig/sky/vector_rt.h"

namespace polrig {

// DIR/aop.png and DIR/dop.png (gnuplot, from DIR/aop.f32 and DIR/dop.f32, with DIR/aop.gp and DIR/dop.gp), the
// sun marked; maps wider than 512 px are sampled every ceil(size/512)-th pixel. Beside a sky that
// is not single scattering, DIR/aop_difference.png and DIR/dop_ratio.png; for every sky at 2° or
// higher, DIR/skies_compared.png: single scattering, Berry's sky fitted to the vector-RT sky of
// `atmosphere` (the rig's sky.rt.*), and that sky.
std::vector<DatasetFile> report_sky_previews(const std::filesystem::path& dir, const SkyMap& map,
                                             const Sky& sky, const VectorRtSettings& atmosphere);

}  // namespace polrig
