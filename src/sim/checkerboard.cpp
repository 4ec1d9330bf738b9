#include "polrig/sim/checkerboard.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "polrig/random.h"
#include "polrig/units.h"

namespace polrig {

namespace {

constexpr std::uint64_t kBoardPoseStream = 6, kBoardNoiseStream = 7;  // derive_seed indices (2: the frames' noise)
constexpr int kMaxDraws = 1000;
constexpr double kInsidePx = 3.0;

// R_b = R_tilt · R_roll: a roll ρ about z, then a tilt τ about the in-plane axis (−sin β, cos β, 0).
std::array<double, 9> board_rotation(double tilt, double beta, double roll) {
  const std::array<double, 9> Rt = rotation_from_vector({-std::sin(beta) * tilt, std::cos(beta) * tilt, 0.0});
  const std::array<double, 9> Rr = rotation_from_vector({0.0, 0.0, roll});
  std::array<double, 9> R{};
  for (std::size_t r = 0; r < 3; ++r)
    for (std::size_t c = 0; c < 3; ++c)
      for (std::size_t k = 0; k < 3; ++k) R[r * 3 + c] += Rt[r * 3 + k] * Rr[k * 3 + c];
  return R;
}

bool inside_all(const FourCameraModel& m, const FourCameraSpec& spec, const CheckerboardSpec& board,
                const BoardPose& pose) {
  const BoardExtent e = checkerboard_extent(board);
  constexpr int kPerEdge = 16;
  for (int j = 0; j < kFourCameras; ++j)
    for (int edge = 0; edge < 4; ++edge)
      for (int q = 0; q < kPerEdge; ++q) {
        const double f = static_cast<double>(q) / kPerEdge;
        const double x = edge == 0 ? e.x0 + f * (e.x1 - e.x0) : edge == 1 ? e.x1 : edge == 2 ? e.x1 - f * (e.x1 - e.x0) : e.x0;
        const double y = edge == 0 ? e.y0 : edge == 1 ? e.y0 + f * (e.y1 - e.y0) : edge == 2 ? e.y1 : e.y1 - f * (e.y1 - e.y0);
        const auto uv = project_from_camera1(m, spec, j, board_point(pose, x, y));
        if (!(uv[0] >= kInsidePx && uv[0] <= m.width - kInsidePx && uv[1] >= kInsidePx && uv[1] <= m.height - kInsidePx))
          return false;
      }
  return true;
}

}  // namespace

std::array<double, 2> project_from_camera1(const FourCameraModel& m, const FourCameraSpec& spec, int j, const Vec3& X) {
  const CameraGeometry& c = m.camera.at(static_cast<std::size_t>(j));
  const Vec3 d = vec3::sub(X, camera_position_mm(spec, j));
  const auto& R = c.R;  // v_j = R_j1·v_1
  const Vec3 v = {R[0] * d[0] + R[1] * d[1] + R[2] * d[2], R[3] * d[0] + R[4] * d[1] + R[5] * d[2],
                  R[6] * d[0] + R[7] * d[1] + R[8] * d[2]};
  // Beyond 90° from the axis project() gives NaN, which every comparison refuses.
  return project(c, v);
}

std::vector<BoardPose> checkerboard_poses(const Rig& rig) {
  const CheckerboardSpec& b = rig.checkerboard;
  const FourCameraModel m = four_camera_truth(rig.four_camera);
  const std::uint64_t seed = derive_seed(rig.seed, kBoardPoseStream);
  const double half_x = 0.5 * deg2rad(four_camera_fov_x_deg(m, 0)), half_y = 0.5 * deg2rad(four_camera_fov_y_deg(m, 0));
  const double cx = 0.5 * (b.inner_corners[0] - 1) * b.square_mm, cy = 0.5 * (b.inner_corners[1] - 1) * b.square_mm;
  std::vector<BoardPose> poses;
  for (int v = 0; v < b.views; ++v) {
    bool placed = false;
    for (int attempt = 0; attempt < kMaxDraws && !placed; ++attempt) {
      const UniformStream u(seed, static_cast<std::uint64_t>(v), static_cast<std::uint64_t>(attempt));
      const double depth = b.distance_mm[0] + (b.distance_mm[1] - b.distance_mm[0]) * u(0);
      const double ax = (2.0 * u(1) - 1.0) * half_x, ay = (2.0 * u(2) - 1.0) * half_y;
      const double tilt = deg2rad(b.tilt_max_deg) * u(3), beta = 2.0 * std::numbers::pi * u(4);
      const double roll = deg2rad(b.roll_max_deg) * (2.0 * u(5) - 1.0);
      BoardPose p;
      p.R = board_rotation(tilt, beta, roll);
      const Vec3 centre = {depth * std::tan(ax), depth * std::tan(ay), depth};
      // t = centre − R·(cx, cy, 0) (p.t is still 0): the inner corners' middle at `centre`.
      p.t = vec3::sub(centre, board_point(p, cx, cy));
      if (inside_all(m, rig.four_camera, b, p)) {
        poses.push_back(p);
        placed = true;
      }
    }
    if (!placed) {
      const BoardExtent e = checkerboard_extent(b);
      throw std::invalid_argument(fmt::format(
          "checkerboard view {}: no pose in {} draws keeps the whole board ({:g} × {:g} mm with its margin) inside all "
          "four cameras' images (checkerboard.distance_mm [{:g}, {:g}], checkerboard.square_mm {:g}, "
          "checkerboard.tilt_max_deg {:g}): move the board farther or make it smaller",
          v + 1, kMaxDraws, e.x1 - e.x0, e.y1 - e.y0, b.distance_mm[0], b.distance_mm[1], b.square_mm, b.tilt_max_deg));
    }
  }
  return poses;
}

CheckerboardRenderer::CheckerboardRenderer(const Rig& rig) : rig_(rig) {
  if (!rig.instrument().has(Instrument::kCameraArray))
    throw std::invalid_argument(
        fmt::format("checkerboard views need a camera array (device.kind four-camera), not {}", rig.device_kind));
  truth_ = four_camera_truth(rig.four_camera);
  poses_ = checkerboard_poses(rig);
  noise_seed_ = derive_seed(rig.seed, kBoardNoiseStream);
}

std::array<std::vector<double>, kFourCameras> CheckerboardRenderer::signal(int view) const {
  const BoardPose& p = poses_.at(static_cast<std::size_t>(view));
  const CheckerboardSpec& b = rig_.checkerboard;
  const int W = truth_.width, H = truth_.height;
  const std::size_t n = static_cast<std::size_t>(W) * static_cast<std::size_t>(H);
  const Vec3 normal = {p.R[2], p.R[5], p.R[8]}, bx = {p.R[0], p.R[3], p.R[6]}, by = {p.R[1], p.R[4], p.R[7]};
  const BoardExtent e = checkerboard_extent(b);
  constexpr int S = kCheckerboardSupersampling;
  std::array<std::vector<double>, kFourCameras> f;
  for (int j = 0; j < kFourCameras; ++j) {
    const auto J = static_cast<std::size_t>(j);
    const CameraGeometry& c = truth_.camera[J];
    const Vec3 o = camera_position_mm(rig_.four_camera, j);
    const double K = truth_.K[J], bj = truth_.b[J];
    // The board's bounding box in this camera, a pixel wider (outside it every ray sees the wall).
    double u0 = W, u1 = 0, v0 = H, v1 = 0;
    for (int q = 0; q <= 64; ++q)
      for (int side = 0; side < 4; ++side) {
        const double t = q / 64.0;
        const double x = side < 2 ? e.x0 + t * (e.x1 - e.x0) : (side == 2 ? e.x0 : e.x1);
        const double y = side < 2 ? (side == 0 ? e.y0 : e.y1) : e.y0 + t * (e.y1 - e.y0);
        const auto uv = project_from_camera1(truth_, rig_.four_camera, j, board_point(p, x, y));
        u0 = std::min(u0, uv[0]), u1 = std::max(u1, uv[0]), v0 = std::min(v0, uv[1]), v1 = std::max(v1, uv[1]);
      }
    f[J].assign(n, K * b.intensity[2] + bj);
    const int r0 = std::max(0, static_cast<int>(std::floor(v0)) - 1), r1 = std::min(H, static_cast<int>(std::ceil(v1)) + 1);
    const int c0 = std::max(0, static_cast<int>(std::floor(u0)) - 1), c1 = std::min(W, static_cast<int>(std::ceil(u1)) + 1);
    const auto& R = c.R;
    tbb::parallel_for(tbb::blocked_range<int>(r0, std::max(r0, r1), 4), [&](const tbb::blocked_range<int>& rows) {
      for (int row = rows.begin(); row < rows.end(); ++row)
        for (int col = c0; col < c1; ++col) {
          double sum = 0;
          for (int sy = 0; sy < S; ++sy)
            for (int sx = 0; sx < S; ++sx) {
              const Vec3 dj = unproject(c, col + (sx + 0.5) / S, row + (sy + 0.5) / S);
              // d_1 = R_j1ᵀ·d_j, from camera j's centre o; the plane n·(X − t) = 0.
              const Vec3 d = {R[0] * dj[0] + R[3] * dj[1] + R[6] * dj[2], R[1] * dj[0] + R[4] * dj[1] + R[7] * dj[2],
                              R[2] * dj[0] + R[5] * dj[1] + R[8] * dj[2]};
              const double nd = vec3::dot(normal, d);
              double I = b.intensity[2];
              if (nd != 0.0) {
                const double s = vec3::dot(normal, vec3::sub(p.t, o)) / nd;
                if (s > 0) {
                  const Vec3 rel = vec3::sub(vec3::add(o, vec3::mul(d, s)), p.t);
                  const int colour = checkerboard_colour(b, vec3::dot(rel, bx), vec3::dot(rel, by));
                  if (colour >= 0) I = b.intensity[colour == 1 ? 0 : 1];
                }
              }
              sum += I;
            }
          f[J][static_cast<std::size_t>(row) * static_cast<std::size_t>(W) + static_cast<std::size_t>(col)] =
              K * sum / (S * S) + bj;
        }
    });
  }
  return f;
}

std::array<std::vector<std::uint16_t>, kFourCameras> CheckerboardRenderer::frames(int view) const {
  const std::array<std::vector<double>, kFourCameras> f = signal(view);
  const DofpCameraSpec noise = exposure_spec(rig_.four_camera);
  std::array<std::vector<std::uint16_t>, kFourCameras> raw;
  for (std::size_t j = 0; j < 4; ++j) {
    raw[j].resize(f[j].size());
    const DofpExposure expose(noise, noise_seed_, static_cast<std::uint64_t>(view), j);
    const double b = truth_.b[j];
    const double* in = f[j].data();
    std::uint16_t* out = raw[j].data();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, f[j].size(), 8192), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i < r.end(); ++i) out[i] = expose(in[i], b, i);
    });
  }
  return raw;
}

std::vector<std::array<double, 2>> CheckerboardRenderer::true_corners(int view, int j) const {
  const BoardPose& p = poses_.at(static_cast<std::size_t>(view));
  std::vector<std::array<double, 2>> uv;
  for (const Vec3& X : checkerboard_object_points(rig_.checkerboard))
    uv.push_back(project_from_camera1(truth_, rig_.four_camera, j, board_point(p, X[0], X[1])));
  return uv;
}

}  // namespace polrig
