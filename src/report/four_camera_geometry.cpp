#include "polrig/report/four_camera_geometry.h"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "polrig/io/csv.h"
#include "polrig/io/exr.h"
#include "polrig/units.h"

namespace polrig {

Vec3 rotation_vector(const std::array<double, 9>& R) {
  // w = (R₂₁ − R₁₂, R₀₂ − R₂₀, R₁₀ − R₀₁)/2 = sin θ·a, trace = 1 + 2 cos θ.
  const Vec3 w = {0.5 * (R[7] - R[5]), 0.5 * (R[2] - R[6]), 0.5 * (R[3] - R[1])};
  const double s = vec3::norm(w), c = 0.5 * (R[0] + R[4] + R[8] - 1.0);
  if (s == 0.0) return {0, 0, 0};
  return vec3::mul(w, std::atan2(s, c) / s);
}

double rotation_angle_between_deg(const std::array<double, 9>& A, const std::array<double, 9>& B) {
  std::array<double, 9> M{};
  for (std::size_t r = 0; r < 3; ++r)
    for (std::size_t c = 0; c < 3; ++c)
      for (std::size_t k = 0; k < 3; ++k) M[r * 3 + c] += A[r * 3 + k] * B[c * 3 + k];
  return rad2deg(vec3::norm(rotation_vector(M)));
}

std::vector<DatasetFile> report_checkerboard_views(const std::filesystem::path& dir, const CheckerboardRenderer& renderer,
                                                   const Progress& progress) {
  const CheckerboardSpec& b = renderer.board();
  const int W = renderer.truth().width, H = renderer.truth().height;
  std::filesystem::create_directory(dir / "checkerboard");
  write_text_file(dir / "checkerboard" / "board.yaml",
                  fmt::format("# The checkerboard target (docs/formats.md \"Four-camera dataset\"): inner corners along a\n"
                              "# row (cols) and a column (rows), the squares' side and the white margin, mm; each view's\n"
                              "# frames are width_px x height_px.\n"
                              "views: {}\ninner_cols: {}\ninner_rows: {}\nsquare_mm: {}\nmargin_mm: {}\nwidth_px: {}\n"
                              "height_px: {}\n",
                              b.views, b.inner_corners[0], b.inner_corners[1], b.square_mm, b.margin_mm, W, H));
  std::string csv = "view,file,R_00,R_01,R_02,R_10,R_11,R_12,R_20,R_21,R_22,t_x_mm,t_y_mm,t_z_mm\n";
  progress.begin("simulate: checkerboard views", b.views);
  for (int v = 0; v < b.views; ++v) {
    const std::string file = fmt::format("checkerboard/view_{:04}.exr", v + 1);
    const auto raw = renderer.frames(v);
    ExrImage image;
    image.width = W, image.height = H;
    for (std::size_t j = 0; j < 4; ++j)
      image.uints.push_back({fmt::format("cam{}", j + 1), std::vector<std::uint32_t>(raw[j].begin(), raw[j].end())});
    image.attributes.doubles = {{"view", v + 1}};
    write_exr_image(dir / file, image);
    const BoardPose& p = renderer.poses()[static_cast<std::size_t>(v)];
    csv += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", v + 1, file, p.R[0], p.R[1], p.R[2], p.R[3], p.R[4],
                       p.R[5], p.R[6], p.R[7], p.R[8], p.t[0], p.t[1], p.t[2]);
    progress.advance();
  }
  progress.finish();
  write_text_file(dir / "checkerboard" / "poses.csv", csv);
  return {{"checkerboard", 1,
           "checkerboard/board.yaml (the target: inner_cols, inner_rows, square_mm, margin_mm, frame size), "
           "checkerboard/poses.csv (per view: file, the board's true pose R (row-major) and t in camera 1's frame, mm), "
           "checkerboard/view_NNNN.exr (raw DN of cameras 1-4 as UINT channels cam1..cam4)"}};
}

FourCameraGeometryCalibration calibrate_four_camera_geometry_folder(const std::filesystem::path& dir,
                                                                    const GeometryFitOptions& options,
                                                                    const Progress& progress) {
  if (!four_camera_geometry_available()) throw std::runtime_error(std::string(kNoOpenCvMessage));
  FourCameraGeometryCalibration out;
  out.views = read_checkerboard_views(dir);
  if (out.views.files.empty())
    throw std::runtime_error(fmt::format("{}: no checkerboard views (simulate the dataset with checkerboard.views > 0)",
                                         dir.string()));
  out.truth = read_four_camera_geometry_truth(dir);
  const CheckerboardSpec& b = out.views.board;
  progress.begin("calibrate: checkerboard views", static_cast<long long>(out.views.files.size()));
  for (std::size_t v = 0; v < out.views.files.size(); ++v) {
    const auto raw = read_checkerboard_view(out.views, v);
    std::array<BoardCorners, kFourCameras> found;
    tbb::parallel_for(0, kFourCameras, [&](int j) {
      const auto J = static_cast<std::size_t>(j);
      found[J] = detect_board_corners(raw[J], out.views.width, out.views.height, b.inner_corners[0], b.inner_corners[1]);
    });
    out.corners.push_back(std::move(found));
    progress.advance();
  }
  progress.finish();
  out.fit = fit_four_camera_geometry(out.corners, b, out.views.width, out.views.height, options);
  return out;
}

std::vector<DatasetFile> report_four_camera_geometry(const std::filesystem::path& out,
                                                     const FourCameraGeometryCalibration& calibration) {
  const FourCameraGeometryFit& fit = calibration.fit;
  const bool truth = calibration.truth.has_value();
  std::string csv =
      "camera,fx_px,fy_px,cx_px,cy_px,k1,k2,k3,k4,rot_x_deg,rot_y_deg,rot_z_deg,position_x_mm,position_y_mm,"
      "position_z_mm,views,views_detected,rms_px,termination,stereo_views,stereo_rms_px,stereo_termination,message";
  if (truth)
    csv += ",fx_true_px,fy_true_px,cx_true_px,cy_true_px,k1_true,k2_true,k3_true,k4_true,rot_x_true_deg,"
           "rot_y_true_deg,rot_z_true_deg,rotation_error_deg,position_error_mm";
  csv += "\n";
  for (std::size_t j = 0; j < 4; ++j) {
    const CameraGeometry& c = fit.camera[j];
    const Vec3 r = vec3::mul(rotation_vector(c.R), rad2deg(1.0));
    const Vec3& p = fit.position_mm[j];
    const CameraFitSummary& s = fit.summary.camera[j];
    const StereoFitSummary& st = fit.summary.stereo[j];
    std::string message = s.message.empty() ? st.message : s.message;
    for (char& ch : message)
      if (ch == ',' || ch == '\n' || ch == '"') ch = ' ';
    csv += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}", j + 1, c.fx, c.fy, c.cx,
                       c.cy, c.k[0], c.k[1], c.k[2], c.k[3], r[0], r[1], r[2], p[0], p[1], p[2], s.views, s.views_detected,
                       s.rms_px, geometry_termination_name(s.termination), st.views_used, st.rms_px,
                       geometry_termination_name(st.termination), message);
    if (truth) {
      const CameraGeometry& t = calibration.truth->camera[j];
      const Vec3 rt = vec3::mul(rotation_vector(t.R), rad2deg(1.0));
      csv += fmt::format(",{},{},{},{},{},{},{},{},{},{},{},{},{}", t.fx, t.fy, t.cx, t.cy, t.k[0], t.k[1], t.k[2], t.k[3],
                         rt[0], rt[1], rt[2], rotation_angle_between_deg(c.R, t.R),
                         vec3::norm(vec3::sub(p, calibration.truth->position_mm[j])));
    }
    csv += "\n";
  }
  write_text_file(out / "geometry.csv", csv);
  return {{"geometry.csv", 1,
           "one row per camera: the fitted fx, fy, cx, cy (px, pixel centres at +0.5), Kannala-Brandt k1..k4, R_j1's "
           "rotation vector (deg), camera j's centre in camera 1's frame (mm), views, views detected, RMS reprojection "
           "error (px), termination, the stereo fit's views, RMS and termination (camera 1 with camera j), a message; "
           "with the dataset's truth also the true values, the rotation error (deg) and the position error (mm)"}};
}

}  // namespace polrig
