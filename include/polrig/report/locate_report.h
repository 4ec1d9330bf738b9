#pragma once
// `polrig locate DIR` (issue 13 §3): W16's position and heading from a four-camera dataset's fused
// sky images. Per stop the sun vector by the eigenvector method over the fused AoP on the virtual
// camera 1 (compass/orientation.h, W16 Eqs. 6–14), then the Eq. 17 fix over all stops and the heading
// ψ = β − α_S per stop (compass/positioning.h: locate). Only glue: the physics is in compass/.
#include <filesystem>
#include <optional>
#include <vector>

#include "polrig/device/four_camera.h"
#include "polrig/io/four_camera_dataset.h"
#include "polrig/io/manifest.h"
#include "polrig/compass/orientation.h"
#include "polrig/compass/positioning.h"
#include "polrig/progress.h"
#include "polrig/sky/sun.h"

namespace polrig {

struct StopSun {
  int stop = 0;
  std::string utc;
  SunVectorSolution sun;  // its status says whether the stop became a sighting
};

struct DatasetLocation {
  std::vector<StopSun> suns;           // every polarized stop with a UTC, in order
  Location location;                   // over the stops whose sun was solved
  std::optional<Site> truth;           // the site of the dataset's sky rig (a simulated dataset)
  std::vector<double> true_heading_deg;  // per sighting (NaN where stops.csv has none)
};

// Throws std::invalid_argument for a dataset with no stop to locate from, and as locate.
// `calibration`: each stop's AoP and DoP re-fused from its raw frames with this model (a
// calibration's, io/four_camera_calibration.h) on its own virtual camera 1, instead of the
// dataset's fused layers (which the simulation fused with its truth); std::invalid_argument for a
// model of another size or a stop without raw frames (a dataset written with --layers fused or aop).
DatasetLocation locate_four_camera_dataset(const FourCameraDataset& dataset, const Site& prior,
                                           const std::optional<Site>& truth,
                                           const OrientationSettings& orientation,
                                           const PositionOptions& options, const Progress& progress = {},
                                           const std::optional<FourCameraModel>& calibration = std::nullopt);
// Reads DIR (rig.yaml, when present, must describe a camera array; its sky gives the truth and the
// ephemeris' settings) and locates; DataError naming the folder for what is wrong with it.
DatasetLocation locate_four_camera_folder(const std::filesystem::path& dir, const Site& prior,
                                          const OrientationSettings& orientation, PositionOptions options,
                                          const Progress& progress = {},
                                          const std::optional<FourCameraModel>& calibration = std::nullopt);

// fix.csv and heading.csv (report_location) and sun.csv: per stop, the eigenvector method's
// status, root, the sun in camera 1's frame (azimuth from X towards Y, elevation) and its fit.
// With `plots` (gnuplot) also map.csv, fix.png (the fix, the truth and each stop's line of position
// on longitude and latitude at equal ground scale), heading.png (the heading per stop against
// time, with the truth) and plots.gp.
std::vector<DatasetFile> report_dataset_location(const std::filesystem::path& dir, const DatasetLocation& run,
                                                 bool plots = false);

}  // namespace polrig
