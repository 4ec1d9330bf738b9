#pragma once
// Reads a four-camera dataset (report/four_camera_dataset.h writes it; docs/formats.md): the stops,
// the virtual camera 1 (the fused image's CameraIntrinsics) and, per stop, the fused AoP and DoP,
// and the raw frames when the dataset holds them. For `locate`, the calibration and Python.
#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "polrig/device/four_camera.h"
#include "polrig/geometry/checkerboard.h"
#include "polrig/compass/orientation.h"
#include "polrig/vec3.h"

namespace polrig {

struct FourCameraDatasetStop {
  int stop = 0;
  std::string utc;                    // empty for a source without a clock (the sphere rig)
  double t_s = 0;
  double theta_R_deg = 0;
  double intensity = 1;
  bool polarized = true;
  std::optional<double> heading_deg;  // true geographic azimuth of camera 1's X (sky rigs)
  std::optional<Vec3> sun_camera1;    // the true sun in camera 1's frame (sky rigs)
  std::string file;                   // relative to the dataset folder
};

struct FourCameraDataset {
  std::filesystem::path dir;
  int width = 0, height = 0;  // the virtual grid's (= each camera's) size
  // The virtual camera 1 of the fused layers: f_c and the principal point, px. Nothing for a
  // measured dataset of raw frames alone (no truth.yaml, no f_c_px attribute): a calibration's
  // fusion brings its own.
  std::optional<CameraIntrinsics> camera;
  std::vector<FourCameraDatasetStop> stops;
};

// A simulated dataset's size and virtual camera come from truth.yaml; a measured one (no
// truth.yaml) gives its size by its first stop's EXR and its virtual camera by that EXR's
// f_c_px, cx_px, cy_px attributes when it has them. Throws std::runtime_error naming the file (and
// the line and column of stops.csv) for a missing or malformed file.
FourCameraDataset read_four_camera_dataset(const std::filesystem::path& dir);

// A stop's fused AoP (degrees, camera 1's image frame, [0°, 180°)) and DoP on the virtual grid,
// row-major, top row first; NaN where no camera array pixel covers it (valid = 0), as
// compass/orientation.h's SkyPoints leave points out. Both stop readers decompress on the calling
// thread (ExrThreads::ThisThread): read several stops side by side (side_by_side.h) to use more
// cores.
struct FusedAopDop {
  std::vector<double> aop_deg, dop;
};
FusedAopDop read_four_camera_fused(const FourCameraDataset& dataset, std::size_t stop_index);
// A stop's four raw frames (DN); throws for a dataset written without them (--layers fused/aop).
std::array<std::vector<std::uint16_t>, 4> read_four_camera_raw(const FourCameraDataset& dataset,
                                                               std::size_t stop_index);

// ---- Checkerboard views (the geometric calibration's; docs/formats.md "Four-camera dataset") ----
// DIR/checkerboard/board.yaml (the target: what a calibration knows), DIR/checkerboard/poses.csv
// (one row per view: its file and, for a simulated dataset, the true pose), view_NNNN.exr (cam1 …
// cam4, raw DN).
struct CheckerboardViews {
  std::filesystem::path dir;   // the dataset folder
  int width = 0, height = 0;   // each camera's frame
  CheckerboardSpec board;      // views, inner corners, square and margin (the rest: defaults)
  std::vector<std::string> files;                 // relative to the dataset folder
  std::vector<std::optional<BoardPose>> poses;    // the truth, when the dataset holds it
};
// Throws std::runtime_error naming the file (and line) for a missing or malformed file; a dataset
// without checkerboard/ gives zero views.
CheckerboardViews read_checkerboard_views(const std::filesystem::path& dir);
// View v's four raw frames (DN), width × height each.
std::array<std::vector<std::uint16_t>, 4> read_checkerboard_view(const CheckerboardViews& views, std::size_t v);

// The cameras' true geometry from truth.yaml (a simulated dataset), or nothing when there is no
// truth.yaml (a measured dataset) or it holds no cameras; throws std::runtime_error naming the
// file for a malformed one.
struct FourCameraGeometryTruth {
  std::array<CameraGeometry, 4> camera;
  std::array<Vec3, 4> position_mm{};
};
std::optional<FourCameraGeometryTruth> read_four_camera_geometry_truth(const std::filesystem::path& dir);

}  // namespace polrig
