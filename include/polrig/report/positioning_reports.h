#pragma once
// What `polrig study positioning` writes (the cells, the trials, plots), and the locate core's
// fix.csv and heading.csv (`polrig locate`). Columns: docs/formats.md.
#include <filesystem>
#include <optional>
#include <vector>

#include "polrig/io/manifest.h"
#include "polrig/compass/positioning.h"
#include "polrig/study/positioning.h"

namespace polrig {

// summary.csv, trials.csv and, with plots, error_vs_window.png, error_vs_noise.png,
// error_vs_tilt.png and fixes.png (the baseline cell's fixes around the truth).
std::vector<DatasetFile> report_positioning_study(const std::filesystem::path& dir,
                                                  const PositioningStudy& study, bool plots);

// fix.csv: one row per root (the chosen first, then the alternative when there is one), with
// error_km against `truth` (NaN without one); heading.csv: one row per sighting, with the
// true heading and the error when `true_heading_deg` is given (one per sighting, NaN allowed).
// Throws std::invalid_argument when true_heading_deg's length differs from the samples'.
std::vector<DatasetFile> report_location(const std::filesystem::path& dir, const Location& location,
                                         const std::optional<Site>& truth = std::nullopt,
                                         const std::vector<double>& true_heading_deg = {});

}  // namespace polrig
