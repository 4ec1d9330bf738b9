#pragma once
// What `polrig study sky` writes (columns: docs/formats.md §6.21): bias.csv (every sky, sun,
// attitude and method), by_sun.csv (over the headings at each sun), summary.csv (over every sun
// and heading), sky_dop.csv, evector_by_dop.csv and, with plots, heading_bias.png,
// sun_el_bias.png (not for one E-vector, which fixes no elevation), methods.png,
// evector_by_dop.png and dop.png.
#include <filesystem>
#include <vector>

#include "polrig/io/manifest.h"
#include "polrig/study/sky_compasses.h"

namespace polrig {

std::vector<DatasetFile> report_sky_study(const std::filesystem::path& dir, const SkyStudy& study, bool plots);

}  // namespace polrig
