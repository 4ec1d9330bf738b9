#pragma once
// What `polrig study navigation` writes: trials.csv, summary.csv, error_vs_time.csv, tilt.csv,
// dop.csv and, with plots, their figures (columns: docs/formats.md).
#include <filesystem>
#include <vector>

#include "polrig/io/manifest.h"
#include "polrig/study/navigation_study.h"

namespace polrig {

// Throws std::runtime_error, before writing anything, for a value that should be finite and is not.
std::vector<DatasetFile> report_navigation_study(const std::filesystem::path& dir, const NavigationStudy& study,
                                                 bool plots);

}  // namespace polrig
