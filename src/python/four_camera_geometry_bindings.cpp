// The four cameras' geometric calibration from Python (docs/python.md §10):
// polrig.fit_four_camera_geometry on a dataset folder with checkerboard views. Thin: it runs the
// library's folder fit (report/four_camera_geometry.h) with the GIL released and converts.
#include <optional>
#include <string>

#include <fmt/format.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.h"
#include "convert.h"
#include "polrig/io/output_dir.h"
#include "polrig/report/four_camera_geometry.h"
#include "polrig/units.h"

namespace polrig::python {
namespace {

constexpr const char* kFitDoc = R"doc(
The four cameras' geometric calibration (docs/physics.md §16.2) from a four-camera dataset whose
rig had checkerboard.views > 0 (DIR/checkerboard/): each camera's corners found (OpenCV's
findChessboardCorners + cornerSubPix), cv::fisheye::calibrate per camera (fx, fy, cx, cy in px with
polrig's pixel centres at +0.5, Kannala–Brandt k1..k4), cv::fisheye::stereoCalibrate of camera 1
with camera j (R_j1 and camera j's centre in camera 1's frame). Needs polrig built with
-DPOLRIG_OPENCV=ON (RuntimeError otherwise).

Returns a dict: cameras (a list of four dicts: fx_px, fy_px, cx_px, cy_px, k (4,), R_j1 (3, 3),
rotation_deg (R_j1's rotation vector, (3,)), position_mm (3,), views, views_detected, rms_px,
termination ('converged', 'iteration_limit', 'too_few_views' or 'failed'), stereo_views,
stereo_rms_px, stereo_termination, message), usable (every fit converged), report (one line per
fit), and truth (the dataset's truth.yaml geometry in the same form, or None). NaN where a fit gave
nothing.

  dir: the dataset folder.
  out: a new folder for geometry.csv (`polrig calibrate --method four-camera`'s file), whole or
    not at all; none: nothing is written.
  force: replace an existing `out`.
  min_views: views a camera (or a pair) must find at least (≥ 1).
  distortion_terms: the Kannala–Brandt terms k1 … kN fitted (0–4; the rest held at 0: fewer
    extrapolate better beyond the boards' corners).
  {threads}
  {progress}
)doc";

py::dict camera_dict(const CameraGeometry& c, const Vec3& p) {
  py::dict d;
  d["fx_px"] = c.fx, d["fy_px"] = c.fy, d["cx_px"] = c.cx, d["cy_px"] = c.cy;
  d["k"] = take(std::vector<double>(c.k.begin(), c.k.end()));
  d["R_j1"] = take(std::vector<double>(c.R.begin(), c.R.end()), {3, 3});
  const Vec3 r = rotation_vector(c.R);
  d["rotation_deg"] = take(std::vector<double>{rad2deg(r[0]), rad2deg(r[1]), rad2deg(r[2])});
  d["position_mm"] = take(std::vector<double>(p.begin(), p.end()));
  return d;
}

}  // namespace

py::dict geometry_calibration_dict(const FourCameraGeometryCalibration& cal) {
  py::list cameras;
  for (std::size_t j = 0; j < 4; ++j) {
    py::dict d = camera_dict(cal.fit.camera[j], cal.fit.position_mm[j]);
    const CameraFitSummary& s = cal.fit.summary.camera[j];
    const StereoFitSummary& st = cal.fit.summary.stereo[j];
    d["views"] = s.views, d["views_detected"] = s.views_detected, d["rms_px"] = s.rms_px;
    d["termination"] = std::string(geometry_termination_name(s.termination));
    d["stereo_views"] = st.views_used, d["stereo_rms_px"] = st.rms_px;
    d["stereo_termination"] = std::string(geometry_termination_name(st.termination));
    d["message"] = s.message.empty() ? st.message : s.message;
    cameras.append(d);
  }
  py::dict result;
  result["cameras"] = cameras;
  result["usable"] = cal.fit.summary.usable();
  result["report"] = cal.fit.summary.brief_report();
  if (cal.truth) {
    py::list truth;
    for (std::size_t j = 0; j < 4; ++j) truth.append(camera_dict(cal.truth->camera[j], cal.truth->position_mm[j]));
    result["truth"] = truth;
  } else {
    result["truth"] = py::none();
  }
  return result;
}

void bind_four_camera_geometry(py::module_& m) {
  m.def("fit_four_camera_geometry", [](const std::filesystem::path& dir, const std::optional<std::filesystem::path>& out,
                                       bool force, int min_views, int distortion_terms, std::optional<int> threads,
                                       const py::object& progress) {
    if (min_views < 1) throw py::value_error(fmt::format("min_views={} (expected ≥ 1)", min_views));
    if (distortion_terms < 0 || distortion_terms > 4)
      throw py::value_error(fmt::format("distortion_terms={} (expected 0 … 4)", distortion_terms));
    GeometryFitOptions o;
    o.min_views = min_views;
    o.distortion_terms = distortion_terms;
    const ThreadLimit limit(threads);
    const Progress p = progress_from(progress);
    FourCameraGeometryCalibration cal;
    {
      py::gil_scoped_release release;
      try {
        // The folder first: an existing one is refused before the fit runs.
        std::optional<OutputDir> folder;
        if (out) folder.emplace(*out, force);
        cal = calibrate_four_camera_geometry_folder(dir, o, p);
        if (folder) {
          report_four_camera_geometry(folder->staging(), cal);
          folder->commit();
        }
      } catch (const std::runtime_error& e) {
        py::gil_scoped_acquire acquire;
        if (!four_camera_geometry_available()) throw;
        throw py::value_error(e.what());
      }
    }
    return geometry_calibration_dict(cal);
  }, with_shared(kFitDoc).c_str(), py::arg("dir"), py::kw_only(), py::arg("out") = py::none(), py::arg("force") = false,
     py::arg("min_views") = 4, py::arg("distortion_terms") = GeometryFitOptions{}.distortion_terms,
     py::arg("threads") = py::none(), py::arg("progress") = py::none());
}

}  // namespace polrig::python
