// The four cameras' geometric calibration (spec sky-and-compasses.md §3.3 item 3, docs/physics.md
// §16.2): OpenCV's fisheye calibration against polrig's own Kannala–Brandt model, on exact corners
// (an independent implementation recovers polrig's parameters: the lens convention, the pixel
// centres and R_j1's sense), on rendered views through corner detection with tolerances derived
// from the measured corner error, and the refusals.
#include <chrono>
#include <cmath>

#include <Eigen/Dense>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "polrig/calib/four_camera_geometry.h"
#include "polrig/io/four_camera_dataset.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/report/four_camera_dataset.h"
#include "polrig/report/four_camera_geometry.h"
#include "polrig/rig/error.h"
#include "polrig/sim/checkerboard.h"
#include "polrig/units.h"
#include "support.h"

using namespace polrig;
using namespace polrig::test;

namespace {

#define SKIP_WITHOUT_OPENCV() \
  if (!four_camera_geometry_available()) GTEST_SKIP() << kNoOpenCvMessage

// A four-camera rig scaled by `s` (1: W16's 1034 × 778 with f ≈ 770 px), with a Kannala–Brandt
// lens that is not the equidistant one (so the fit has distortion to find), the default
// misalignments and the board's keys: at a third of W16's size, 45 mm squares at 0.6–0.9 m are
// 13–19 px wide, which cv::findChessboardCorners finds in every view (30 mm ones at 0.8 m, under
// 10 px and foreshortened, it misses in some).
constexpr const char* kBoard = "  square_mm: 45\n  margin_mm: 35\n  distance_mm: [600, 900]\n";
std::string rig_text(double s, bool noise, int views, const std::string& board = kBoard) {
  const int W = static_cast<int>(1034 * s), H = static_cast<int>(778 * s);
  const double f = 770 * s;
  return fmt::format(
      "device:\n  kind: four-camera\n  cameras:\n    width_px: {}\n    height_px: {}\n    noise: {}\n"
      "    fx_px: [{}, {}, {}, {}]\n    fy_px: [{}, {}, {}, {}]\n"
      "    cx_px: [{}, {}, {}, {}]\n    cy_px: [{}, {}, {}, {}]\n"
      "    k1: [0.02, -0.01, 0.015, 0.005]\n    k2: [-0.01, 0.004, 0.0, 0.008]\n"
      "    k3: [0.003, 0.0, -0.002, 0.001]\n    k4: [0.0, 0.001, 0.0, -0.001]\n"
      "checkerboard:\n  views: {}\n{}"
      "schedule:\n  start_deg: 0\n  step_deg: 0\n  count: 1\n",
      W, H, noise ? "true" : "false", f, f * 1.0015, f * 0.9986, f * 1.0008, f * 1.0004, f * 1.0011, f * 0.999,
      f * 1.0002, 0.5 * W + 1.2 * s, 0.5 * W - 1.4 * s, 0.5 * W + 0.6 * s, 0.5 * W - 0.3 * s, 0.5 * H - 0.8 * s,
      0.5 * H + 1.1 * s, 0.5 * H - 0.5 * s, 0.5 * H + 0.9 * s, views, board);
}

Rig make_rig(const std::string& text) { return parse_rig(text, "test.yaml").rig; }

// ---- The linearised estimator: how corner errors move the fitted parameters (first order) ----
// Camera j sees the board of view v with pose (R_jv, t_jv): X_j = R_jv·X_b + t_jv.
struct Pose {
  std::array<double, 9> R;
  Vec3 t;
};
std::array<double, 9> mul(const std::array<double, 9>& A, const std::array<double, 9>& B) {
  std::array<double, 9> M{};
  for (std::size_t r = 0; r < 3; ++r)
    for (std::size_t c = 0; c < 3; ++c)
      for (std::size_t k = 0; k < 3; ++k) M[r * 3 + c] += A[r * 3 + k] * B[k * 3 + c];
  return M;
}
Vec3 rotate(const std::array<double, 9>& R, const Vec3& x) {
  return {R[0] * x[0] + R[1] * x[1] + R[2] * x[2], R[3] * x[0] + R[4] * x[1] + R[5] * x[2],
          R[6] * x[0] + R[7] * x[1] + R[8] * x[2]};
}
Pose camera_pose(const FourCameraModel& m, const Rig& rig, int j, const BoardPose& b) {
  const auto& Rj = m.camera[static_cast<std::size_t>(j)].R;
  return {mul(Rj, b.R), rotate(Rj, vec3::sub(b.t, camera_position_mm(rig.four_camera, j)))};
}
// The 2·n corner coordinates of one view in one camera.
void corners_into(const CameraGeometry& c, const Pose& p, const std::vector<Vec3>& object, Eigen::Ref<Eigen::VectorXd> out) {
  for (std::size_t i = 0; i < object.size(); ++i) {
    const auto uv = project(c, vec3::add(rotate(p.R, object[i]), p.t));
    out[static_cast<Eigen::Index>(2 * i)] = uv[0], out[static_cast<Eigen::Index>(2 * i + 1)] = uv[1];
  }
}
CameraGeometry perturbed(CameraGeometry c, int k, double h) {
  double* p[8] = {&c.fx, &c.fy, &c.cx, &c.cy, &c.k[0], &c.k[1], &c.k[2], &c.k[3]};
  *p[k] += h;
  return c;
}
Pose perturbed(const Pose& p, int k, double h) {  // k < 3: exp([h·e_k])·R; else t_k + h
  Pose q = p;
  if (k < 3) {
    Vec3 w{0, 0, 0};
    w[static_cast<std::size_t>(k)] = h;
    q.R = mul(rotation_from_vector(w), p.R), q.t = rotate(rotation_from_vector(w), p.t);
  } else {
    q.t[static_cast<std::size_t>(k - 3)] += h;
  }
  return q;
}
constexpr double kStepIntrinsic[8] = {1e-4, 1e-4, 1e-4, 1e-4, 1e-6, 1e-6, 1e-6, 1e-6};
constexpr double kStepPose[6] = {1e-7, 1e-7, 1e-7, 1e-4, 1e-4, 1e-4};

// The Jacobian (central differences of polrig's project()) of camera j's corners over `views`
// w.r.t. its 8 intrinsics and each view's 6 pose parameters (OpenCV's per-camera fit's unknowns).
// m: the intrinsics fitted (fx, fy, cx, cy and the first m − 4 of k).
Eigen::MatrixXd camera_jacobian(const CameraGeometry& c, const std::vector<Pose>& poses, const std::vector<Vec3>& object,
                                int m) {
  const auto n = static_cast<Eigen::Index>(2 * object.size());
  const auto V = static_cast<Eigen::Index>(poses.size());
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(n * V, m + 6 * V);
  Eigen::VectorXd a(n), b(n);
  for (Eigen::Index v = 0; v < V; ++v) {
    const Pose& p = poses[static_cast<std::size_t>(v)];
    for (int k = 0; k < m; ++k) {
      const double h = kStepIntrinsic[k];
      corners_into(perturbed(c, k, h), p, object, a);
      corners_into(perturbed(c, k, -h), p, object, b);
      J.block(v * n, k, n, 1) = (a - b) / (2 * h);
    }
    for (int k = 0; k < 6; ++k) {
      const double h = kStepPose[k];
      corners_into(c, perturbed(p, k, h), object, a);
      corners_into(c, perturbed(p, k, -h), object, b);
      J.block(v * n, m + 6 * v + k, n, 1) = (a - b) / (2 * h);
    }
  }
  return J;
}
Eigen::MatrixXd pinv(const Eigen::MatrixXd& J) { return (J.transpose() * J).ldlt().solve(J.transpose()); }

// First-order bounds of the fitted parameters' errors given the measured corner errors: a fit is
// θ̂ = θ + G·e + O(e²) with G the estimator's linear map, so |δθ_i| ≤ ‖G_i‖·‖e‖ (Cauchy–Schwarz)
// for ANY error pattern of the measured size — systematic (the detector's bias on a rendered
// board) or random. For camera j's intrinsics G = (JᵀJ)⁻¹Jᵀ of camera_jacobian. For R_j1 the
// estimator is sequential as OpenCV's: intrinsics from each camera's own fit, then the stereo fit
// (camera 1's poses, ω, T) with them fixed: δ_ext = pinv(J_ext)·(e_s − J_int·δ_int), whose map on
// (e_1, e_j) is L = pinv(J_ext)·(I − J_int·diag(G_1, G_j)); the rotation's bound is ‖(‖L_ω,k‖)‖·‖e‖.
struct Bounds {
  std::array<std::array<double, 8>, 4> intrinsic{};  // fx, fy, cx, cy, k1..k4
  std::array<double, 4> rotation_rad{};               // R_j1's angle, j = 2..4
  std::array<std::array<double, 8>, 4> intrinsic_pred{};  // G·e: the first-order error itself
  std::array<Vec3, 4> rotation_pred{};                    // ω = L·e
  std::array<Eigen::VectorXd, 4> error;               // each camera's measured corner errors
};

Bounds derive_bounds(const FourCameraModel& model, const Rig& rig, const std::vector<BoardPose>& boards,
                     const std::array<std::vector<std::vector<std::array<double, 2>>>, 4>& found,
                     const std::array<std::vector<std::vector<std::array<double, 2>>>, 4>& truth, int m = 8) {
  const std::vector<Vec3> object = checkerboard_object_points(rig.checkerboard);
  const auto n = static_cast<Eigen::Index>(2 * object.size());
  const auto V = static_cast<Eigen::Index>(boards.size());
  Bounds out;
  std::array<Eigen::MatrixXd, 4> G;
  for (std::size_t j = 0; j < 4; ++j) {
    std::vector<Pose> poses;
    for (const BoardPose& b : boards) poses.push_back(camera_pose(model, rig, static_cast<int>(j), b));
    G[j] = pinv(camera_jacobian(model.camera[j], poses, object, m));
    out.error[j].resize(n * V);
    for (Eigen::Index v = 0; v < V; ++v)
      for (Eigen::Index i = 0; i < n / 2; ++i)
        for (int a = 0; a < 2; ++a)
          out.error[j][v * n + 2 * i + a] = found[j][static_cast<std::size_t>(v)][static_cast<std::size_t>(i)][static_cast<std::size_t>(a)] -
                                            truth[j][static_cast<std::size_t>(v)][static_cast<std::size_t>(i)][static_cast<std::size_t>(a)];
    for (int k = 0; k < m; ++k) {
      out.intrinsic[j][static_cast<std::size_t>(k)] = G[j].row(k).norm() * out.error[j].norm();
      out.intrinsic_pred[j][static_cast<std::size_t>(k)] = G[j].row(k).dot(out.error[j]);
    }
  }
  for (std::size_t j = 1; j < 4; ++j) {
    // Stereo unknowns: camera 1's pose per view (6V), then ω (3) and T (3) of camera j.
    const Eigen::Index P = 6 * V + 6;  // columns
    Eigen::MatrixXd Jext = Eigen::MatrixXd::Zero(2 * n * V, P), Jint = Eigen::MatrixXd::Zero(2 * n * V, 2 * m);
    Eigen::VectorXd a(n), b(n);
    const CameraGeometry& c1 = model.camera[0];
    const CameraGeometry& cj = model.camera[j];
    const std::array<double, 9>& R = cj.R;
    const Vec3 T = vec3::mul(rotate(R, camera_position_mm(rig.four_camera, static_cast<int>(j))), -1.0);
    auto pose_j = [&](const Pose& p1, const std::array<double, 9>& Rj, const Vec3& Tj) {
      return Pose{mul(Rj, p1.R), vec3::add(rotate(Rj, p1.t), Tj)};
    };
    for (Eigen::Index v = 0; v < V; ++v) {
      const Pose p1 = camera_pose(model, rig, 0, boards[static_cast<std::size_t>(v)]);
      const Eigen::Index r1 = v * n, rj = n * V + v * n;
      for (int k = 0; k < 6; ++k) {
        const double h = kStepPose[k];
        corners_into(c1, perturbed(p1, k, h), object, a);
        corners_into(c1, perturbed(p1, k, -h), object, b);
        Jext.block(r1, 6 * v + k, n, 1) = (a - b) / (2 * h);
        corners_into(cj, pose_j(perturbed(p1, k, h), R, T), object, a);
        corners_into(cj, pose_j(perturbed(p1, k, -h), R, T), object, b);
        Jext.block(rj, 6 * v + k, n, 1) = (a - b) / (2 * h);
      }
      for (int k = 0; k < 6; ++k) {
        const double h = kStepPose[k];
        auto moved = [&](double s) {
          if (k < 3) {
            Vec3 w{0, 0, 0};
            w[static_cast<std::size_t>(k)] = s;
            return pose_j(p1, mul(rotation_from_vector(w), R), T);
          }
          Vec3 Tm = T;
          Tm[static_cast<std::size_t>(k - 3)] += s;
          return pose_j(p1, R, Tm);
        };
        corners_into(cj, moved(h), object, a);
        corners_into(cj, moved(-h), object, b);
        Jext.block(rj, 6 * V + k, n, 1) = (a - b) / (2 * h);
      }
      for (int k = 0; k < m; ++k) {
        const double h = kStepIntrinsic[k];
        corners_into(perturbed(c1, k, h), p1, object, a);
        corners_into(perturbed(c1, k, -h), p1, object, b);
        Jint.block(r1, k, n, 1) = (a - b) / (2 * h);
        corners_into(perturbed(cj, k, h), pose_j(p1, R, T), object, a);
        corners_into(perturbed(cj, k, -h), pose_j(p1, R, T), object, b);
        Jint.block(rj, m + k, n, 1) = (a - b) / (2 * h);
      }
    }
    Eigen::MatrixXd Gint = Eigen::MatrixXd::Zero(2 * m, 2 * n * V);
    Gint.block(0, 0, m, n * V) = G[0].topRows(m);
    Gint.block(m, n * V, m, n * V) = G[j].topRows(m);
    const Eigen::MatrixXd Pext = pinv(Jext);
    const Eigen::MatrixXd L = Pext - (Pext * Jint) * Gint;
    Eigen::VectorXd e(2 * n * V);
    e << out.error[0], out.error[j];
    double b2 = 0;
    for (int k = 0; k < 3; ++k) {
      b2 += std::pow(L.row(6 * V + k).norm() * e.norm(), 2);
      out.rotation_pred[j][static_cast<std::size_t>(k)] = L.row(6 * V + k).dot(e);
    }
    out.rotation_rad[j] = std::sqrt(b2);
  }
  return out;
}

// The rendered views' corners found, every camera; views where a camera does not find the board
// are dropped for all (the bounds' linear map then covers exactly the fitted views).
struct Detected {
  std::vector<std::array<BoardCorners, 4>> corners;
  std::vector<BoardPose> poses;
  std::array<std::vector<std::vector<std::array<double, 2>>>, 4> found, truth;
  int dropped = 0;
  double rms_px = 0, max_px = 0;
};
Detected render_and_detect(const CheckerboardRenderer& r) {
  Detected d;
  const int W = r.truth().width, H = r.truth().height;
  double sum2 = 0;
  long count = 0;
  for (int v = 0; v < static_cast<int>(r.poses().size()); ++v) {
    const auto raw = r.frames(v);
    std::array<BoardCorners, 4> c;
    bool all = true;
    for (std::size_t j = 0; j < 4; ++j) {
      c[j] = detect_board_corners(raw[j], W, H, r.board().inner_corners[0], r.board().inner_corners[1]);
      all = all && c[j].found;
    }
    if (!all) {
      ++d.dropped;
      continue;
    }
    d.corners.push_back(c);
    d.poses.push_back(r.poses()[static_cast<std::size_t>(v)]);
    for (std::size_t j = 0; j < 4; ++j) {
      const auto t = r.true_corners(v, static_cast<int>(j));
      d.found[j].push_back(c[j].uv);
      d.truth[j].push_back(t);
      for (std::size_t i = 0; i < t.size(); ++i) {
        const double e = std::hypot(c[j].uv[i][0] - t[i][0], c[j].uv[i][1] - t[i][1]);
        sum2 += e * e, ++count, d.max_px = std::max(d.max_px, e);
      }
    }
  }
  d.rms_px = std::sqrt(sum2 / static_cast<double>(std::max(1L, count)));
  return d;
}

// Fits the rendered views and checks every parameter within its derived bound.
void check_rendered(const Rig& rig, int min_views, int distortion_terms = 4) {
  const auto t0 = std::chrono::steady_clock::now();
  const CheckerboardRenderer r(rig);
  const Detected d = render_and_detect(r);
  const auto t1 = std::chrono::steady_clock::now();
  ASSERT_GE(static_cast<int>(d.corners.size()), min_views) << d.dropped << " views dropped";
  GeometryFitOptions options;
  options.distortion_terms = distortion_terms;
  const FourCameraGeometryFit fit =
      fit_four_camera_geometry(d.corners, rig.checkerboard, r.truth().width, r.truth().height, options);
  const auto t2 = std::chrono::steady_clock::now();
  ASSERT_TRUE(fit.summary.usable()) << fit.summary.brief_report();
  const Bounds b = derive_bounds(r.truth(), rig, d.poses, d.found, d.truth, 4 + distortion_terms);
  std::printf("  %zu views (%d dropped), corner error RMS %.4f px, max %.4f px; render+detect %.2f s, fit %.3f s\n",
              d.corners.size(), d.dropped, d.rms_px, d.max_px, std::chrono::duration<double>(t1 - t0).count(),
              std::chrono::duration<double>(t2 - t1).count());
  for (std::size_t j = 0; j < 4; ++j) {
    const CameraGeometry& c = fit.camera[j];
    const CameraGeometry& t = r.truth().camera[j];
    const double got[8] = {c.fx, c.fy, c.cx, c.cy, c.k[0], c.k[1], c.k[2], c.k[3]};
    const double want[8] = {t.fx, t.fy, t.cx, t.cy, t.k[0], t.k[1], t.k[2], t.k[3]};
    static constexpr const char* kName[8] = {"fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4"};
    for (std::size_t k = 0; k < 8; ++k) {
      EXPECT_NEAR(got[k], want[k], b.intrinsic[j][k]) << "camera " << j + 1 << " " << kName[k];
      // The error is the first-order one of these corner errors; what is left is second order in
      // e, a few per mille of the worst case here: 2 % of it is the allowance.
      EXPECT_NEAR(got[k] - want[k], b.intrinsic_pred[j][k], 0.02 * b.intrinsic[j][k]) << "camera " << j + 1 << " " << kName[k];
      std::printf("  camera %zu %s: error %+.3e (first order %+.3e, bound %.3e)\n", j + 1, kName[k], got[k] - want[k],
                  b.intrinsic_pred[j][k], b.intrinsic[j][k]);
    }
    if (j > 0) {
      const double angle = deg2rad(rotation_angle_between_deg(c.R, t.R));
      EXPECT_LE(angle, b.rotation_rad[j]) << "camera " << j + 1;
      const std::array<double, 9>& Rt = t.R;
      const Vec3 w = rotation_vector(mul(c.R, {Rt[0], Rt[3], Rt[6], Rt[1], Rt[4], Rt[7], Rt[2], Rt[5], Rt[8]}));
      EXPECT_LE(vec3::norm(vec3::sub(w, b.rotation_pred[j])), 0.02 * b.rotation_rad[j]) << "camera " << j + 1;
      // What the fusion uses: where camera 1's directions land in camera j (the infinite
      // homography with the lens), fitted against true, over camera 1's image.
      // The views' corners cover camera 1's image only within their bounding box (the board is
      // seen whole by all four cameras, so it never reaches the image's corners).
      double u0 = 1e9, u1 = -1e9, v0 = 1e9, v1 = -1e9;
      for (const auto& view : d.found[0])
        for (const auto& uv : view) u0 = std::min(u0, uv[0]), u1 = std::max(u1, uv[0]), v0 = std::min(v0, uv[1]), v1 = std::max(v1, uv[1]);
      double coreg = 0, covered = 0;
      for (int v = 0; v <= 40; ++v)
        for (int u = 0; u <= 40; ++u) {
          const double px = u * r.truth().width / 40.0, py = v * r.truth().height / 40.0;
          const Vec3 d1 = unproject(r.truth().camera[0], px, py);
          const auto a = project(c, rotate(c.R, d1)), tt = project(t, rotate(t.R, d1));
          if (!std::isfinite(tt[0])) continue;
          const double e = std::hypot(a[0] - tt[0], a[1] - tt[1]);
          coreg = std::max(coreg, e);
          if (px >= u0 && px <= u1 && py >= v0 && py <= v1) covered = std::max(covered, e);
        }
      std::printf("  camera %zu co-registration: largest error %.3f px within the corners' cover (%.0f-%.0f, %.0f-%.0f), "
                  "%.3f px over camera 1's whole image\n", j + 1, covered, u0, u1, v0, v1, coreg);
      std::printf("  camera %zu R_j1: error %.3e deg (%+.2e %+.2e %+.2e, first order %+.2e %+.2e %+.2e; bound %.3e deg); "
                  "RMS %.4f px, stereo %.4f px\n",
                  j + 1, rad2deg(angle), w[0], w[1], w[2], b.rotation_pred[j][0], b.rotation_pred[j][1],
                  b.rotation_pred[j][2], rad2deg(b.rotation_rad[j]), fit.summary.camera[j].rms_px,
                  fit.summary.stereo[j].rms_px);
    }
  }
}

}  // namespace

// (a) Exact corners: polrig's own project() of the true board corners, no rendering, no
// detection. OpenCV's independent fisheye model must give back polrig's fx, fy, cx, cy, k, R_j1
// and the positions to its solver's precision: this checks polrig's Kannala–Brandt convention,
// its pixel centres and R_j1's sense against OpenCV's.
TEST(FourCameraGeometry, OpenCvRecoversPolrigsCamerasFromExactCorners) {
  SKIP_WITHOUT_OPENCV();
  const Rig rig = make_rig(rig_text(1.0 / 3.0, false, 16));
  const CheckerboardRenderer r(rig);
  std::vector<std::array<BoardCorners, 4>> corners(r.poses().size());
  for (std::size_t v = 0; v < corners.size(); ++v)
    for (std::size_t j = 0; j < 4; ++j) corners[v][j] = {true, r.true_corners(static_cast<int>(v), static_cast<int>(j))};
  const FourCameraGeometryFit fit = fit_four_camera_geometry(corners, rig.checkerboard, r.truth().width, r.truth().height);
  ASSERT_TRUE(fit.summary.usable()) << fit.summary.brief_report();
  // Solver precision: the reprojection RMS of exact data is OpenCV's convergence floor (≲ 1e-6
  // px); the parameters follow within their conditioning (k's the least determined).
  for (std::size_t j = 0; j < 4; ++j) {
    const CameraGeometry& c = fit.camera[j];
    const CameraGeometry& t = r.truth().camera[j];
    EXPECT_LT(fit.summary.camera[j].rms_px, 1e-6) << j;
    EXPECT_NEAR(c.fx, t.fx, 1e-5) << j;
    EXPECT_NEAR(c.fy, t.fy, 1e-5) << j;
    EXPECT_NEAR(c.cx, t.cx, 1e-5) << j;
    EXPECT_NEAR(c.cy, t.cy, 1e-5) << j;
    for (std::size_t i = 0; i < 4; ++i) EXPECT_NEAR(c.k[i], t.k[i], 1e-6) << j << " k" << i + 1;
    EXPECT_LT(rotation_angle_between_deg(c.R, t.R), 1e-7) << j;
    const Vec3 p = camera_position_mm(rig.four_camera, static_cast<int>(j));
    EXPECT_LT(vec3::norm(vec3::sub(fit.position_mm[j], p)), 1e-5) << j;
    if (j > 0) {
      EXPECT_LT(fit.summary.stereo[j].rms_px, 1e-6) << j;
    }
    std::printf("  camera %zu: dfx %.2e dcx %.2e dk1 %.2e dR %.2e deg, position error %.2e mm\n", j + 1, c.fx - t.fx,
                c.cx - t.cx, c.k[0] - t.k[0], rotation_angle_between_deg(c.R, t.R),
                vec3::norm(vec3::sub(fit.position_mm[j], p)));
  }
  // The pixel-centre convention and R_j1's sense matter: half a pixel off, or R_j1ᵀ, is far away.
  EXPECT_GT(std::abs(fit.camera[1].cx - 0.5 - r.truth().camera[1].cx), 0.4);
  const auto& R = r.truth().camera[1].R;
  EXPECT_GT(rotation_angle_between_deg(fit.camera[1].R, {R[0], R[3], R[6], R[1], R[4], R[7], R[2], R[5], R[8]}), 0.5);
}

// (b) Rendered, noise-free views through corner detection, within the derived bounds.
TEST(FourCameraGeometry, RecoversTheCamerasFromNoiseFreeRenderedViews) {
  SKIP_WITHOUT_OPENCV();
  check_rendered(make_rig(rig_text(1.0 / 3.0, false, 16)), 12);
}

// (c) The same with the cameras' default noise (shot noise, 1 DN read noise, 12 bits).
TEST(FourCameraGeometry, RecoversTheCamerasFromNoisyRenderedViews) {
  SKIP_WITHOUT_OPENCV();
  check_rendered(make_rig(rig_text(1.0 / 3.0, true, 16)), 12);
}

// W16's full 1034 × 778 cameras with their default lens and misalignments, with noise.
TEST(SlowFourCameraGeometry, RecoversW16sFullSizeCameras) {
  SKIP_WITHOUT_OPENCV();
  const std::string text =
      "device:\n  kind: four-camera\ncheckerboard:\n  views: 12\n"
      "schedule:\n  start_deg: 0\n  step_deg: 0\n  count: 1\n";
  check_rendered(make_rig(text), 10);
  // W16's lens is the equidistant one (k = 0): fitting k1, k2 only extrapolates better beyond
  // the views' corners (docs/physics.md §16.2).
  check_rendered(make_rig(text), 10, 2);
}

// (d) Refusals. A board that cannot be placed in every camera's view is refused with the keys.
TEST(FourCameraGeometry, RefusesABoardThatCannotBeSeenWhole) {
  const Rig rig = make_rig(rig_text(1.0 / 3.0, false, 2, "  distance_mm: [80, 120]\n"));
  try {
    const CheckerboardRenderer r(rig);
    FAIL() << "expected a refusal";
  } catch (const std::invalid_argument& e) {
    EXPECT_PRED_FORMAT2(HasText, e.what(), "checkerboard.distance_mm [80, 120]");
    EXPECT_PRED_FORMAT2(HasText, e.what(), "inside all four cameras' images");
  }
  // and the rig's own checks: a square grid, near > far, white no brighter than black
  for (const auto& [keys, says] :
       {std::pair{"  inner_cols: 6\n", "checkerboard.inner_rows"}, {"  distance_mm: [900, 500]\n", "near ≤ far"},
        {"  intensity: [0.1, 0.2, 0.3]\n", "brighter than the black"}}) {
    try {
      make_rig(rig_text(1.0 / 3.0, false, 2, keys));
      ADD_FAILURE() << keys;
    } catch (const RigError& e) {
      EXPECT_PRED_FORMAT2(HasText, e.what(), says);
    }
  }
}

// A view where no corners are found is counted (not fatal); too few views is a reported failure.
TEST(FourCameraGeometry, ReportsViewsWithoutCornersAndTooFewViews) {
  SKIP_WITHOUT_OPENCV();
  const Rig rig = make_rig(rig_text(1.0 / 3.0, false, 6));
  const CheckerboardRenderer r(rig);
  const int W = r.truth().width, H = r.truth().height;
  // A frame of the wall alone (uniform) and one of pure noise: nothing found, no exception.
  std::vector<std::uint16_t> wall(static_cast<std::size_t>(W * H), 700);
  EXPECT_FALSE(detect_board_corners(wall, W, H, 9, 6).found);
  std::vector<std::uint16_t> noise(wall.size());
  for (std::size_t i = 0; i < noise.size(); ++i) noise[i] = static_cast<std::uint16_t>((i * 2654435761u) % 4096);
  EXPECT_FALSE(detect_board_corners(noise, W, H, 9, 6).found);

  std::vector<std::array<BoardCorners, 4>> corners(r.poses().size());
  for (std::size_t v = 0; v < corners.size(); ++v)
    for (std::size_t j = 0; j < 4; ++j) corners[v][j] = {true, r.true_corners(static_cast<int>(v), static_cast<int>(j))};
  corners[2][3] = {};  // camera 4 did not find view 3
  FourCameraGeometryFit fit = fit_four_camera_geometry(corners, rig.checkerboard, W, H);
  EXPECT_EQ(fit.summary.camera[3].views, 6);
  EXPECT_EQ(fit.summary.camera[3].views_detected, 5);
  EXPECT_EQ(fit.summary.stereo[3].views_used, 5);
  EXPECT_TRUE(fit.summary.usable()) << fit.summary.brief_report();

  // Three views: below the default minimum of 4, reported per camera; nothing is fitted.
  corners.resize(3);
  fit = fit_four_camera_geometry(corners, rig.checkerboard, W, H);
  EXPECT_FALSE(fit.summary.usable());
  for (std::size_t j = 0; j < 4; ++j) {
    EXPECT_EQ(fit.summary.camera[j].termination, GeometryTermination::TooFewViews) << j;
    EXPECT_TRUE(std::isnan(fit.camera[j].fx)) << j;
  }
  EXPECT_PRED_FORMAT2(HasText, fit.summary.brief_report(), "camera 1: too_few_views, 3 of 3 views detected");
  EXPECT_PRED_FORMAT2(HasText, fit.summary.camera[0].message, "expected at least 4");

  // Corners of the wrong count are a programming error.
  corners[0][0].uv.pop_back();
  EXPECT_THROW(fit_four_camera_geometry(corners, rig.checkerboard, W, H), std::invalid_argument);
}

// Without OpenCV the API exists and says how to get it.
TEST(FourCameraGeometry, SaysHowToBuildItWithoutOpenCv) {
  if (four_camera_geometry_available()) GTEST_SKIP() << "built with OpenCV";
  try {
    fit_four_camera_geometry({}, CheckerboardSpec{}, 10, 10);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_PRED_FORMAT2(HasText, e.what(), "-DPOLRIG_OPENCV=ON");
  }
}

// The dataset: `simulate`'s checkerboard files read back, the views' frames as rendered, the
// fit on the folder and geometry.csv with the truth.
TEST(FourCameraGeometry, DatasetViewsReadBackAndFitFromTheFolder) {
  TempDir tmp("polrig_geom_");
  const LoadedRig loaded = parse_rig(rig_text(1.0 / 3.0, true, 8), "test.yaml");
  write_four_camera_dataset(loaded, tmp.path() / "ds", {FourCameraLayers::All}, "test", false);
  const CheckerboardViews views = read_checkerboard_views(tmp.path() / "ds");
  ASSERT_EQ(views.files.size(), 8u);
  EXPECT_EQ(views.board.inner_corners, (std::array<int, 2>{9, 6}));
  const CheckerboardRenderer r(loaded.rig);
  for (std::size_t v = 0; v < 8; ++v) {
    ASSERT_TRUE(views.poses[v].has_value());
    EXPECT_EQ(views.poses[v]->R, r.poses()[v].R);
    EXPECT_EQ(views.poses[v]->t, r.poses()[v].t);
  }
  EXPECT_EQ(read_checkerboard_view(views, 4), r.frames(4));
  const std::string manifest = read_file(tmp.path() / "ds" / "manifest.yaml");
  EXPECT_PRED_FORMAT2(HasText, manifest, "checkerboard/poses.csv");
  if (!four_camera_geometry_available()) return;
  const FourCameraGeometryCalibration cal = calibrate_four_camera_geometry_folder(tmp.path() / "ds");
  EXPECT_TRUE(cal.fit.summary.usable()) << cal.fit.summary.brief_report();
  ASSERT_TRUE(cal.truth.has_value());
  report_four_camera_geometry(tmp.path(), cal);
  const Csv csv = read_csv(tmp.path() / "geometry.csv");
  ASSERT_EQ(csv.rows.size(), 4u);
  EXPECT_EQ(csv.header.front(), "camera");
  EXPECT_EQ(csv.header.back(), "position_error_mm");
}

// The rotation vector inverts Rodrigues' formula (rotation_from_vector, device/four_camera.h).
TEST(FourCameraGeometry, RotationVectorInvertsRodrigues) {
  for (const Vec3& r : {Vec3{0.01, -0.02, 0.005}, Vec3{1e-9, 0, 0}, Vec3{0.7, 1.1, -0.4}}) {
    const Vec3 back = rotation_vector(rotation_from_vector(r));
    for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(back[i], r[i], 1e-15 + 1e-13 * std::abs(r[i]));
  }
}

// The views are the seed's: the same poses and frames for any thread count, others for another seed.
TEST(FourCameraGeometry, ViewsAreDeterministicForAnyThreadCount) {
  const Rig rig = make_rig(rig_text(1.0 / 4.0, true, 3));
  const CheckerboardRenderer r(rig);
  std::array<std::vector<std::uint16_t>, 4> one;
  {
    const tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
    one = CheckerboardRenderer(rig).frames(2);
  }
  EXPECT_EQ(r.frames(2), one);
  EXPECT_NE(r.frames(1)[0], r.frames(2)[0]);
  Rig other = rig;
  other.seed += 1;
  EXPECT_NE(checkerboard_poses(other)[0].t, r.poses()[0].t);
  EXPECT_EQ(checkerboard_poses(rig)[0].t, r.poses()[0].t);
}
