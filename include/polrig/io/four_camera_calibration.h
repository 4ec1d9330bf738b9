#pragma once
// calibration.yaml of the four-camera sensor (docs/formats.md "Four-camera calibration"): per
// camera its gain and offset, polarizer axis and mounting error, and its geometry (intrinsics,
// Kannala–Brandt k, R_j1 as a rotation vector, position), the image size and where each part came
// from. Its per-camera keys are truth.yaml's (report/four_camera_dataset.h), so the reader also
// takes a dataset's truth.yaml (its extra keys ignored). It is what `calibrate --method four-camera`
// writes and what `--geometry` and `locate --calibration` read.
#include <array>
#include <filesystem>
#include <optional>
#include <string>

#include "polrig/device/four_camera.h"
#include "polrig/compass/orientation.h"
#include "polrig/vec3.h"

namespace polrig {

// truth.yaml's virtual_camera: camera 1's undistorted pinhole grid, the fused layers' image.
struct VirtualCameraSpec {
  int width = 0, height = 0;
  CameraIntrinsics camera;
};

struct FourCameraCalibrationFile {
  FourCameraModel model;  // width, height, each camera's geometry, K, b, axis_deg = φ_j + ε_j
  PerCamera polarizer_deg{}, eps_deg{};
  std::array<Vec3, kFourCameras> position_mm{};
  // Whether the file holds the radiometric (K_DN, b_DN) and polarizer (polarizer_deg, eps_deg,
  // axis_deg) parts: a geometry-only file (the geometric calibration's) has neither.
  bool radiometric = false, polarizer = false;
  // Where each part came from (sources.radiometric/polarizer/geometry; "" when not given).
  std::string radiometric_from, polarizer_from, geometry_from;
  // truth.yaml's extra keys, checked as strictly: its virtual_camera, and each camera's R_j1 as
  // written (exact, where rvec_deg rounds).
  std::optional<VirtualCameraSpec> virtual_camera;
  std::array<std::optional<std::array<double, 9>>, kFourCameras> R_j1{};
};

// The file's text (shortest round-trip numbers: it reads back to the same doubles). It does not
// check ranges: report/four_camera_calibration_report.h reads what it writes back.
std::string four_camera_calibration_yaml(const FourCameraCalibrationFile& file);

// Reads calibration.yaml (or truth.yaml: the one reader of both). Throws DataError naming the file,
// the line, the key and the value for a missing, malformed or out-of-range value (every value has a
// physical range, docs/formats.md), an unknown key, a key given twice, cameras not numbered 1–4 in
// order, camera 1 rotated, or axis_deg ≠ polarizer_deg + eps_deg.
FourCameraCalibrationFile read_four_camera_calibration(const std::filesystem::path& path);

// The model of a full calibration.yaml (what `locate --calibration` fuses with): read_four_camera_
// calibration, and DataError naming the file when it lacks the radiometric or polarizer part (a
// geometry-only file).
FourCameraModel read_four_camera_model(const std::filesystem::path& path);

// The rotation vector (degrees) of a rotation matrix (row-major): the inverse of
// rotation_from_vector, angle in [0°, 180°].
Vec3 rotation_vector_deg(const std::array<double, 9>& R);

}  // namespace polrig
