#pragma once
// What `polrig calibrate DIR --method dofp` writes (docs/formats.md "DoFP calibration"): the
// per-pixel parameters (params.exr), Table 1 (table1.csv) and its error curves (errors.csv), the
// per-cell fit summaries (cells.csv), and plots: the error curves and a map of each parameter.
#include <filesystem>
#include <vector>

#include "polrig/calib/dofp.h"
#include "polrig/io/dofp_dataset.h"
#include "polrig/progress.h"
#include "polrig/io/manifest.h"

namespace polrig {

// Writes into `dir` (a staging folder the caller commits) and returns the files written, for
// the manifest. Throws std::runtime_error naming a file that cannot be written.
std::vector<DatasetFile> report_dofp_calibration(const std::filesystem::path& dir,
                                                 const DofpCalibration& calibration, bool plots);

// Both steps and Table 1 on a camera dataset (`polrig calibrate DIR --method dofp`, Python's
// calibrate_dofp_dataset): its unpolarized stops are step 1's levels, its polarized stops step 2's,
// each stop's mean frame; the mosaic's axes are the dataset's (DofpDataset::mosaic_deg) and replace
// options.step2.mosaic_deg; without a saturation level set, step 1 leaves out values at the
// dataset's ADC top (2^adc_bits − 1). Per cell, steps 1 and 2 run on bands of `band_rows` rows
// (even; ≤ 0: as many as keep every stop's band within 128 MB), reading only those rows of each
// stop: the results are calibrate_dofp's on whole frames, bit for bit; Table 1 then reads its
// stops whole. A global step 2 reads every whole frame. Reports "calibrate dofp: steps 1 and 2 by
// bands of rows" (global: "dofp: reading frames" and step 2's cells) to `progress`. Throws
// std::runtime_error naming a file that cannot be read, std::invalid_argument for bad input and
// CalibrationError when Table 1 cannot be formed.
DofpCalibration calibrate_dofp_dataset(const DofpDataset& dataset, DofpCalibrationOptions options,
                                       const Progress& progress = {}, int band_rows = 0);

// calibrate_dofp_dataset on a dataset folder, as `polrig calibrate DIR --method dofp` and Python's
// calibrate_dofp_dataset take it: DIR/rig.yaml (when present) must describe an instrument with
// frames. Throws RigError (a rig without frames), DataError naming a file that cannot be read or a
// bad value, CalibrationError when Table 1 cannot be formed.
DofpCalibration calibrate_dofp_folder(const std::filesystem::path& dir, const DofpCalibrationOptions& options = {},
                                      const Progress& progress = {});

}  // namespace polrig
