#pragma once
// The checkerboard target of the four cameras' geometric calibration (spec sky-and-compasses.md
// §3.3 item 3, docs/physics.md §16.2): the `checkerboard.*` rig keys and the board's own frame.
//
// The board's frame b: origin at the first inner corner, x_b along a row of inner corners (cols
// of them), y_b along a column (rows of them), z_b = x_b × y_b, the normal pointing away from the
// side the cameras see (a board facing camera 1 squarely has R_b = I: x_b, y_b along the image's
// +x, +y). Inner corner (i, k) (column i, row k) sits at (i·s, k·s, 0), s the square's side; the
// squares fill [−s, cols·s] × [−s, rows·s] and a white margin surrounds them. The square whose
// top-left corner is (−s, −s) is black.
#include <array>
#include <vector>

#include "polrig/vec3.h"

namespace polrig {

struct CheckerboardSpec {
  int views = 0;                    // board poses rendered (0: none)
  std::array<int, 2> inner_corners = {9, 6};  // [cols, rows] of inner corners [C: OpenCV's sample board]
  double square_mm = 30.0;          // a square's side [C]
  double margin_mm = 30.0;          // the white border around the squares [C: one square]
  std::array<double, 2> distance_mm = {450.0, 800.0};  // the board centre's depth in camera 1 [C]
  double tilt_max_deg = 35.0;       // the board normal's largest angle from camera 1's axis [C]
  double roll_max_deg = 15.0;       // the largest turn of the board about its normal [C]
  // The light: I of the white squares and margin, of the black squares, and of the wall behind
  // (the source's intensity units, f = K·I + b) [C: a white well below a 12-bit ADC's top].
  std::array<double, 3> intensity = {2.5, 0.15, 0.6};
};

// A board pose: a point X_b of the board frame lies at R·X_b + t in camera 1's frame (mm).
struct BoardPose {
  std::array<double, 9> R = {1, 0, 0, 0, 1, 0, 0, 0, 1};  // row-major
  Vec3 t = {0, 0, 0};
};

// The board's point (x, y, 0) in camera 1's frame.
inline Vec3 board_point(const BoardPose& p, double x, double y) {
  return {p.R[0] * x + p.R[1] * y + p.t[0], p.R[3] * x + p.R[4] * y + p.t[1], p.R[6] * x + p.R[7] * y + p.t[2]};
}

// The inner corners in the board frame, row-major (k·cols + i), mm: OpenCV's object points.
std::vector<Vec3> checkerboard_object_points(const CheckerboardSpec& board);

// The reflectance pattern at the board point (x, y) (mm, board frame): 1 white (squares and
// margin), 0 black, −1 off the board.
int checkerboard_colour(const CheckerboardSpec& board, double x, double y);

// The board's outline with its margin: x in [x0, x1], y in [y0, y1] (mm, board frame).
struct BoardExtent {
  double x0, x1, y0, y1;
};
BoardExtent checkerboard_extent(const CheckerboardSpec& board);

}  // namespace polrig
