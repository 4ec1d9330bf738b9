#pragma once
// `polrig calibrate DIR --method four-camera` (docs/formats.md "Four-camera calibration"): W16's
// radiometric and polarizer-angle calibration (calib/four_camera.h) on a four-camera dataset
// written with its raw frames (--layers all), the geometry from a file, or else from the dataset's
// checkerboard views (the geometric calibration, report/four_camera_geometry.h), or else (a
// simulated dataset without views) from its truth.
//   OUT/calibration.yaml  the calibrated model (io/four_camera_calibration.h)
//   OUT/radiometric.csv   per camera and level: the window's mean DN, the line, the residual
//   OUT/polarizer.csv     per polarized stop: the window's fused AoP and DoP with the nominal and
//                         the fitted axes, the AoP residuals
//   OUT/summary.csv       per fit: how it ended (termination, iterations, rank, residual)
//   OUT/errors.csv        against the dataset's truth.yaml, when it has one
//   OUT/geometry.csv      the geometric calibration, when it ran (docs/formats.md §6.14c)
//   OUT/radiometric.png, OUT/polarizer.png (with plots)
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "polrig/calib/four_camera.h"
#include "polrig/io/four_camera_calibration.h"
#include "polrig/io/manifest.h"
#include "polrig/progress.h"
#include "polrig/report/four_camera_geometry.h"

namespace polrig {

struct FourCameraCalibrationRun {
  FourCameraCalibration calibration;
  FourCameraCalibrationFile file;              // what calibration.yaml holds
  std::optional<FourCameraCalibrationFile> truth;  // the dataset's truth.yaml, when it has one
  std::optional<double> truth_dop;             // the rig's device.d (a simulated dataset)
  int levels = 0, polarized = 0;               // the stops used
  std::optional<FourCameraGeometryCalibration> geometry;  // the checkerboard fit, when it ran
};

// Reads DIR (stops.csv, truth.yaml, each stop's raw frames; rig.yaml, when present, must describe
// a camera array and gives the ADC's top and, for a cos4 sphere, its intensity per level E_0), takes
// the geometry from `geometry_file` (a calibration.yaml or truth.yaml), or else from the geometric
// calibration of DIR's checkerboard views (OpenCV, `geometry_options`), or else, for a dataset
// without views, from DIR/truth.yaml, and calibrates. Throws RigError (not a camera array),
// DataError naming the folder or file (no raw frames, no geometry, sizes that disagree, views in a
// build without OpenCV), CalibrationError (a fit that cannot be used, the geometric one included).
FourCameraCalibrationRun calibrate_four_camera_folder(const std::filesystem::path& dir,
                                                      const std::optional<std::filesystem::path>& geometry_file,
                                                      FourCameraCalibrationOptions options = {},
                                                      const Progress& progress = {},
                                                      const GeometryFitOptions& geometry_options = {});

// Writes the files into `dir` (a staging folder) and returns them for the manifest; reads
// calibration.yaml back (so a file polrig writes is one it reads).
std::vector<DatasetFile> report_four_camera_calibration(const std::filesystem::path& dir,
                                                        const FourCameraCalibrationRun& run, bool plots);

}  // namespace polrig
