#pragma once
// The simulate dataset's CSV files (docs/formats.md): stops.csv, one row per table stop, and
// samples.csv, every quantized sample, when asked for.
#include <filesystem>
#include <vector>

#include "polrig/io/manifest.h"
#include "polrig/sim/simulate.h"

namespace polrig {

// Writes the CSVs and returns their manifest entries.
std::vector<DatasetFile> write_simulation(const std::filesystem::path& dir, const Simulation& sim);

}  // namespace polrig
