#pragma once
// The files of `polrig sky` and `polrig sky table` (docs/formats.md §6.11, §6.12): reading and
// formatting only; the values come from sky/ (sky_map, sky_along), the previews from report/.
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "polrig/io/exr.h"
#include "polrig/io/manifest.h"
#include "polrig/io/measured.h"
#include "polrig/sky/sky.h"
#include "polrig/sky/sky_map.h"
#include "polrig/sky/sun_rows.h"

namespace polrig {

// A sun.yaml: the site, time and sun settings, then A_s, h_s, θ_s, δ, GHA and LHA; `what` says
// which sun in its header comment ("at the map's time (polrig sky)").
std::string sun_yaml(std::string_view what, UtcTime t, const Sky& sky, const SunPosition& sun);

// DIR/sky.exr (layers S0, S1, S2, AoP, DoP, A) and DIR/sun.yaml.
std::vector<DatasetFile> write_sky_map(const std::filesystem::path& dir, const SkyMap& map,
                                       const Sky& sky, ExrCompression compression);

// `polrig sky table`'s input: every row of INPUT as a query, in one of two forms: columns utc,
// lat_deg, lon_deg, view_az_deg, view_el_deg (the sun from the ephemeris), or sun_az_deg,
// sun_el_deg, view_az_deg, view_el_deg (a fixed sun, no ephemeris); others are carried through.
// Throws DataError naming the file, line, column and value of the first bad cell, for a file
// without data rows, or for an input column named like one sky table adds.
std::vector<SkyQuery> read_sky_table_input(const CsvFile& input);
// Whether INPUT gives its suns (sun_az_deg, sun_el_deg) rather than times and places.
bool sky_table_fixed_sun(const CsvFile& input);
// sky.csv: the input's columns as written, then sun_az_deg, sun_el_deg (ephemeris rows only), dop,
// aop_deg, and I_sr, Q_sr, U_sr where the sky has an absolute radiance (vector-rt).
std::string sky_table_csv(const CsvFile& input, std::span<const SkySample> samples);

}  // namespace polrig
