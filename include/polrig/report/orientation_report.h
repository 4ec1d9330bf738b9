#pragma once
// What `polrig orient` writes (issue 12 §4): per sky frame and method, the sun in the camera frame,
// the heading and its error where the true heading is known (docs/formats.md "orientation.csv").
#include <array>
#include <filesystem>
#include <optional>
#include <vector>

#include "polrig/device/dofp_camera.h"
#include "polrig/io/dofp_dataset.h"
#include "polrig/io/manifest.h"
#include "polrig/compass/orientation.h"
#include "polrig/progress.h"
#include "polrig/sky/sky.h"

namespace polrig {

// One frame's three estimates (compass/orientation.h: orient_frame) and its true heading, if known.
struct FrameOrientation {
  int frame = 0;
  std::array<OrientationEstimate, 3> estimates{};
  std::optional<double> true_heading_deg;
};

// DIR/orientation.csv: one row per frame and method, columns frame, method, sun_az_deg,
// sun_el_deg, heading_deg, heading_error_deg, status; `nan` where a value is not defined (no
// solution, a comparator's elevation, no true heading). With plots (and gnuplot),
// DIR/heading_error.png: the heading error per frame of the three methods. Throws
// std::runtime_error naming the frame and column if a defined value is not finite (nothing is
// written then).
std::vector<DatasetFile> report_orientation(const std::filesystem::path& dir,
                                            const std::vector<FrameOrientation>& frames, bool plots);

// Every polarized stop of a camera dataset oriented (`polrig orient DIR`, Python's
// orient_dofp_dataset): the stop's mean frame → each cell's AoP and DoP (calib/dofp_polarization:
// with `parameters`, a calibration's per-pixel maps; else the nominal ones of the dataset's mosaic)
// → orient_frame with the dataset's intrinsics and, where the stop has a UTC and `sky` is given,
// the sun's geographic azimuth from the ephemeris; the true heading from stops.csv. With
// heading_prior_deg (an approximate heading of X_l at table angle 0, e.g. a magnetic compass's)
// and a sky, each frame's prior sun is sun_in_level_camera of heading_prior_deg + θ_R (the table
// turns the camera's heading up by θ_R: docs/physics.md §13): the solar/antisolar choice near the
// horizon (spec §2.5); it replaces settings.prior_sun. Reports
// "orient: frames" to `progress`. Throws std::runtime_error naming a file that cannot be read and
// std::invalid_argument for parameters of another size.
std::vector<FrameOrientation> orient_dofp_dataset(const DofpDataset& dataset, const std::optional<Sky>& sky,
                                                  const DofpTruth* parameters,
                                                  const OrientationSettings& settings = {},
                                                  std::optional<double> heading_prior_deg = std::nullopt,
                                                  const Progress& progress = {});

// orient_dofp_dataset on a dataset folder, as `polrig orient DIR` and Python's orient_dofp_dataset
// take it: DIR/rig.yaml (when present) must describe an instrument with frames and gives the sky;
// `params` (when not empty) is a calibration's params.exr. Throws RigError (a rig without frames),
// DataError naming a file that cannot be read or a bad value, std::invalid_argument for
// heading_prior_deg without a sky rig.
std::vector<FrameOrientation> orient_dofp_folder(const std::filesystem::path& dir, const std::filesystem::path& params,
                                                 const OrientationSettings& settings = {},
                                                 std::optional<double> heading_prior_deg = std::nullopt,
                                                 const Progress& progress = {});

}  // namespace polrig
