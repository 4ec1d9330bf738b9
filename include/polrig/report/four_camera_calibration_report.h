#pragma once
// `polrig calibrate DIR --method four-camera` (docs/formats.md "Four-camera calibration"): W16's
// radiometric and polarizer-angle calibration (calib/four_camera.h) on a four-camera dataset
// written with its raw frames (--layers all), the geometry from a file or the dataset's truth.
//   OUT/calibration.yaml  the calibrated model (io/four_camera_calibration.h)
//   OUT/radiometric.csv   per camera and level: the window's mean DN, the line, the residual
//   OUT/polarizer.csv     per polarized stop: the window's fused AoP and DoP with the nominal and
//                         the fitted axes, the AoP residuals
//   OUT/summary.csv       per fit: how it ended (termination, iterations, rank, residual)
//   OUT/errors.csv        against the dataset's truth.yaml, when it has one
//   OUT/radiometric.png, OUT/polarizer.png (with plots)
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "polrig/calib/four_camera.h"
#include "polrig/io/four_camera_calibration.h"
#include "polrig/io/manifest.h"
#include "polrig/progress.h"

namespace polrig {

struct FourCameraCalibrationRun {
  FourCameraCalibration calibration;
  FourCameraCalibrationFile file;              // what calibration.yaml holds
  std::optional<FourCameraCalibrationFile> truth;  // the dataset's truth.yaml, when it has one
  std::optional<double> truth_dop;             // the rig's device.d (a simulated dataset)
  int levels = 0, polarized = 0;               // the stops used
};

// Reads DIR (stops.csv, truth.yaml, each stop's raw frames; rig.yaml, when present, must describe
// a camera array and gives the ADC's top and, for a cos4 sphere, its intensity per level E_0), takes
// the geometry from `geometry_file` (a calibration.yaml or truth.yaml) or else from DIR/truth.yaml,
// and calibrates. Throws RigError (not a camera array), DataError naming the folder or file (no raw
// frames, no geometry, sizes that disagree), CalibrationError (a fit that cannot be used).
FourCameraCalibrationRun calibrate_four_camera_folder(const std::filesystem::path& dir,
                                                      const std::optional<std::filesystem::path>& geometry_file,
                                                      FourCameraCalibrationOptions options = {},
                                                      const Progress& progress = {});

// Writes the files into `dir` (a staging folder) and returns them for the manifest; reads
// calibration.yaml back (so a file polrig writes is one it reads).
std::vector<DatasetFile> report_four_camera_calibration(const std::filesystem::path& dir,
                                                        const FourCameraCalibrationRun& run, bool plots);

}  // namespace polrig
