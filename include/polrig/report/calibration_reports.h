#pragma once
// What the calibration commands write: parameters, error curves, accuracies, the replacement
// analysis (CSV + PNG plots like the paper's Figs. 16, 17, 19, 20 and 21).
#include <filesystem>
#include <vector>

#include "polrig/calib/pipeline.h"
#include "polrig/io/manifest.h"

namespace polrig {

// params.yaml, points.csv, errors.csv, accuracy.csv, replacement.csv and plots.
std::vector<DatasetFile> report_calibration(const std::filesystem::path& dir,
                                            const CalibrationResult& result,
                                            const CalibrationOptions& options, bool plots);

// comparison.csv and comparison.png (Fig. 20): the accuracy of each calibration type.
std::vector<DatasetFile> report_calibration_comparison(
    const std::filesystem::path& dir, const std::vector<CalibrationResult>& results, bool plots);

}  // namespace polrig

#include "polrig/study/calibration_trials.h"

namespace polrig {

// trials.csv, summary.csv, failures.csv (when any failed), cdf.csv and accuracy_cdf.png.
std::vector<DatasetFile> report_calibration_trials(const std::filesystem::path& dir,
                                                   const std::vector<Trial>& trials, bool plots);

}  // namespace polrig
