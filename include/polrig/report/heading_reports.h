#pragma once
// What `polrig study heading` writes: the trials, a summary (overall, per factor alone, binned)
// and plots of the heading error against each factor.
#include <filesystem>
#include <vector>

#include "polrig/io/manifest.h"
#include "polrig/progress.h"
#include "polrig/study/heading_trials.h"

namespace polrig {

// trials.csv, summary.csv, cdf.csv, sun.yaml and, with plots, error_vs_*.png and error_cdf.png
// (drawn in parallel, reported on `progress`: 10⁴ trials take seconds of gnuplot).
std::vector<DatasetFile> report_heading_trials(const std::filesystem::path& dir,
                                               const std::vector<HeadingTrial>& trials,
                                               const HeadingStudySettings& settings, bool plots,
                                               const Progress& progress = {});

}  // namespace polrig
