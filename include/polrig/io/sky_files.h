#pragma once
// The files of `polrig sky` and `polrig sky table` (docs/formats.md).
#include <filesystem>
#include <string>
#include <vector>

#include "polrig/io/manifest.h"
#include "polrig/io/measured.h"
#include "polrig/sky/sky.h"
#include "polrig/sky/sky_map.h"

namespace polrig {

// DIR/sky.exr (layers S0, S1, S2, AoP, DoP, A), DIR/sun.yaml and, with plots, DIR/aop.png and
// DIR/dop.png (gnuplot, from DIR/aop.f32 and DIR/dop.f32, with DIR/sky.gp).
std::vector<DatasetFile> write_sky_map(const std::filesystem::path& dir, const SkyMap& map,
                                       const Sky& sky, bool plots);

// `polrig sky table`: every row of INPUT (columns utc, lat_deg, lon_deg, view_az_deg,
// view_el_deg) with sun_az_deg, sun_el_deg, dop, aop_deg added, as CSV text. Throws DataError
// naming the file, line, column and value of the first bad cell.
std::string sky_table_csv(const CsvFile& input, const SkyModel& model, const SunSettings& sun);

}  // namespace polrig
