#pragma once
// Checkerboard views for the four cameras' geometric calibration (spec sky-and-compasses.md §3.3
// item 3, docs/physics.md §16.2): board poses drawn from the rig's seed, each with the whole board
// (its margin included) inside all four cameras' images, and each camera's frame of each view.
// Per pixel, 4 × 4 rays from camera j's centre (camera_position_mm: the baseline matters at a
// finite distance) through its lens (unproject, then R_j1ᵀ into camera 1's frame) meet the board
// plane; the mean of their intensities (white, black or the wall behind) is the pixel's I, the
// light is unpolarized, so f_j = K_j·I + b_j; then the cameras' noise and ADC (DofpExposure, as
// the four-camera frames).
#include <array>
#include <cstdint>
#include <vector>

#include "polrig/device/four_camera.h"
#include "polrig/geometry/checkerboard.h"
#include "polrig/rig/rig.h"

namespace polrig {

inline constexpr int kCheckerboardSupersampling = 4;  // rays per pixel along each axis

// The poses of the rig's checkerboard.views views (camera 1's frame), drawn from the rig's seed:
// the board centre's depth uniform in checkerboard.distance_mm, its direction uniform in angle
// within camera 1's field, the normal tilted up to checkerboard.tilt_max_deg in a uniform azimuth,
// a roll up to checkerboard.roll_max_deg. A draw whose outline (with its margin, 16 points per
// edge) is not inside every camera's image by 3 px is drawn again (view, attempt: its own random
// stream). Throws std::invalid_argument naming the keys when 1000 draws of a view all fail (a
// board too large or too near for the cameras' fields).
std::vector<BoardPose> checkerboard_poses(const Rig& rig);

// Where camera j sees the board point X (camera 1's frame, mm): the continuous pixel.
std::array<double, 2> project_from_camera1(const FourCameraModel& m, const FourCameraSpec& spec, int j, const Vec3& X);

class CheckerboardRenderer {
 public:
  // Throws std::invalid_argument for a rig whose instrument is not a camera array, whose cameras
  // cannot be simulated (four_camera_truth) or whose board cannot be placed (checkerboard_poses).
  explicit CheckerboardRenderer(const Rig& rig);
  const FourCameraModel& truth() const { return truth_; }
  const std::vector<BoardPose>& poses() const { return poses_; }
  const CheckerboardSpec& board() const { return rig_.checkerboard; }

  // View v's noise-free signal f_j (DN), row-major, top row first, every camera (TBB over rows).
  std::array<std::vector<double>, kFourCameras> signal(int view) const;
  // View v's frames: the signal with noise (seed, view, camera, pixel) and the ADC; bit-identical
  // for any number of threads.
  std::array<std::vector<std::uint16_t>, kFourCameras> frames(int view) const;
  // The true pixel of every inner corner (row-major) in camera j at view v.
  std::vector<std::array<double, 2>> true_corners(int view, int j) const;

 private:
  Rig rig_;
  FourCameraModel truth_;
  std::vector<BoardPose> poses_;
  std::uint64_t noise_seed_ = 0;
};

}  // namespace polrig
