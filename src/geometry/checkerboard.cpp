#include "polrig/geometry/checkerboard.h"

#include <cmath>
#include <vector>

namespace polrig {

std::vector<Vec3> checkerboard_object_points(const CheckerboardSpec& board) {
  std::vector<Vec3> p;
  p.reserve(static_cast<std::size_t>(board.inner_corners[0] * board.inner_corners[1]));
  for (int k = 0; k < board.inner_corners[1]; ++k)
    for (int i = 0; i < board.inner_corners[0]; ++i) p.push_back({i * board.square_mm, k * board.square_mm, 0.0});
  return p;
}

BoardExtent checkerboard_extent(const CheckerboardSpec& board) {
  const double s = board.square_mm, m = board.margin_mm;
  return {-s - m, board.inner_corners[0] * s + m, -s - m, board.inner_corners[1] * s + m};
}

int checkerboard_colour(const CheckerboardSpec& board, double x, double y) {
  const BoardExtent e = checkerboard_extent(board);
  if (!(x >= e.x0 && x <= e.x1 && y >= e.y0 && y <= e.y1)) return -1;
  const double s = board.square_mm;
  // Square (a, b) spans [(a − 1)·s, a·s) × [(b − 1)·s, b·s); a, b in [0, cols] × [0, rows].
  const double a = std::floor(x / s) + 1.0, b = std::floor(y / s) + 1.0;
  if (a < 0 || b < 0 || a > board.inner_corners[0] || b > board.inner_corners[1]) return 1;  // the margin
  return (static_cast<long long>(a + b) % 2 == 0) ? 0 : 1;
}

}  // namespace polrig
