// polrig.calibrate_four_camera: W16's radiometric and polarizer-angle calibration of a four-camera
// dataset (report/four_camera_calibration_report.h), the computation of `polrig calibrate DIR
// --method four-camera`.
#include <array>
#include <optional>
#include <string>

#include <fmt/format.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.h"
#include "convert.h"
#include "polrig/report/four_camera_calibration_report.h"

namespace polrig::python {

namespace {

py::array_t<double> per_camera(const std::array<double, 4>& v) { return take(std::vector<double>(v.begin(), v.end())); }

py::dict run_dict(const FourCameraCalibrationRun& run) {
  const FourCameraCalibration& c = run.calibration;
  py::dict d;
  std::array<double, 4> K{}, K_se{}, b{}, b_se{}, rms{};
  py::list radiometric;
  for (std::size_t j = 0; j < 4; ++j) {
    const CameraRadiometry& r = c.radiometry.camera[j];
    K[j] = r.K, K_se[j] = r.K_se, b[j] = r.b, b_se[j] = r.b_se, rms[j] = r.residual_rms_DN;
    py::dict f;
    f["rank"] = r.rank;
    f["levels_used"] = r.levels_used;
    f["residual_rms_DN"] = r.residual_rms_DN;
    f["usable"] = r.usable();
    f["message"] = r.message;
    std::vector<double> level, mean, sd;
    for (const RadiometricLevel& l : r.levels) level.push_back(l.level), mean.push_back(l.mean_DN), sd.push_back(l.sd_DN);
    f["level"] = take(std::move(level));
    f["mean_DN"] = take(std::move(mean));
    f["sd_DN"] = take(std::move(sd));
    radiometric.append(f);
  }
  d["K"] = per_camera(K);
  d["K_se"] = per_camera(K_se);
  d["b"] = per_camera(b);
  d["b_se"] = per_camera(b_se);
  const PolarizerFit& p = c.polarizer;
  d["eps_deg"] = per_camera(p.eps_deg);
  d["eps_se_deg"] = per_camera(p.eps_se_deg);
  d["axis_deg"] = per_camera(c.model.axis_deg);
  d["psi0_deg"] = p.psi0_deg;
  d["dop"] = p.dop;
  py::dict fit;
  fit["termination"] = std::string(termination_name(p.summary.termination));
  fit["message"] = p.summary.message;
  fit["iterations"] = p.summary.iterations;
  fit["rank"] = p.rank;
  fit["unknowns"] = p.unknowns;
  fit["observations"] = p.summary.observations;
  fit["residual_rms_deg"] = p.residual_rms_deg;
  fit["residual_rms_before_deg"] = p.residual_rms_before_deg;
  fit["usable"] = p.usable();
  d["polarizer"] = fit;
  d["radiometric"] = radiometric;
  std::vector<double> theta, before, after, rb, ra;
  for (const PolarizerStopRow& s : p.stops)
    theta.push_back(s.theta_R_deg), before.push_back(s.aop_before_deg), after.push_back(s.aop_after_deg),
        rb.push_back(s.residual_before_deg), ra.push_back(s.residual_after_deg);
  d["theta_R_deg"] = take(std::move(theta));
  d["aop_before_deg"] = take(std::move(before));
  d["aop_after_deg"] = take(std::move(after));
  d["residual_before_deg"] = take(std::move(rb));
  d["residual_after_deg"] = take(std::move(ra));
  d["geometry_from"] = run.file.geometry_from;
  d["geometry"] = run.geometry ? py::object(geometry_calibration_dict(*run.geometry)) : py::object(py::none());
  d["calibration_yaml"] = four_camera_calibration_yaml(run.file);
  return d;
}

}  // namespace

void bind_four_camera_calibration(py::module_& m) {
  m.def(
      "calibrate_four_camera",
      [](const std::filesystem::path& dir, const std::optional<std::filesystem::path>& geometry,
         int distortion_terms, std::optional<int> threads, const py::object& progress) {
        if (distortion_terms < 0 || distortion_terms > 4)
          throw py::value_error(fmt::format("distortion_terms={} (expected 0 … 4)", distortion_terms));
        if (geometry && distortion_terms != GeometryFitOptions{}.distortion_terms)
          throw py::value_error(fmt::format("distortion_terms={}: the geometric calibration's option, but geometry={} "
                                            "gives the geometry",
                                            distortion_terms, geometry->string()));
        const Progress p = progress_from(progress);
        ThreadLimit limit(threads);
        GeometryFitOptions geometry_options;
        geometry_options.distortion_terms = distortion_terms;
        FourCameraCalibrationRun run;
        {
          py::gil_scoped_release release;
          run = calibrate_four_camera_folder(dir, geometry, {}, p, geometry_options);
        }
        return run_dict(run);
      },
      py::arg("dir"), py::arg("geometry") = py::none(), py::kw_only(),
      py::arg("distortion_terms") = GeometryFitOptions{}.distortion_terms, py::arg("threads") = py::none(),
      py::arg("progress") = py::none(),
      (std::string("`polrig calibrate DIR --method four-camera [--geometry FILE]`'s computation (report/"
                   "four_camera_calibration_report.h): W16's radiometric calibration (K_j, b_j per camera from the "
                   "unpolarized stops) and polarizer-angle calibration (ε_j, gauge ε_1 = 0, from the polarized stops "
                   "turned by the table) of a four-camera dataset with raw frames (--layers all). geometry: a "
                   "calibration.yaml or truth.yaml giving each camera's geometry (None: the geometric calibration of "
                   "DIR's checkerboard views with OpenCV, fitting k1 … k_distortion_terms, whose result is the dict's "
                   "'geometry' (as fit_four_camera_geometry's; None when the geometry came from a file); a "
                   "dataset without views: DIR/truth.yaml). Returns a "
                   "dict: K, K_se, b, b_se, eps_deg, eps_se_deg, axis_deg (arrays of 4), psi0_deg, dop, polarizer "
                   "(the fit's summary), radiometric (per camera: rank, levels_used, residual_rms_DN, usable, "
                   "message, level, mean_DN, sd_DN), polarizer.csv's columns (theta_R_deg, aop_before_deg, "
                   "aop_after_deg, residual_before_deg, residual_after_deg), geometry_from and calibration_yaml (the "
                   "text of the CLI's calibration.yaml). Raises RigError for a rig that is not a camera array, "
                   "DataError for a file that cannot be read or a dataset without raw frames, CalibrationError for a "
                   "fit that cannot be used.\n") +
       kThreadsDoc + "\n" + kProgressDoc)
          .c_str());
}

}  // namespace polrig::python
