// polrig.sun_vector, polrig.orient and polrig.camera_heading: orientation from a DoFP camera's sky
// image (compass/orientation.h, H17 Eqs. 6–14, spec sky-and-compasses.md §2.5) on NumPy AoP (and DoP)
// images. Frames and senses are compass/orientation.h's.
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.h"
#include "convert.h"
#include "polrig/compass/orientation.h"
#include "polrig/report/orientation_report.h"
#include "sky_args.h"

namespace polrig::python {
using namespace pybind11::literals;

namespace {

constexpr const char* kFrames =
    "Frames (compass/orientation.h): camera frame l right-handed, Z_l along the optical axis (the "
    "zenith for a level camera), X_l = image +x (columns), Y_l = image +y (rows grow); every "
    "image angle (the AoP, the sun's azimuth α_S) runs from X_l towards Y_l (anticlockwise seen "
    "from above for a level camera looking up). Pixel (col, row)'s centre is at (col + 0.5, "
    "row + 0.5); element (c, r) of the image given is centred at ((c + ½)·element_px, "
    "(r + ½)·element_px). The heading is the geographic azimuth of X_l, clockwise from north: "
    "H = A_s + α_S.";

struct Image {
  SkyPoints points;
  CameraIntrinsics camera;
};

// A 2-D AoP image (and optional DoP image of the same shape) as points, with the intrinsics.
Image image_points(const py::object& aop_deg, const py::object& dop, double f_c_px,
                   const std::optional<std::pair<double, double>>& principal_point,
                   double element_px) {
  const DoubleArray a = as_array(aop_deg, "aop_deg", 2);
  const auto rows = static_cast<int>(a.shape(0)), cols = static_cast<int>(a.shape(1));
  std::vector<double> aop(a.data(), a.data() + a.size());
  std::vector<double> d;
  if (!dop.is_none()) {
    const DoubleArray b = as_array(dop, "dop", 2);
    if (b.shape(0) != a.shape(0) || b.shape(1) != a.shape(1))
      throw py::value_error(fmt::format("dop: expected the shape of aop_deg ({}, {}), got ({}, {})",
                                        rows, cols, b.shape(0), b.shape(1)));
    d.assign(b.data(), b.data() + b.size());
  }
  check_option(element_px, "element_px", 1e-9, 1e9, "px");
  Image im;
  im.points = grid_points(cols, rows, element_px, std::move(aop), std::move(d));
  im.camera.f_c_px = f_c_px;
  if (principal_point) {
    im.camera.x_c_px = principal_point->first;
    im.camera.y_c_px = principal_point->second;
  } else {
    im.camera.x_c_px = 0.5 * cols * element_px;
    im.camera.y_c_px = 0.5 * rows * element_px;
  }
  check_intrinsics(im.camera);
  return im;
}

OrientationSettings settings_from(const std::string& conversion, bool dop_weighting, double min_dop,
                                  const std::optional<std::vector<double>>& prior_sun,
                                  double horizon_margin_deg, bool correct_noise_bias = false) {
  OrientationSettings s;
  const auto c = parse_aop_conversion(conversion);
  if (!c)
    throw py::value_error(fmt::format(
        "conversion: expected 'meridional' or 'analyzer-in-front', got '{}'", conversion));
  s.conversion = *c;
  s.dop_weighting = dop_weighting;
  s.correct_noise_bias = correct_noise_bias;
  s.min_dop = min_dop;
  if (prior_sun) {
    if (prior_sun->size() != 3)
      throw py::value_error(fmt::format("prior_sun: expected 3 numbers, got {}", prior_sun->size()));
    s.prior_sun = Vec3{(*prior_sun)[0], (*prior_sun)[1], (*prior_sun)[2]};
  }
  s.horizon_margin_deg = horizon_margin_deg;
  check_orientation_settings(s);  // std::invalid_argument → ValueError, naming the setting
  return s;
}

constexpr const char* kCameraArgs =
    "aop_deg: 2-D array (rows, cols), each element's AoP φ_pix in degrees in the image frame "
    "(NaN: left out); dop: None or the DoP image of the same shape; f_c_px: the focal length in "
    "pixels (H17: 3 mm / 7.4 µm); principal_point: (x_c, y_c) in pixels, default the image's "
    "centre (cols·element_px/2, rows·element_px/2); element_px: the element's size in pixels (2: "
    "the 2 × 2 mosaic's unit cells, 1: pixels); conversion: 'meridional' (φ = φ_pix − α, the "
    "default) or 'analyzer-in-front'; dop_weighting: weight EEᵀ by the DoP; min_dop: leave out "
    "elements below this DoP; prior_sun: None or a direction in frame l choosing between the sun "
    "and the antisun (else the root with s_z > 0); horizon_margin_deg: without a prior, a sun this "
    "close to the camera's horizon has status 'near-horizon'; correct_noise_bias: remove the noise "
    "bias of EEᵀ (DoP² weights and the generalized eigenproblem EEᵀ·s = c·Σ(I − v·vᵀ)·s, "
    "docs/physics.md §15; needs dop; replaces dop_weighting).";

}  // namespace

void bind_orientation(py::module_& m) {
  py::class_<SunVectorSolution>(m, "SunVector",
                                "The eigenvector method's sun (compass/orientation.h, H17 Eqs. 10–13).")
      .def_property_readonly("status", [](const SunVectorSolution& s) {
             return std::string(sun_vector_status_name(s.status));
           }, "'ok', 'near-horizon', 'too-few-vectors' or 'degenerate'.")
      .def_property_readonly("root", [](const SunVectorSolution& s) {
             return std::string(sun_root_name(s.root));
           }, "Which of ±s was taken: 'above-horizon' (s_z > 0), 'prior' or 'none'.")
      .def_property_readonly("sun", [](const SunVectorSolution& s) {
             return take(std::vector<double>(s.sun.begin(), s.sun.end()));
           }, "s*, the unit vector to the sun in frame l, shape (3,); zeros without a solution.")
      .def_readonly("sun_az_deg", &SunVectorSolution::sun_az_deg,
                    "α_S* = atan2(s_2, s_1), degrees from X_l towards Y_l, [0, 360).")
      .def_readonly("sun_el_deg", &SunVectorSolution::sun_el_deg,
                    "asin(s_3): the sun's elevation above the camera's X–Y plane, degrees.")
      .def_property_readonly("eigenvalues", [](const SunVectorSolution& s) {
             return take(std::vector<double>(s.eigenvalues.begin(), s.eigenvalues.end()));
           }, "EEᵀ's eigenvalues, rising, shape (3,).")
      .def_readonly("relative_gap", &SunVectorSolution::relative_gap, "(λ₂ − λ₁)/(λ₁ + λ₂ + λ₃).")
      .def_readonly("rms_residual", &SunVectorSolution::rms_residual,
                    "√(λ₁/Σw): the RMS of e·s* (its rounding floor is about 1e-8).")
      .def_readonly("vectors_used", &SunVectorSolution::vectors_used, "The number of E-vectors in EEᵀ.")
      .def_readonly("stokes_noise_sd", &SunVectorSolution::stokes_noise_sd,
                    "With correct_noise_bias: the normalised Stokes noise σ = 2√c the fit implies "
                    "(c its smallest generalized eigenvalue); else 0.")
      .def("__repr__", [](const SunVectorSolution& s) {
        return fmt::format("<polrig.SunVector: status '{}', root '{}', sun_az_deg {}, sun_el_deg {}, "
                           "vectors_used {}, relative_gap {}>",
                           sun_vector_status_name(s.status), sun_root_name(s.root), s.sun_az_deg,
                           s.sun_el_deg, s.vectors_used, s.relative_gap);
      });

  py::class_<OrientationEstimate>(m, "OrientationEstimate",
                                  "One method's result for one frame (orientation.csv's row).")
      .def_property_readonly("method", [](const OrientationEstimate& e) {
             return std::string(orientation_method_name(e.method));
           }, "'eigenvector', 'single-point' or 'line-detection'.")
      .def_property_readonly("status", [](const OrientationEstimate& e) { return std::string(e.status); },
                             "The method's status: the eigenvector's ('ok', 'near-horizon', "
                             "'too-few-vectors', 'degenerate') or a comparator's ('ok', "
                             "'ambiguous-180', 'no-points').")
      .def_readonly("solved", &OrientationEstimate::solved,
                    "True when a sun azimuth was found and its half of the meridian chosen.")
      .def_property_readonly("sun_az_deg", [](const OrientationEstimate& e) -> std::optional<double> {
             if (!e.solved) return std::nullopt;
             return e.sun_az_deg;
           }, "α_S in frame l, degrees, [0, 360); None when not solved.")
      .def_readonly("sun_el_deg", &OrientationEstimate::sun_el_deg,
                    "The sun's elevation in frame l (the eigenvector method only), else None.")
      .def_readonly("heading_deg", &OrientationEstimate::heading_deg,
                    "H = A_s + α_S, degrees clockwise from north, [0, 360); None when not solved or "
                    "without sun_azimuth_deg.")
      .def("__repr__", [](const OrientationEstimate& e) {
        return fmt::format("<polrig.OrientationEstimate: method '{}', status '{}', sun_az_deg {}, "
                           "heading_deg {}>",
                           orientation_method_name(e.method), e.status,
                           e.solved ? fmt::format("{}", e.sun_az_deg) : "None",
                           e.heading_deg ? fmt::format("{}", *e.heading_deg) : "None");
      });

  const double default_fc = CameraIntrinsics{}.f_c_px;
  const OrientationSettings defaults;

  m.def("sun_vector", [](const py::object& aop_deg, const py::object& dop, double f_c_px,
                         std::optional<std::pair<double, double>> principal_point, double element_px,
                         const std::string& conversion, bool dop_weighting, double min_dop,
                         std::optional<std::vector<double>> prior_sun, double horizon_margin_deg,
                         bool correct_noise_bias) {
        const Image im = image_points(aop_deg, dop, f_c_px, principal_point, element_px);
        if (correct_noise_bias && dop.is_none()) throw py::value_error("correct_noise_bias: needs dop (None given)");
        const OrientationSettings s = settings_from(conversion, dop_weighting, min_dop, prior_sun,
                                                    horizon_margin_deg, correct_noise_bias);
        py::gil_scoped_release release;
        return sun_vector_eigen(im.points, im.camera, s);
      }, "aop_deg"_a, "dop"_a = py::none(), py::kw_only(), "f_c_px"_a = default_fc,
      "principal_point"_a = py::none(), "element_px"_a = 2.0, "conversion"_a = "meridional",
      "dop_weighting"_a = false, "min_dop"_a = 0.0, "prior_sun"_a = py::none(),
      "horizon_margin_deg"_a = defaults.horizon_margin_deg, "correct_noise_bias"_a = false,
      (std::string("The sun vector of a sky image by H17's eigenvector method (Eqs. 6–13): the "
                   "eigenvector of EEᵀ for its smallest eigenvalue.\n\n") +
       kFrames + "\n\n" + kCameraArgs +
       "\nReturns polrig.SunVector (a status, never an exception, when there is no sun).\n"
       "Raises ValueError for a bad shape or setting.").c_str());

  m.def("orient", [](const py::object& aop_deg, const py::object& dop,
                     std::optional<double> sun_azimuth_deg, double f_c_px,
                     std::optional<std::pair<double, double>> principal_point, double element_px,
                     const std::string& conversion, bool dop_weighting, double min_dop,
                     std::optional<std::vector<double>> prior_sun, double horizon_margin_deg,
                     double zenith_radius_px, double line_aop_tolerance_deg,
                     double line_min_radius_px, double hough_bin_deg, bool correct_noise_bias) {
        const Image im = image_points(aop_deg, dop, f_c_px, principal_point, element_px);
        if (correct_noise_bias && dop.is_none()) throw py::value_error("correct_noise_bias: needs dop (None given)");
        OrientationSettings s = settings_from(conversion, dop_weighting, min_dop, prior_sun,
                                              horizon_margin_deg, correct_noise_bias);
        s.zenith_radius_px = zenith_radius_px;
        s.line_aop_tolerance_deg = line_aop_tolerance_deg;
        s.line_min_radius_px = line_min_radius_px;
        s.hough_bin_deg = hough_bin_deg;
        check_orientation_settings(s);
        if (sun_azimuth_deg && !std::isfinite(*sun_azimuth_deg))
          throw py::value_error(fmt::format("sun_azimuth_deg: {} is not finite", *sun_azimuth_deg));
        py::gil_scoped_release release;
        const auto est = orient_frame(im.points, im.camera, sun_azimuth_deg, s);
        return std::vector<OrientationEstimate>(est.begin(), est.end());
      }, "aop_deg"_a, "dop"_a = py::none(), py::kw_only(), "sun_azimuth_deg"_a = py::none(),
      "f_c_px"_a = default_fc, "principal_point"_a = py::none(), "element_px"_a = 2.0,
      "conversion"_a = "meridional", "dop_weighting"_a = false, "min_dop"_a = 0.0,
      "prior_sun"_a = py::none(), "horizon_margin_deg"_a = defaults.horizon_margin_deg,
      "zenith_radius_px"_a = defaults.zenith_radius_px,
      "line_aop_tolerance_deg"_a = defaults.line_aop_tolerance_deg,
      "line_min_radius_px"_a = defaults.line_min_radius_px, "hough_bin_deg"_a = defaults.hough_bin_deg,
      "correct_noise_bias"_a = false,
      (std::string("One sky frame through the three methods of H17 (§2.3, §4.2): the eigenvector "
                   "method, then the single-point (zenith) and line-detection (Hough) comparators "
                   "with the eigenvector's sun azimuth as their prior for the meridian's half.\n\n") +
       kFrames + "\n\n" + kCameraArgs +
       "\nsun_azimuth_deg: the sun's geographic azimuth A_s at the frame's time (e.g. "
       "polrig.Sky(...).sun().azimuth_deg), for the heading; zenith_radius_px: the single point's "
       "radius around the principal point; line_aop_tolerance_deg, line_min_radius_px, "
       "hough_bin_deg: the line detection's band |φ − 90°|, its exclusion radius and its bins.\n"
       "Returns a list of three polrig.OrientationEstimate (eigenvector, single-point, "
       "line-detection).").c_str());

  m.def("camera_heading", [](double sun_azimuth_deg, double sun_az_camera_deg) {
        if (!std::isfinite(sun_azimuth_deg) || !std::isfinite(sun_az_camera_deg))
          throw py::value_error(fmt::format("camera_heading: arguments must be finite, got {} and {}",
                                            sun_azimuth_deg, sun_az_camera_deg));
        return camera_heading_deg(sun_azimuth_deg, sun_az_camera_deg);
      }, "sun_azimuth_deg"_a, "sun_az_camera_deg"_a,
      "H17 Eq. 14 in the sense of spec §0: the heading of a level camera (the geographic azimuth of "
      "X_l, degrees clockwise from north, [0, 360)) from the sun's geographic azimuth A_s and its "
      "azimuth α_S in frame l (from X_l towards Y_l): H = A_s + α_S.");

  m.def("orient_dofp_dataset", [](const std::filesystem::path& dir, const std::optional<std::filesystem::path>& params,
                                  const std::string& conversion, bool dop_weighting,
                                  std::optional<double> heading_prior_deg, const py::object& progress,
                                  bool correct_noise_bias) {
        OrientationSettings s = settings_from(conversion, dop_weighting, 0.0, std::nullopt,
                                              OrientationSettings{}.horizon_margin_deg, correct_noise_bias);
        if (heading_prior_deg && !std::isfinite(*heading_prior_deg))
          throw py::value_error(fmt::format("heading_prior_deg: {} is not finite", *heading_prior_deg));
        const Progress p = progress_from(progress);
        std::vector<FrameOrientation> frames;
        {
          py::gil_scoped_release release;
          frames = orient_dofp_folder(dir, params.value_or(std::filesystem::path()), s, heading_prior_deg, p);
        }
        py::list out;
        for (const FrameOrientation& f : frames) {
          py::dict d;
          d["frame"] = f.frame;
          d["true_heading_deg"] = f.true_heading_deg;
          d["estimates"] = std::vector<OrientationEstimate>(f.estimates.begin(), f.estimates.end());
          out.append(d);
        }
        return out;
      }, "dir"_a, py::kw_only(), "params"_a = py::none(), "conversion"_a = "meridional",
      "dop_weighting"_a = false, "heading_prior_deg"_a = py::none(), "progress"_a = py::none(),
      "correct_noise_bias"_a = false,
      (std::string("`polrig orient DIR`'s computation (report/orientation_report.h): every polarized "
                   "frame of a DoFP camera dataset through the three methods. params: a calibration's "
                   "params.exr (None: the nominal parameters); heading_prior_deg: an approximate heading "
                   "of X_l at table angle 0 (each frame adds its table angle), for the sun/antisun "
                   "choice near the horizon; correct_noise_bias: the eigenvector method without its "
                   "noise bias (`--correct-noise-bias`, docs/physics.md §15). Returns a list of dicts "
                   "(frame, true_heading_deg or None, estimates: three polrig.OrientationEstimate). Raises "
                   "RigError for a rig without frames, DataError for a file that cannot be read.\n") + kProgressDoc).c_str());
}

}  // namespace polrig::python
