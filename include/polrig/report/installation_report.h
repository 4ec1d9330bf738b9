#pragma once
// What `polrig calibrate --method unit-array` writes (docs/formats.md §6.19): calibration.yaml (each
// unit's mounting errors, their standard errors, the fit's end, the sun-elevation error before and
// after, the layout fitted), installation.csv (the same per unit, Z21 Table 2's before → after)
// and installation.png. Its reader is io/installation_yaml.h.
#include <filesystem>
#include <vector>

#include "polrig/io/manifest.h"
#include "polrig/study/installation.h"

namespace polrig {

std::vector<DatasetFile> report_installation(const std::filesystem::path& dir, const InstallationRun& run, bool plots);

}  // namespace polrig
