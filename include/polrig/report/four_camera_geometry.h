#pragma once
// The four cameras' geometric calibration on a dataset (spec sky-and-compasses.md §3.3 item 3,
// docs/physics.md §16.2; docs/formats.md "Four-camera dataset"): the checkerboard views `polrig
// simulate` writes, their corners found and the OpenCV fit (calib/four_camera_geometry.h), and
// geometry.csv, which `polrig calibrate DIR --method four-camera` and Python write.
#include <array>
#include <filesystem>
#include <optional>
#include <vector>

#include "polrig/calib/four_camera_geometry.h"
#include "polrig/io/four_camera_dataset.h"
#include "polrig/io/manifest.h"
#include "polrig/progress.h"
#include "polrig/rig/rig.h"
#include "polrig/sim/checkerboard.h"

namespace polrig {

// DIR/checkerboard/ (board.yaml, poses.csv, view_NNNN.exr with cam1 … cam4 raw DN) of the
// renderer's views, reporting "simulate: checkerboard views"; returns the manifest's entry. The
// renderer is made first (it refuses a board that cannot be placed), so a refusal writes nothing.
std::vector<DatasetFile> report_checkerboard_views(const std::filesystem::path& dir, const CheckerboardRenderer& renderer,
                                                   const Progress& progress = {});

struct FourCameraGeometryCalibration {
  CheckerboardViews views;
  std::vector<std::array<BoardCorners, kFourCameras>> corners;  // [view][camera], polrig's pixels
  FourCameraGeometryFit fit;
  std::optional<FourCameraGeometryTruth> truth;  // from truth.yaml when the dataset is simulated
};

// Reads the dataset's checkerboard views, finds each camera's corners (TBB over the cameras of a
// view; "calibrate: checkerboard views" to `progress`) and fits. A view a camera does not find is
// counted in the summary, not an error. Throws std::runtime_error for a dataset without views
// (naming the folder and checkerboard.views) or a malformed file, and without OpenCV.
FourCameraGeometryCalibration calibrate_four_camera_geometry_folder(const std::filesystem::path& dir,
                                                                    const GeometryFitOptions& options = {},
                                                                    const Progress& progress = {});

// geometry.csv into `out` (an existing folder): one row per camera, the fit (fx, fy, cx, cy, k,
// R_j1's rotation vector in degrees, the position), its summary (views, RMS, termination) and,
// with the truth, the truth's values and the errors (the rotation error as the angle of
// R_fit·R_trueᵀ). Returns the manifest's entry.
std::vector<DatasetFile> report_four_camera_geometry(const std::filesystem::path& out,
                                                     const FourCameraGeometryCalibration& calibration);

// The rotation vector (radians) of a rotation matrix (row-major): the inverse of Rodrigues'
// formula, accurate for small angles (atan2 of the skew part's norm against the trace).
Vec3 rotation_vector(const std::array<double, 9>& R);
// The angle (degrees) of A·Bᵀ: how far rotation A is from B.
double rotation_angle_between_deg(const std::array<double, 9>& A, const std::array<double, 9>& B);

}  // namespace polrig
