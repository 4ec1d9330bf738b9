#include "polrig/calib/four_camera_geometry.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#ifdef POLRIG_HAVE_OPENCV
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#endif

namespace polrig {

std::string_view geometry_termination_name(GeometryTermination t) {
  switch (t) {
    case GeometryTermination::Converged: return "converged";
    case GeometryTermination::IterationLimit: return "iteration_limit";
    case GeometryTermination::TooFewViews: return "too_few_views";
    case GeometryTermination::Failed: return "failed";
  }
  return "failed";
}

bool FourCameraGeometrySummary::usable() const {
  for (int j = 0; j < kFourCameras; ++j)
    if (!camera[static_cast<std::size_t>(j)].usable() || !stereo[static_cast<std::size_t>(j)].usable()) return false;
  return true;
}

std::string FourCameraGeometrySummary::brief_report() const {
  std::string out;
  for (std::size_t j = 0; j < 4; ++j) {
    const CameraFitSummary& c = camera[j];
    out += fmt::format("camera {}: {}, {} of {} views detected, {} used, RMS {:.4f} px{}{}\n", j + 1,
                       geometry_termination_name(c.termination), c.views_detected, c.views, c.views_used, c.rms_px,
                       c.message.empty() ? "" : ": ", c.message);
  }
  for (std::size_t j = 1; j < 4; ++j) {
    const StereoFitSummary& s = stereo[j];
    out += fmt::format("cameras 1-{}: {}, {} views, RMS {:.4f} px{}{}\n", j + 1, geometry_termination_name(s.termination),
                       s.views_used, s.rms_px, s.message.empty() ? "" : ": ", s.message);
  }
  return out;
}

#ifndef POLRIG_HAVE_OPENCV

bool four_camera_geometry_available() { return false; }

BoardCorners detect_board_corners(std::span<const std::uint16_t>, int, int, int, int) {
  throw std::runtime_error(std::string(kNoOpenCvMessage));
}

FourCameraGeometryFit fit_four_camera_geometry(const std::vector<std::array<BoardCorners, kFourCameras>>&,
                                               const CheckerboardSpec&, int, int, const GeometryFitOptions&) {
  throw std::runtime_error(std::string(kNoOpenCvMessage));
}

#else

bool four_camera_geometry_available() { return true; }

BoardCorners detect_board_corners(std::span<const std::uint16_t> frame, int width, int height, int cols, int rows) {
  if (frame.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
    throw std::invalid_argument(fmt::format("a {} × {} frame holds {} pixels, not {}", width, height,
                                            width * height, frame.size()));
  BoardCorners out;
  const auto [lo, hi] = std::minmax_element(frame.begin(), frame.end());
  if (frame.empty() || *hi <= *lo) return out;
  // 8 bits between the frame's extremes: findChessboardCorners wants an 8-bit image.
  cv::Mat image(height, width, CV_8UC1);
  const double scale = 255.0 / (*hi - *lo);
  for (int r = 0; r < height; ++r) {
    auto* row = image.ptr<std::uint8_t>(r);
    for (int c = 0; c < width; ++c)
      row[c] = static_cast<std::uint8_t>(std::lround((frame[static_cast<std::size_t>(r * width + c)] - *lo) * scale));
  }
  std::vector<cv::Point2f> found;
  try {
    if (!cv::findChessboardCorners(image, cv::Size(cols, rows), found,
                                   cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE))
      return out;
    // The refinement's window must hold the corner's own edges only: a neighbour's edges that do
    // not pass through the corner bias it. They start one corner spacing d away, so the half
    // window is d/2 (at least 2 px, at most 10 px).
    double d = std::numeric_limits<double>::infinity();
    for (int k = 0; k < rows; ++k)
      for (int i = 0; i < cols; ++i) {
        const cv::Point2f& p = found[static_cast<std::size_t>(k * cols + i)];
        if (i + 1 < cols) d = std::min(d, static_cast<double>(cv::norm(found[static_cast<std::size_t>(k * cols + i + 1)] - p)));
        if (k + 1 < rows) d = std::min(d, static_cast<double>(cv::norm(found[static_cast<std::size_t>((k + 1) * cols + i)] - p)));
      }
    const int half = std::clamp(static_cast<int>(0.5 * d), 2, 10);
    // Refined on the frame itself (float): the 8-bit copy's rounding would bias the gradients.
    cv::Mat fine(height, width, CV_32FC1);
    for (int r = 0; r < height; ++r) {
      auto* row = fine.ptr<float>(r);
      for (int c = 0; c < width; ++c) row[c] = static_cast<float>(frame[static_cast<std::size_t>(r * width + c)]);
    }
    cv::cornerSubPix(fine, found, cv::Size(half, half), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 1e-4));
  } catch (const cv::Exception&) {
    return out;  // not found: the caller counts the view as not detected
  }
  if (found.size() != static_cast<std::size_t>(cols * rows)) return out;
  if (found.front().x > found.back().x) std::reverse(found.begin(), found.end());
  out.found = true;
  out.uv.reserve(found.size());
  for (const cv::Point2f& p : found) out.uv.push_back({p.x + 0.5, p.y + 0.5});  // OpenCV's centres at integers
  return out;
}

namespace {

using Points2 = std::vector<cv::Point2d>;
using Points3 = std::vector<cv::Point3d>;

Points2 to_cv(const BoardCorners& c) {
  Points2 p;
  p.reserve(c.uv.size());
  for (const auto& uv : c.uv) p.emplace_back(uv[0], uv[1]);
  return p;
}

cv::TermCriteria criteria(const GeometryFitOptions& o, int extra) {
  return {cv::TermCriteria::COUNT + cv::TermCriteria::EPS, o.max_iterations + extra, o.epsilon};
}

bool same(const cv::Mat& a, const cv::Mat& b) {
  return a.size == b.size && a.type() == b.type() && std::equal(a.datastart, a.dataend, b.datastart);
}

bool finite(const cv::Mat& m) { return cv::checkRange(m); }

// How a fit ended (OpenCV does not say): non-finite values fail it; a re-run allowed one more
// iteration that gives the same bits means it converged, else the iteration limit stopped it.
template <class Summary>
void set_ending(Summary& s, bool finite_values, bool unchanged, const GeometryFitOptions& options) {
  if (!finite_values) {
    s.termination = GeometryTermination::Failed;
    s.message = "the fit gave non-finite values";
  } else if (unchanged) {
    s.termination = GeometryTermination::Converged;
  } else {
    s.termination = GeometryTermination::IterationLimit;
    s.message = fmt::format("stopped after {} iterations (relative change still above {:g})", options.max_iterations,
                            options.epsilon);
  }
}

struct CameraRun {
  cv::Mat K, D;
  double rms = 0;
};

CameraRun run_calibrate(const std::vector<Points3>& object, const std::vector<Points2>& image, cv::Size size,
                        const GeometryFitOptions& o, int extra) {
  CameraRun r;
  r.K = cv::Mat::eye(3, 3, CV_64F);
  r.D = cv::Mat::zeros(4, 1, CV_64F);
  std::vector<cv::Mat> rvecs, tvecs;
  int flags = cv::fisheye::CALIB_RECOMPUTE_EXTRINSIC | cv::fisheye::CALIB_FIX_SKEW;
  static constexpr int kFix[4] = {cv::fisheye::CALIB_FIX_K1, cv::fisheye::CALIB_FIX_K2, cv::fisheye::CALIB_FIX_K3,
                                  cv::fisheye::CALIB_FIX_K4};
  for (int i = o.distortion_terms; i < 4; ++i) flags |= kFix[i];
  r.rms = cv::fisheye::calibrate(object, image, size, r.K, r.D, rvecs, tvecs, flags, criteria(o, extra));
  return r;
}

struct StereoRun {
  cv::Mat R;
  cv::Vec3d T;
  double rms = 0;
};

StereoRun run_stereo(const std::vector<Points3>& object, const std::vector<Points2>& image1,
                     const std::vector<Points2>& imagej, const CameraRun& c1, const CameraRun& cj, cv::Size size,
                     const GeometryFitOptions& o, int extra) {
  StereoRun r;
  cv::Mat K1 = c1.K.clone(), D1 = c1.D.clone(), Kj = cj.K.clone(), Dj = cj.D.clone();
  r.rms = cv::fisheye::stereoCalibrate(object, image1, imagej, K1, D1, Kj, Dj, size, r.R, r.T,
                                       cv::fisheye::CALIB_FIX_INTRINSIC, criteria(o, extra));
  return r;
}

}  // namespace

FourCameraGeometryFit fit_four_camera_geometry(const std::vector<std::array<BoardCorners, kFourCameras>>& corners,
                                               const CheckerboardSpec& board, int width, int height,
                                               const GeometryFitOptions& options) {
  if (options.distortion_terms < 0 || options.distortion_terms > 4)
    throw std::invalid_argument(fmt::format("distortion_terms = {} (expected 0 … 4)", options.distortion_terms));
  const std::size_t n_corners = static_cast<std::size_t>(board.inner_corners[0] * board.inner_corners[1]);
  for (std::size_t v = 0; v < corners.size(); ++v)
    for (std::size_t j = 0; j < 4; ++j)
      if (corners[v][j].found && corners[v][j].uv.size() != n_corners)
        throw std::invalid_argument(fmt::format("view {}, camera {}: {} corners (the board has {} × {} = {})", v + 1,
                                                j + 1, corners[v][j].uv.size(), board.inner_corners[0],
                                                board.inner_corners[1], n_corners));
  Points3 object;
  for (const Vec3& X : checkerboard_object_points(board)) object.emplace_back(X[0], X[1], X[2]);
  const cv::Size size(width, height);

  FourCameraGeometryFit fit;
  // NaN until a fit gives a value: a camera that could not be fitted shows none.
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t j = 0; j < 4; ++j) {
    fit.camera[j] = {nan, nan, nan, nan, {nan, nan, nan, nan}, {1, 0, 0, 0, 1, 0, 0, 0, 1}};
    if (j > 0) fit.camera[j].R.fill(nan), fit.position_mm[j] = {nan, nan, nan};
  }
  std::array<CameraRun, kFourCameras> runs;
  for (std::size_t j = 0; j < 4; ++j) {
    CameraFitSummary& s = fit.summary.camera[j];
    s.views = static_cast<int>(corners.size());
    std::vector<Points3> obj;
    std::vector<Points2> img;
    for (const auto& view : corners)
      if (view[j].found) obj.push_back(object), img.push_back(to_cv(view[j]));
    s.views_detected = static_cast<int>(img.size());
    if (s.views_detected < options.min_views) {
      s.termination = GeometryTermination::TooFewViews;
      s.message = fmt::format("{} views with the board found (expected at least {})", s.views_detected, options.min_views);
      continue;
    }
    try {
      runs[j] = run_calibrate(obj, img, size, options, 0);
      const CameraRun again = run_calibrate(obj, img, size, options, 1);
      s.views_used = s.views_detected;
      s.rms_px = runs[j].rms;
      set_ending(s, finite(runs[j].K) && finite(runs[j].D) && std::isfinite(runs[j].rms),
                 same(runs[j].K, again.K) && same(runs[j].D, again.D), options);
    } catch (const cv::Exception& e) {
      s.termination = GeometryTermination::Failed;
      s.message = fmt::format("OpenCV: {}", e.what());
      continue;
    }
    for (int i = 0; i < 4 && s.usable(); ++i)
      if (std::abs(runs[j].D.at<double>(i)) > kMaxKannalaBrandtK) {
        s.termination = GeometryTermination::Failed;
        s.message = fmt::format("k{} = {:.4g} is no lens (|k| ≤ {}): too few views, or views too alike", i + 1,
                                runs[j].D.at<double>(i), kMaxKannalaBrandtK);
      }
    CameraGeometry& c = fit.camera[j];
    const cv::Mat& K = runs[j].K;
    c.fx = K.at<double>(0, 0), c.fy = K.at<double>(1, 1), c.cx = K.at<double>(0, 2), c.cy = K.at<double>(1, 2);
    for (int i = 0; i < 4; ++i) c.k[static_cast<std::size_t>(i)] = runs[j].D.at<double>(i);
  }

  StereoFitSummary& self = fit.summary.stereo[0];
  self.termination = GeometryTermination::Converged, self.rms_px = 0;
  self.views_used = fit.summary.camera[0].views_detected;
  for (std::size_t j = 1; j < 4; ++j) {
    StereoFitSummary& s = fit.summary.stereo[j];
    if (!fit.summary.camera[0].usable() || !fit.summary.camera[j].usable()) {
      s.termination = GeometryTermination::Failed;
      s.message = fmt::format("camera {}'s intrinsics are not usable", fit.summary.camera[0].usable() ? j + 1 : 1);
      continue;
    }
    std::vector<Points3> obj;
    std::vector<Points2> img1, imgj;
    for (const auto& view : corners)
      if (view[0].found && view[j].found) obj.push_back(object), img1.push_back(to_cv(view[0])), imgj.push_back(to_cv(view[j]));
    s.views_used = static_cast<int>(obj.size());
    if (s.views_used < options.min_views) {
      s.termination = GeometryTermination::TooFewViews;
      s.message = fmt::format("{} views with the board found by both cameras (expected at least {})", s.views_used,
                              options.min_views);
      continue;
    }
    StereoRun run;
    try {
      run = run_stereo(obj, img1, imgj, runs[0], runs[j], size, options, 0);
      const StereoRun again = run_stereo(obj, img1, imgj, runs[0], runs[j], size, options, 1);
      s.rms_px = run.rms;
      set_ending(s, finite(run.R) && std::isfinite(run.T[0] + run.T[1] + run.T[2]) && std::isfinite(run.rms),
                 same(run.R, again.R) && run.T == again.T, options);
      if (s.termination == GeometryTermination::Failed) continue;
    } catch (const cv::Exception& e) {
      s.termination = GeometryTermination::Failed;
      s.message = fmt::format("OpenCV: {}", e.what());
      continue;
    }
    CameraGeometry& c = fit.camera[j];
    cv::Mat R;
    run.R.convertTo(R, CV_64F);
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) c.R[static_cast<std::size_t>(r * 3 + k)] = R.at<double>(r, k);
    // X_j = R·X_1 + T: camera j's centre (X_j = 0) is −Rᵀ·T in camera 1's frame.
    for (std::size_t r = 0; r < 3; ++r)
      fit.position_mm[j][r] = -(c.R[r] * run.T[0] + c.R[3 + r] * run.T[1] + c.R[6 + r] * run.T[2]);
  }
  return fit;
}

#endif

}  // namespace polrig
