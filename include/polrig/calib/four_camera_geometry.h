#pragma once
// The four cameras' geometric calibration (spec sky-and-compasses.md §3.3 item 3, docs/physics.md
// §16.2): each camera's intrinsics with the Kannala–Brandt lens (fx, fy, cx, cy, k1..k4; skew
// fixed at 0) and the cameras' rotations R_j1 and positions, from checkerboard views, by OpenCV's
// camera calibration (cv::findChessboardCorners + cv::cornerSubPix, cv::fisheye::calibrate per
// camera, cv::fisheye::stereoCalibrate of camera 1 with camera j, intrinsics fixed): a library
// made for it rather than a hand-written one. Built only with -DPOLRIG_OPENCV=ON; otherwise every
// function here but four_camera_geometry_available() throws std::runtime_error saying so.
//
// Pixel convention: polrig's (pixel (col, row)'s centre at (col + ½, row + ½)) everywhere in this
// API. OpenCV's images put pixel centres at integers, so detection adds ½ to what OpenCV finds;
// the fit's model is the same for both conventions but for c_x, c_y, so it runs on polrig's
// coordinates and its c_x, c_y are polrig's.
#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "polrig/device/four_camera.h"
#include "polrig/geometry/checkerboard.h"
#include "polrig/vec3.h"

namespace polrig {

// Whether polrig was built with OpenCV (-DPOLRIG_OPENCV=ON).
bool four_camera_geometry_available();
// The message of every call made without it.
inline constexpr std::string_view kNoOpenCvMessage =
    "the geometric calibration needs polrig built with -DPOLRIG_OPENCV=ON (Debian's libopencv-dev)";

// One camera's inner corners in one view: row-major over the board (OpenCV's object-point order,
// checkerboard_object_points), polrig's pixel convention. found = false: none (detection failed).
struct BoardCorners {
  bool found = false;
  std::vector<std::array<double, 2>> uv;
};

// The inner corners of a cols × rows board in one raw frame (DN, row-major, width × height):
// the frame scaled to 8 bits between its smallest and largest value, cv::findChessboardCorners
// (adaptive threshold, normalised image), cv::cornerSubPix (a window half the corners' smallest
// spacing wide, 2–10 px either side; to 1e-4 px or 100 iterations). The order is made the board's: the first corner is the one whose image x is
// smaller than the last's (OpenCV may return the grid from either end). Never throws for an image
// without the board (found = false); throws std::runtime_error without OpenCV.
BoardCorners detect_board_corners(std::span<const std::uint16_t> frame, int width, int height, int cols, int rows);

// How one OpenCV fit ended. OpenCV's fisheye solvers stop when the parameters' relative change is
// ≤ ε or after max_iterations; they report neither, so the fit is run again with one more
// iteration allowed: the same result bit for bit means it stopped on ε (converged), else on the
// count (iteration_limit).
enum class GeometryTermination {
  Converged,
  IterationLimit,
  TooFewViews,  // fewer views than min_views detected (in both cameras, for a pair)
  Failed,       // OpenCV threw (its message), or a result is not finite
};
std::string_view geometry_termination_name(GeometryTermination t);  // "converged", "iteration_limit", …

struct CameraFitSummary {
  int views = 0;           // views offered
  int views_detected = 0;  // views whose corners were found
  int views_used = 0;      // views in the fit
  double rms_px = std::numeric_limits<double>::quiet_NaN();  // OpenCV's RMS reprojection error
  GeometryTermination termination = GeometryTermination::TooFewViews;
  std::string message;
  bool usable() const { return termination == GeometryTermination::Converged; }
};

struct StereoFitSummary {
  int views_used = 0;  // views found by both cameras
  double rms_px = std::numeric_limits<double>::quiet_NaN();
  GeometryTermination termination = GeometryTermination::TooFewViews;
  std::string message;
  bool usable() const { return termination == GeometryTermination::Converged; }
};

struct FourCameraGeometrySummary {
  std::array<CameraFitSummary, kFourCameras> camera;
  // stereo[j]: camera 1 with camera j (j = 1, 2, 3); stereo[0] is camera 1 itself (converged,
  // identity, no fit).
  std::array<StereoFitSummary, kFourCameras> stereo;
  bool usable() const;
  // One line per fit: "camera 2: converged, 12/12 views, RMS 0.031 px" …
  std::string brief_report() const;
};

struct FourCameraGeometryFit {
  std::array<CameraGeometry, kFourCameras> camera;  // R of camera 1: the identity
  std::array<Vec3, kFourCameras> position_mm{};     // camera j's centre in camera 1's frame, −R_j1ᵀ·T
  FourCameraGeometrySummary summary;
};

struct GeometryFitOptions {
  int max_iterations = 200;
  double epsilon = 1e-14;  // OpenCV's relative parameter change
  int min_views = 4;       // fewer: TooFewViews (8 intrinsics + 6 per view; the lens needs varied tilts)
  // Kannala–Brandt terms fitted, k1 … k_n (0–4); the rest are held at 0 (OpenCV's
  // fisheye::CALIB_FIX_K1 … K4). Fewer terms extrapolate better beyond the views' corners
  // (docs/physics.md §16.2); throws std::invalid_argument outside [0, 4].
  int distortion_terms = 4;
};

// The fit from detected (or exact) corners: corners[v][j] is camera j's in view v. The board
// gives the object points (checkerboard_object_points). Never throws for data that cannot be
// fitted (the summary says why); throws std::invalid_argument for corners of the wrong count and
// std::runtime_error without OpenCV.
FourCameraGeometryFit fit_four_camera_geometry(const std::vector<std::array<BoardCorners, kFourCameras>>& corners,
                                               const CheckerboardSpec& board, int width, int height,
                                               const GeometryFitOptions& options = {});

}  // namespace polrig
