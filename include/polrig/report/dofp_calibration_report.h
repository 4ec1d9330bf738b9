#pragma once
// What `polrig calibrate DIR --method dofp` writes (docs/formats.md "DoFP calibration"): the
// per-pixel parameters (params.exr), Table 1 (table1.csv) and its error curves (errors.csv), the
// per-cell fit summaries (cells.csv), and plots: the error curves and a map of each parameter.
#include <filesystem>
#include <vector>

#include "polrig/calib/dofp.h"
#include "polrig/io/manifest.h"

namespace polrig {

// Writes into `dir` (a staging folder the caller commits) and returns the files written, for
// the manifest. Throws std::runtime_error naming a file that cannot be written.
std::vector<DatasetFile> report_dofp_calibration(const std::filesystem::path& dir,
                                                 const DofpCalibration& calibration, bool plots);

}  // namespace polrig
