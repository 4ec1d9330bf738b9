// polrig.calibrate, its result, the calibration parameters (apply, params.yaml) and the measured
// data reader: the calls of `polrig calibrate` and `polrig apply` on NumPy arrays.
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <pybind11/operators.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.h"
#include "convert.h"
#include "polrig/calib/angles.h"
#include "polrig/calib/model.h"
#include "polrig/calib/pipeline.h"
#include "polrig/calib/rig_options.h"
#include "polrig/calib/stop_corrections.h"
#include "polrig/device/electronics.h"
#include "polrig/io/csv.h"
#include "polrig/io/measured.h"
#include "polrig/io/params_yaml.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/units.h"
#include "rig_handle.h"
#include "sky_args.h"

namespace polrig::python {
namespace {

// A result array after convert.h's check_finite (the CLI's refusal of a non-finite value).
py::array_t<double> finite_result(py::array_t<double> a, const char* name, bool allow_nan = false) {
  check_finite(a, name, allow_nan);
  return a;
}

// A calibration and the options it ran with (params.yaml's volts per decade, the film axes of
// the replacement analysis's theory values).
struct PyCalibration {
  CalibrationResult result;
  CalibrationOptions options;
};

// params.yaml as read back, for `polrig apply`.
struct PyParamsFile {
  LoadedParams loaded;
  std::string origin;
};

// The columns of `polrig apply`'s angles.csv.
struct AppliedAngles {
  py::object theta_R_deg, error_deg;  // None without reference angles
  py::array_t<double> theta12_deg, theta13_deg, theta23_deg, theta_sec_deg, d;
  py::array_t<std::int64_t> section;
};

// What read_measured / read_voltages give.
struct PyMeasured {
  MeasuredData data;
  bool have_angles = true;
  std::optional<PyRig> rig;  // the dataset's rig.yaml, as a polrig.Rig
};

PyMeasured measured_of(MeasuredData&& data) {
  PyMeasured m{std::move(data), true, std::nullopt};
  if (m.data.rig) m.rig = PyRig{load_rig(m.data.rig_origin)};
  return m;
}

py::object or_none(const std::optional<ArrayLike>& a) { return a ? a->obj : py::none(); }

constexpr const char* kMethods = "section, cs, cs-nc or nc";

template <std::size_t N>
std::array<double, N> fixed_array(const py::handle& obj, const char* name) {
  const DoubleArray a = as_array(obj, name, 1);
  if (a.size() != static_cast<py::ssize_t>(N))
    throw py::value_error(fmt::format("{}: expected {} values, got {}", name, N, a.size()));
  const std::vector<double> v = finite_values(a, name);
  std::array<double, N> out{};
  std::copy(v.begin(), v.end(), out.begin());
  return out;
}

double positive_finite(double v, const char* name) {
  if (!(std::isfinite(v) && v > 0))
    throw py::value_error(fmt::format("{}: expected a positive finite number, got {}", name, v));
  return v;
}

// V of shape (N, 3), finite, as rows.
std::vector<std::array<double, 3>> voltage_rows(const py::handle& obj, const char* name) {
  const DoubleArray a = as_array(obj, name, 2, 3);
  const std::vector<double> v = finite_values(a, name);
  std::vector<std::array<double, 3>> rows(v.size() / 3);
  for (std::size_t n = 0; n < rows.size(); ++n) rows[n] = {v[3 * n], v[3 * n + 1], v[3 * n + 2]};
  return rows;
}

PairInversion inversion_of(const std::string& name) {
  if (name == "atan2") return PairInversion::Atan2;
  if (name == "arctan-sign") return PairInversion::ArctanSignExtension;
  throw py::value_error(fmt::format("inversion='{}': expected 'atan2' or 'arctan-sign'", name));
}

// The CLI's refusal of a fit that is not usable, for what only a usable fit has (the model,
// params.yaml, the replacement analysis).
const PyCalibration& usable_or_throw(const PyCalibration& c) {
  if (!c.result.usable())
    throw CalibrationError(fmt::format("method {}: the fit is not usable: {}",
                                       method_name(c.result.method), c.result.fit.summary.brief_report()));
  return c;
}

py::array_t<double> rows_array(const std::vector<std::array<double, 3>>& rows) {
  std::vector<double> flat;
  flat.reserve(3 * rows.size());
  for (const auto& r : rows) flat.insert(flat.end(), r.begin(), r.end());
  return take(std::move(flat), {static_cast<py::ssize_t>(rows.size()), 3});
}

// θ12, θ13, θ23, θ_sec, section and d of every row, as `polrig apply` computes them; a DataError
// naming the row for voltages that give no angle (its rules: calib/angles.h measured_angles).
AppliedAngles apply_rows(const CalibrationParams& p, double volts_per_decade, const py::handle& V,
                         const py::handle& theta_R_deg, const std::string& inversion) {
  Electronics e;
  e.volts_per_decade = positive_finite(volts_per_decade, "volts_per_decade");
  const PairInversion method = inversion_of(inversion);
  const std::vector<std::array<double, 3>> rows = voltage_rows(V, "V");
  const std::size_t n = rows.size();
  std::vector<double> ref;
  if (!theta_R_deg.is_none()) {
    ref = finite_values(as_array(theta_R_deg, "theta_R_deg", 1), "theta_R_deg");
    if (ref.size() != n)
      throw py::value_error(fmt::format("theta_R_deg: {} values for {} rows of V", ref.size(), n));
  }
  std::vector<double> t12(n), t13(n), t23(n), tsec(n), d(n), err(ref.empty() ? 0 : n);
  std::vector<std::int64_t> section(n);
  {
    py::gil_scoped_release release;
    for (std::size_t k = 0; k < n; ++k) {
      const MeasuredAngles m = measured_angles(p, e, rows[k], method);
      if (!m.problem.empty()) throw DataError(fmt::format("V row {}: {}", k, m.problem));
      t12[k] = m.angles.theta12.theta_deg;
      t13[k] = m.angles.theta13.theta_deg;
      t23[k] = m.angles.theta23.theta_deg;
      tsec[k] = m.angles.theta_sec_deg;
      section[k] = m.angles.section;
      d[k] = m.d;
      if (!ref.empty()) err[k] = axis_difference_deg(m.angles.theta_sec_deg, ref[k]);
    }
  }
  AppliedAngles out;
  out.theta_R_deg = ref.empty() ? py::object(py::none()) : py::object(take(std::move(ref)));
  out.error_deg = err.empty() ? py::object(py::none())
                              : py::object(finite_result(take(std::move(err)), "error_deg"));
  out.theta12_deg = finite_result(take(std::move(t12)), "theta12_deg");
  out.theta13_deg = finite_result(take(std::move(t13)), "theta13_deg");
  out.theta23_deg = finite_result(take(std::move(t23)), "theta23_deg");
  out.theta_sec_deg = finite_result(take(std::move(tsec)), "theta_sec_deg");
  out.d = finite_result(take(std::move(d)), "d");
  out.section = take(std::move(section));
  return out;
}

py::tuple apply_pair(const CalibrationParams& p, double v_dec, const py::handle& V,
                     const std::string& inversion) {
  AppliedAngles a = apply_rows(p, v_dec, V, py::none(), inversion);
  return py::make_tuple(a.theta_sec_deg, a.d);
}

std::string params_repr(const CalibrationParams& p) {
  return fmt::format("CalibrationParams(alpha_deg=[{}], k_mV=[{}], kv=[{}], kd=[{}])",
                     fmt::join(p.alpha_deg, ", "), fmt::join(p.k_mV, ", "), fmt::join(p.kv, ", "),
                     fmt::join(p.kd, ", "));
}

std::vector<EvalPoint> eval_points(const py::handle& theta_ref_deg, const py::handle& V,
                                   const py::handle& d_ratio) {
  const std::vector<double> theta = finite_values(as_array(theta_ref_deg, "theta_ref_deg", 1), "theta_ref_deg");
  const std::vector<std::array<double, 3>> rows = voltage_rows(V, "V");
  if (rows.size() != theta.size())
    throw py::value_error(fmt::format("V: {} rows for {} values of theta_ref_deg", rows.size(), theta.size()));
  std::vector<double> ratio(theta.size(), 1.0);
  if (!d_ratio.is_none()) {
    ratio = finite_values(as_array(d_ratio, "d_ratio", 1), "d_ratio");
    if (ratio.size() != theta.size())
      throw py::value_error(fmt::format("d_ratio: {} values for {} points", ratio.size(), theta.size()));
  }
  std::vector<EvalPoint> points(theta.size());
  for (std::size_t n = 0; n < points.size(); ++n) points[n] = {theta[n], rows[n], ratio[n]};
  return points;
}

py::list replacement_list(const std::vector<Replacement>& rep) {
  py::list out;
  for (const Replacement& r : rep) out.append(py::make_tuple(r.label, r.mask, r.accuracy_deg));
  return out;
}

py::dict accuracy_dict(const std::array<AngleAccuracy, 4>& a) {
  static const char* names[4] = {"theta12", "theta13", "theta23", "theta_sec"};
  py::dict d;
  for (int k = 0; k < 4; ++k) d[names[k]] = a[static_cast<std::size_t>(k)];
  return d;
}

PyCalibration run_calibrate(const py::handle& theta_R_deg, const py::handle& V,
                            const std::string& method_name_text, std::optional<double> d_a,
                            const py::object& rig_obj, double nc_threshold, int nc_min_points,
                            const py::object& film_axes_deg, std::optional<double> volts_per_decade,
                            const std::string& drift, const py::object& utc, const py::object& t_s,
                            const py::object& site, const FitOptions& fit) {
  const std::optional<CalibrationMethod> method = parse_method(method_name_text);
  if (!method)
    throw py::value_error(fmt::format("method='{}': expected {}", method_name_text, kMethods));
  const std::optional<DriftMode> drift_mode = parse_drift_mode(drift);
  if (!drift_mode)
    throw py::value_error(fmt::format("drift='{}': expected none, angle, per-stop or linear", drift));
  const bool raw_stops = uses_raw_stops(*method);
  if (*drift_mode != DriftMode::None && !raw_stops)
    throw py::value_error(fmt::format("drift='{}' needs method 'nc' or 'section' (the raw stops), "
                                      "not '{}': a CS point mixes two times", drift, method_name_text));
  const NoncontinuousRule rule{nc_threshold, nc_min_points};
  if (const auto problem = noncontinuous_rule_problem(rule)) throw py::value_error(*problem);
  if (d_a && !(*d_a > 0 && *d_a < 1))
    throw py::value_error(fmt::format("d_a: expected a degree of polarization in (0, 1), got {}", *d_a));

  // The stops.
  const std::vector<double> theta = finite_values(as_array(theta_R_deg, "theta_R_deg", 1), "theta_R_deg");
  const std::vector<std::array<double, 3>> rows = voltage_rows(V, "V");
  if (rows.size() != theta.size())
    throw py::value_error(fmt::format("V: {} rows for {} values of theta_R_deg", rows.size(), theta.size()));
  std::vector<StopVoltages> stops(theta.size());
  for (std::size_t k = 0; k < stops.size(); ++k) {
    stops[k] = {theta[k], rows[k], fmt::format("stop {}", k)};
    const std::string problem = adc_range_problem(rows[k]);
    if (!problem.empty()) throw DataError(fmt::format("V row {}: {}", k, problem));
  }

  // The sensor (film axes, amplifier) and d_a, as `polrig calibrate --rig`.
  if (!rig_obj.is_none() && !py::isinstance<PyRig>(rig_obj))
    throw py::type_error(fmt::format("rig: expected a polrig.Rig or None, got {}",
                                     py::str(py::type::of(rig_obj)).cast<std::string>()));
  if (!rig_obj.is_none())
    require(rig_obj.cast<const PyRig&>(), Instrument::kPairVoltages, "calibrate method='" + method_name_text + "'");
  const Rig rig = rig_obj.is_none() ? Rig{} : rig_obj.cast<const PyRig&>().rig();
  if (rig.light->has(Source::kTimeDependent) && !raw_stops)
    throw py::value_error(fmt::format("method='{}': the rig's light is the sky, which drifts with "
                                      "the sun during the run; use method='nc' with drift="
                                      "'per-stop' (or 'angle', 'linear', 'none')", method_name_text));
  // d_a: given, else the rig's stated d (only a rig the caller gave states one).
  const std::optional<double> rig_d =
      rig_obj.is_none() ? std::nullopt : std::optional<double>(rig.device.d);
  CalibrationOptions o = calibration_options(rig, d_a ? d_a : rig_d, rule);
  o.method = *method;
  if (d_a) o.d_a_source = "d_a";
  else if (rig_d) o.d_a_source = "the rig's device.d";
  if (!film_axes_deg.is_none()) o.film_axis_deg = fixed_array<6>(film_axes_deg, "film_axes_deg");
  if (volts_per_decade) o.volts_per_decade = positive_finite(*volts_per_decade, "volts_per_decade");
  o.fit = fit;

  // The sun-drift corrections, as --drift.
  if (*drift_mode != DriftMode::None) {
    DriftRequest request;
    request.mode = *drift_mode;
    if (!utc.is_none()) request.utc = utc_times(utc, "utc");
    if (!t_s.is_none()) request.t_s = finite_values(as_array(t_s, "t_s", 1), "t_s");
    if (!request.utc.empty() && request.utc.size() != stops.size())
      throw py::value_error(fmt::format("utc: {} times for {} stops", request.utc.size(), stops.size()));
    if (!request.t_s.empty() && request.t_s.size() != stops.size())
      throw py::value_error(fmt::format("t_s: {} times for {} stops", request.t_s.size(), stops.size()));
    request.origin = "the stops";
    request.drift_option = fmt::format("drift='{}'", drift);
    request.site_option = "site=(lat, lon)";
    request.times_missing = "needs the stops' times: utc= (each stop's UTC), or t_s= with a sky rig";
    std::optional<Site> s;
    std::string site_from;
    if (!site.is_none()) {
      s = site_of(site, "site");
      site_from = fmt::format("site {},{}", s->lat_deg, s->lon_deg);
      if (s->height_m != 0) site_from += fmt::format(" (height {} m)", s->height_m);
    }
    try {
      o.corrections = sun_drift_corrections(request, s, site_from, rig);
    } catch (const std::invalid_argument& e) {
      throw DataError(e.what());
    }
  }

  PyCalibration out;
  out.options = o;
  {
    py::gil_scoped_release release;
    out.result = calibrate(stops, o);
  }
  return out;
}

template <class F>
py::array_t<double> point_column(const std::vector<EvalPoint>& points, const char* name, F f) {
  std::vector<double> v(points.size());
  for (std::size_t n = 0; n < points.size(); ++n) v[n] = f(points[n]);
  return finite_result(take(std::move(v)), name);
}

template <class F>
py::array_t<double> error_column(const std::vector<AngleErrors>& errors, const char* name, F f) {
  std::vector<double> v(errors.size());
  for (std::size_t n = 0; n < errors.size(); ++n) v[n] = f(errors[n]);
  return finite_result(take(std::move(v)), name);
}

const char* kApplyDoc = R"doc(
V: pair voltages, shape (N, 3), volts (V1, V2, V3 of each row).
volts_per_decade: the log amplifier's scale, V per decade (0.5 for the seed sensor; params.yaml's
    volts_per_decade).
inversion: 'atan2' (2θ = atan2(d·sin2θ, d·cos2θ)) or 'arctan-sign' (the paper's arctan with the
    sign extension); `polrig apply` uses 'atan2'.
Raises ValueError for a V not of shape (N, 3) or not finite, and polrig.DataError naming the row
for voltages that give no angle (outside any ADC's range |V| ≤ 100 V, beyond 300 decades of light
ratio from the pair's offset, or no finite angle), as `polrig apply` refuses them.)doc";

void bind_params(py::module_& m) {
  py::class_<AppliedAngles>(m, "AppliedAngles",
                            "The columns of `polrig apply`'s angles.csv, each (N,), one per row of V.")
      .def_readonly("theta12_deg", &AppliedAngles::theta12_deg, "θ12 from pair voltages V1, V2, degrees in [0, 180).")
      .def_readonly("theta13_deg", &AppliedAngles::theta13_deg, "θ13 from V1, V3, degrees in [0, 180).")
      .def_readonly("theta23_deg", &AppliedAngles::theta23_deg, "θ23 from V2, V3, degrees in [0, 180).")
      .def_readonly("theta_sec_deg", &AppliedAngles::theta_sec_deg,
                    "θ_sec of the section algorithm (the pair without the section's bad voltage), degrees.")
      .def_readonly("section", &AppliedAngles::section, "The section 0..5 θ12 falls in (int64).")
      .def_readonly("d", &AppliedAngles::d, "Degree of polarization of θ_sec's pair (scaled by d_a).")
      .def_readonly("theta_R_deg", &AppliedAngles::theta_R_deg, "The reference angles given, degrees, or None.")
      .def_readonly("error_deg", &AppliedAngles::error_deg,
                    "θ_sec − theta_R_deg wrapped to [−90°, 90°), degrees; None without theta_R_deg.")
      .def("__len__", [](const AppliedAngles& a) { return a.d.size(); })
      .def("__repr__", [](const AppliedAngles& a) { return fmt::format("<polrig.AppliedAngles: {} rows>", a.d.size()); });

  py::class_<CalibrationParams> p(m, "CalibrationParams", R"doc(
Eq. 15's parameters of the six-photodiode sensor (Wang et al. 2019 §3.4–3.5, Table 2): what a
simulated device carries as its truth and what a calibration estimates.

alpha_deg: (6,) installation angles α_m in the doubled-angle domain, degrees.
k_mV: (3,) additive offset of each pair's voltage, mV.
kv: (3,) log-amplifier gain deviation (1 = nominal).
kd: (6,) polarizer non-ideality (1 + kd_m)·d; 0 = ideal film, ≤ 0 physically.
The fields are float64 arrays (copies); assign a whole array to change one.
CalibrationParams() are the theory values for the seed sensor's film axes.)doc");
  p.def(py::init([](const std::optional<ArrayLike>& alpha, const std::optional<ArrayLike>& k,
                    const std::optional<ArrayLike>& kv, const std::optional<ArrayLike>& kd) {
          CalibrationParams c;
          if (alpha) c.alpha_deg = fixed_array<6>(alpha->obj, "alpha_deg");
          if (k) c.k_mV = fixed_array<3>(k->obj, "k_mV");
          if (kv) c.kv = fixed_array<3>(kv->obj, "kv");
          if (kd) c.kd = fixed_array<6>(kd->obj, "kd");
          return c;
        }),
        py::kw_only(), py::arg("alpha_deg") = py::none(), py::arg("k_mV") = py::none(),
        py::arg("kv") = py::none(), py::arg("kd") = py::none(),
        "Parameters from arrays (alpha_deg (6,) degrees, k_mV (3,) mV, kv (3,), kd (6,)); each "
        "omitted one keeps its theory value for the seed sensor's film axes. ValueError for a "
        "wrong length or a non-finite value.")
      .def_property("alpha_deg", [](const CalibrationParams& c) { return to_array(c.alpha_deg); },
                    [](CalibrationParams& c, const py::handle& v) { c.alpha_deg = fixed_array<6>(v, "alpha_deg"); },
                    "(6,) installation angles α_1..α_6 (doubled-angle domain), degrees.")
      .def_property("k_mV", [](const CalibrationParams& c) { return to_array(c.k_mV); },
                    [](CalibrationParams& c, const py::handle& v) { c.k_mV = fixed_array<3>(v, "k_mV"); },
                    "(3,) offsets k_1..k_3 of the pair voltages, mV.")
      .def_property("kv", [](const CalibrationParams& c) { return to_array(c.kv); },
                    [](CalibrationParams& c, const py::handle& v) { c.kv = fixed_array<3>(v, "kv"); },
                    "(3,) log-amplifier gain deviations kv_1..kv_3 (dimensionless, 1 nominal).")
      .def_property("kd", [](const CalibrationParams& c) { return to_array(c.kd); },
                    [](CalibrationParams& c, const py::handle& v) { c.kd = fixed_array<6>(v, "kd"); },
                    "(6,) polarizer non-idealities kd_1..kd_6 (dimensionless, 0 ideal).")
      .def_static("theory", [](const ArrayLike& axes) {
            return CalibrationParams::theory(fixed_array<6>(axes.obj, "film_axes_deg"));
          }, py::arg("film_axes_deg"),
          "Nominal values for films at the given axes ((6,), degrees in the sensor frame, as the "
          "rig key device.film_axes_deg): α_j = −2·f_j, α_h = 180° − 2·f_h wrapped to "
          "(−180°, 180°]; k = 0, kv = 1, kd = 0.")
      .def_static("wang2019_indoor", &CalibrationParams::wang2019_indoor,
                  "Table 2's \"Indoor\" column of Wang et al. 2019.")
      .def(py::self == py::self)
      .def("__eq__", [](const CalibrationParams&, const py::object&) { return false; })
      .def("__repr__", &params_repr)
      .def("copy", [](const CalibrationParams& c) { return c; }, "An independent copy.")
      .def("__copy__", [](const CalibrationParams& c) { return c; })
      .def("__deepcopy__", [](const CalibrationParams& c, py::dict) { return c; }, py::arg("memo"))
      .def(py::pickle(
          [](const CalibrationParams& c) {
            return py::make_tuple(to_array(c.alpha_deg), to_array(c.k_mV), to_array(c.kv), to_array(c.kd));
          },
          [](const py::tuple& t) {
            CalibrationParams c;
            c.alpha_deg = fixed_array<6>(t[0], "alpha_deg");
            c.k_mV = fixed_array<3>(t[1], "k_mV");
            c.kv = fixed_array<3>(t[2], "kv");
            c.kd = fixed_array<6>(t[3], "kd");
            return c;
          }))
      .def("apply", [](const CalibrationParams& c, const ArrayLike& V, double v_dec,
                       const std::string& inversion) { return apply_pair(c, v_dec, V.obj, inversion); },
           py::arg("V"), py::kw_only(), py::arg("volts_per_decade") = Electronics{}.volts_per_decade,
           py::arg("inversion") = "atan2",
           (std::string("The polarization angle and degree of every row of voltages, as `polrig "
                        "apply`: returns (theta_deg, d), each (N,): θ_sec in [0°, 180°) from the "
                        "section algorithm and the d of the pair it used (scaled by the d_a of "
                        "the decoupling).\n") + kApplyDoc).c_str())
      .def("angles", [](const CalibrationParams& c, const ArrayLike& V, double v_dec,
                        const std::string& inversion, const std::optional<ArrayLike>& theta_R_deg) {
             return apply_rows(c, v_dec, V.obj, or_none(theta_R_deg), inversion);
           }, py::arg("V"), py::kw_only(), py::arg("volts_per_decade") = Electronics{}.volts_per_decade,
           py::arg("inversion") = "atan2", py::arg("theta_R_deg") = py::none(),
           (std::string("Every column of `polrig apply`'s angles.csv for each row of voltages: "
                        "an AppliedAngles (θ12, θ13, θ23, θ_sec, section, d; with theta_R_deg, "
                        "(N,) degrees, also error_deg = θ_sec − θ_R wrapped to [−90°, 90°)).\n") +
            kApplyDoc).c_str());

  py::class_<PyParamsFile>(m, "ParamsFile", "A params.yaml read back: the parameters, d_a and the amplifier scale.")
      .def_property_readonly("params", [](const PyParamsFile& f) { return f.loaded.params; },
                             "The calibrated parameters (CalibrationParams).")
      .def_property_readonly("d_a", [](const PyParamsFile& f) { return f.loaded.d_a; },
                             "The degree of polarization d_a of the decoupling.")
      .def_property_readonly("volts_per_decade", [](const PyParamsFile& f) { return f.loaded.volts_per_decade; },
                             "The log amplifier's scale the parameters were fitted with, V per decade.")
      .def_property_readonly("origin", [](const PyParamsFile& f) { return f.origin; }, "The file read.")
      .def("apply", [](const PyParamsFile& f, const ArrayLike& V, const std::string& inversion) {
             return apply_pair(f.loaded.params, f.loaded.volts_per_decade, V.obj, inversion);
           }, py::arg("V"), py::kw_only(), py::arg("inversion") = "atan2",
           "CalibrationParams.apply with the file's volts_per_decade: (theta_deg, d), each (N,), "
           "for V of shape (N, 3) volts.")
      .def("angles", [](const PyParamsFile& f, const ArrayLike& V, const std::string& inversion,
                        const std::optional<ArrayLike>& theta_R_deg) {
             return apply_rows(f.loaded.params, f.loaded.volts_per_decade, V.obj, or_none(theta_R_deg),
                               inversion);
           }, py::arg("V"), py::kw_only(), py::arg("inversion") = "atan2",
           py::arg("theta_R_deg") = py::none(),
           "`polrig apply PARAMS VOLTAGES`: the AppliedAngles of every row of V ((N, 3) volts), with "
           "error_deg when theta_R_deg ((N,) degrees) is given.")
      .def("__repr__", [](const PyParamsFile& f) {
        return fmt::format("<polrig.ParamsFile {}: d_a = {}, volts_per_decade = {}>", f.origin,
                           f.loaded.d_a, f.loaded.volts_per_decade);
      });

  m.def("read_params", [](const std::filesystem::path& path) {
          return PyParamsFile{read_params_yaml(path), path.string()};
        },
        py::arg("path"),
        "Reads a params.yaml written by `polrig calibrate` (or CalibrationResult.save); path: str or "
        "os.PathLike. Returns a "
        "ParamsFile (params, d_a, volts_per_decade). Raises polrig.DataError naming the file, the "
        "line and the key.");
}

void bind_result(py::module_& m) {
  py::class_<FitSummary>(m, "FitSummary", R"doc(
How the Levenberg–Marquardt fit of Eq. 15 ended (after Ceres Solver's Solver::Summary). A fit
that fails is data, not an exception: termination says how, message why.)doc")
      .def_property_readonly("termination", [](const FitSummary& s) { return std::string(termination_name(s.termination)); },
                             "'converged', 'no_convergence', 'outside_domain', 'rank_deficient' or "
                             "'too_few_observations'; only 'converged' gives parameters to use.")
      .def_readonly("message", &FitSummary::message, "Why it stopped, for the user.")
      .def_readonly("solver_status", &FitSummary::solver_status,
                    "Eigen's LevenbergMarquardtSpace::Status, '' if the solver did not run.")
      .def_readonly("initial_cost", &FitSummary::initial_cost, "½·Σr² at the start, V² (NaN if not run).")
      .def_readonly("final_cost", &FitSummary::final_cost, "½·Σr² at the end, V² (NaN if not run).")
      .def_readonly("iterations", &FitSummary::iterations, "Jacobian evaluations.")
      .def_readonly("evaluations", &FitSummary::evaluations, "Residual evaluations.")
      .def_readonly("observations", &FitSummary::observations, "Voltages fitted.")
      .def("usable", &FitSummary::usable, "True when the fit converged (termination 'converged').")
      .def("brief_report", &FitSummary::brief_report,
           "One line: termination, iterations, evaluations, observations, costs and the message.")
      .def("__repr__", [](const FitSummary& s) { return "<polrig.FitSummary " + s.brief_report() + ">"; });

  py::class_<AngleAccuracy>(m, "AngleAccuracy",
                            "The range of one error curve over the points (accuracy.csv's row), degrees.")
      .def_readonly("max_deg", &AngleAccuracy::max_deg, "Largest error, degrees.")
      .def_readonly("min_deg", &AngleAccuracy::min_deg, "Smallest error, degrees.")
      .def_property_readonly("accuracy_deg", &AngleAccuracy::accuracy_deg,
                             "Half the range (max − min)/2, degrees: the paper's ± accuracy (§4.5).")
      .def("__repr__", [](const AngleAccuracy& a) {
        return fmt::format("<polrig.AngleAccuracy ±{}° (max {}, min {})>", a.accuracy_deg(), a.max_deg, a.min_deg);
      });

  py::class_<PyCalibration>(m, "CalibrationResult", R"doc(
One calibration (polrig.calibrate): the fit, the decoupled parameters and their accuracy at the
points, as `polrig calibrate` writes them (params.yaml, points.csv, errors.csv, accuracy.csv).
When the fit is not usable (fit.termination != 'converged') params, errors and accuracy are not
filled in (theory values, empty arrays, zeros); the points are.)doc")
      .def_property_readonly("method", [](const PyCalibration& c) { return std::string(method_name(c.result.method)); },
                             "'section', 'cs', 'cs-nc' or 'nc'.")
      .def_property_readonly("d_a", [](const PyCalibration& c) { return c.result.d_a; },
                             "The degree of polarization the parameters were decoupled with.")
      .def_property_readonly("d_a_source", [](const PyCalibration& c) { return c.result.d_a_source; },
                             "Where d_a came from: 'd_a', \"the rig's device.d\" or how it was chosen.")
      .def_property_readonly("drift", [](const PyCalibration& c) { return c.result.drift; },
                             "How the sun-drift corrections were made (params.yaml's drift), '' without.")
      .def_property_readonly("volts_per_decade", [](const PyCalibration& c) { return c.options.volts_per_decade; },
                             "The log amplifier's scale the fit used, V per decade.")
      .def_property_readonly("params", [](const PyCalibration& c) { return c.result.params; },
                             "The calibrated parameters (CalibrationParams), decoupled with d_a.")
      .def_property_readonly("standard_error", [](const PyCalibration& c) { return c.result.standard_error; },
                             "Standard errors of the parameters (CalibrationParams; kd's from c's: "
                             "se(c_m)/d_a); NaN without redundancy (18 observations).")
      .def_property_readonly("c", [](const PyCalibration& c) { return to_array(c.result.fit.params.c); },
                             "(6,) the fitted products c_m = (1 + kd_m)·d before decoupling.")
      .def_property_readonly("fit", [](const PyCalibration& c) { return c.result.fit.summary; },
                             "The FitSummary: how the fit ended.")
      .def_property_readonly("residual_rms_V", [](const PyCalibration& c) { return c.result.fit.residual_rms_V; },
                             "RMS of the fit's residuals, V.")
      .def_property_readonly("theta_ref_deg", [](const PyCalibration& c) {
            return point_column(c.result.points, "theta_ref_deg",
                                [](const EvalPoint& p) { return p.theta_ref_deg; });
          }, "(M,) reference angle of each point (raw stop, or CS point), degrees (points.csv).")
      .def_property_readonly("V", [](const PyCalibration& c) {
            std::vector<std::array<double, 3>> rows;
            for (const EvalPoint& p : c.result.points) rows.push_back(p.V);
            return finite_result(rows_array(rows), "V");
          }, "(M, 3) voltages at each point, V (a CS point's: the mean of its two stops).")
      .def_property_readonly("d_ratio", [](const PyCalibration& c) {
            return point_column(c.result.points, "d_ratio", [](const EvalPoint& p) { return p.d_ratio; });
          }, "(M,) the light's d at each point over d at the first stop (1 without drift corrections).")
      .def_property_readonly("V_model", [](const PyCalibration& c) {
            usable_or_throw(c);
            std::vector<std::array<double, 3>> rows;
            for (const EvalPoint& p : c.result.points) {
              std::array<double, 3> v{};
              for (int i = 0; i < 3; ++i)
                v[static_cast<std::size_t>(i)] = eq15_voltage(c.result.fit.params, c.options.volts_per_decade,
                                                              i, p.theta_ref_deg, p.d_ratio);
              rows.push_back(v);
            }
            return finite_result(rows_array(rows), "V_model");
          }, "(M, 3) the fitted Eq. 15 at each point, V (points.csv's V*_model). Raises "
             "polrig.CalibrationError when the fit is not usable.")
      .def_property_readonly("fitted", [](const PyCalibration& c) {
            const std::size_t n = c.result.points.size();
            const bool known = c.result.fitted.size() == 3;  // only a usable fit records them
            py::array_t<bool> a({static_cast<py::ssize_t>(n), py::ssize_t{3}});
            auto w = a.mutable_unchecked<2>();
            for (std::size_t k = 0; k < n; ++k)
              for (std::size_t i = 0; i < 3; ++i)
                w(static_cast<py::ssize_t>(k), static_cast<py::ssize_t>(i)) = known && c.result.fitted[i][k];
            return a;
          }, "(M, 3) bool: voltage V_i of point m entered the fit (points.csv's V*_fitted); all "
             "False when the fit is not usable.")
      .def("model", [](const PyCalibration& c, const ArrayLike& theta_deg,
                       const std::optional<ArrayLike>& d_ratio) {
            usable_or_throw(c);
            const std::vector<double> t = finite_values(as_array(theta_deg.obj, "theta_deg", 1), "theta_deg");
            std::vector<double> r(t.size(), 1.0);
            if (d_ratio) {
              r = finite_values(as_array(d_ratio->obj, "d_ratio", 1), "d_ratio");
              if (r.size() != t.size())
                throw py::value_error(fmt::format("d_ratio: {} values for {} angles", r.size(), t.size()));
            }
            std::vector<double> v(3 * t.size());
            for (std::size_t k = 0; k < t.size(); ++k)
              for (int i = 0; i < 3; ++i)
                v[3 * k + static_cast<std::size_t>(i)] =
                    eq15_voltage(c.result.fit.params, c.options.volts_per_decade, i, t[k], r[k]);
            return finite_result(take(std::move(v), {static_cast<py::ssize_t>(t.size()), 3}), "model");
          }, py::arg("theta_deg"), py::arg("d_ratio") = py::none(),
          "The fitted Eq. 15 at polarization angles theta_deg ((N,) degrees): (N, 3) volts "
          "(model_curve.csv is model(np.arange(721) * 0.5)). d_ratio ((N,), default 1) scales d "
          "as the drift corrections do. Raises polrig.CalibrationError when the fit is not usable "
          "and RuntimeError where Eq. 15 is undefined (1 + d_ratio·c_j·cos(2θ + α_j) ≤ 0 or "
          "1 − d_ratio·c_h·cos(2θ + α_h) ≤ 0), as the CLI refuses to write a non-finite "
          "model_curve.csv.")
      .def_property_readonly("errors", [](const PyCalibration& c) {
            const auto& e = c.result.errors;
            py::dict d;
            d["theta_ref_deg"] = error_column(e, "errors['theta_ref_deg']", [](const AngleErrors& x) { return x.theta_ref_deg; });
            std::vector<std::int64_t> section(e.size());
            for (std::size_t n = 0; n < e.size(); ++n) section[n] = e[n].section;
            d["section"] = take(std::move(section));
            d["err12_deg"] = error_column(e, "errors['err12_deg']", [](const AngleErrors& x) { return x.e12_deg; });
            d["err13_deg"] = error_column(e, "errors['err13_deg']", [](const AngleErrors& x) { return x.e13_deg; });
            d["err23_deg"] = error_column(e, "errors['err23_deg']", [](const AngleErrors& x) { return x.e23_deg; });
            d["errsec_deg"] = error_column(e, "errors['errsec_deg']", [](const AngleErrors& x) { return x.esec_deg; });
            d["d"] = error_column(e, "errors['d']", [](const AngleErrors& x) { return x.d; });
            return d;
          }, "errors.csv as {column: (M,) array}: theta_ref_deg, section (int64), err12_deg, "
             "err13_deg, err23_deg, errsec_deg (θ − reference wrapped to [−90°, 90°), degrees) "
             "and d. Empty arrays when the fit is not usable.")
      .def_property_readonly("accuracy", [](const PyCalibration& c) { return accuracy_dict(c.result.accuracy); },
                             "accuracy.csv as {'theta12', 'theta13', 'theta23', 'theta_sec': "
                             "AngleAccuracy (max_deg, min_deg, accuracy_deg)}.")
      .def("usable", [](const PyCalibration& c) { return c.result.usable(); },
           "True when the fit converged and the parameters can be used.")
      .def("replacement", [](const PyCalibration& c) {
            usable_or_throw(c);
            return replacement_list(replacement_analysis(
                c.result.params, CalibrationParams::theory(c.options.film_axis_deg),
                c.options.volts_per_decade, c.result.points));
          }, "replacement.csv (§4.6, Fig. 21): [(label, mask, accuracy_deg)] for the 16 subsets of "
             "{α, k, kv, kd} put back to their theory values (for the rig's film axes); mask bit 0 "
             "α, 1 k, 2 kv, 3 kd; accuracy_deg is θ_sec's, degrees. Raises polrig.CalibrationError "
             "when the fit is not usable.")
      .def("to_yaml", [](const PyCalibration& c) {
            return params_to_yaml(usable_or_throw(c).result, c.options.volts_per_decade);
          }, "params.yaml's text, as `polrig calibrate` writes it (read back by polrig.read_params "
             "and a rig's device.truth_from). Raises polrig.CalibrationError when the fit is not "
             "usable, as the CLI refuses to write it.")
      .def("save", [](const PyCalibration& c, const std::filesystem::path& path) {
            write_text_file(path, params_to_yaml(usable_or_throw(c).result, c.options.volts_per_decade));
          }, py::arg("path"), "Writes to_yaml() to a file (params.yaml); path: str or os.PathLike. Raises "
             "polrig.CalibrationError when the fit is not usable, RuntimeError naming the path when "
             "the file cannot be written.")
      .def("__repr__", [](const PyCalibration& c) {
        const CalibrationResult& r = c.result;
        if (!r.usable())
          return fmt::format("<polrig.CalibrationResult {}: not usable: {}>", method_name(r.method),
                             r.fit.summary.brief_report());
        return fmt::format("<polrig.CalibrationResult {}: θ_sec ±{:.5f}°, {} observations, d_a = {}>",
                           method_name(r.method), r.accuracy[kThetaSec].accuracy_deg(),
                           r.fit.summary.observations, r.d_a);
      });
}

void bind_measured(py::module_& m) {
  py::class_<PyMeasured>(m, "MeasuredData", "Voltages read from a simulate folder or a CSV (docs/formats.md, \"Measured data\").")
      .def_property_readonly("origin", [](const PyMeasured& d) { return d.data.origin; }, "The CSV read.")
      .def_property_readonly("theta_R_deg", [](const PyMeasured& d) -> py::object {
            if (!d.have_angles) return py::none();
            std::vector<double> v;
            for (const StopVoltages& s : d.data.stops) v.push_back(s.theta_R_deg);
            return finite_result(take(std::move(v)), "theta_R_deg");
          }, "(N,) table angle of each row, degrees; None when the file has no theta_R_deg column "
             "(read_voltages).")
      .def_property_readonly("V", [](const PyMeasured& d) {
            std::vector<std::array<double, 3>> rows;
            for (const StopVoltages& s : d.data.stops) rows.push_back(s.V);
            return finite_result(rows_array(rows), "V");
          }, "(N, 3) pair voltages V1, V2, V3, volts.")
      .def_property_readonly("utc", [](const PyMeasured& d) -> py::object {
            if (d.data.utc.empty()) return py::none();
            std::vector<std::int64_t> ns;
            for (const UtcTime& t : d.data.utc) ns.push_back(std::llround(t.unix_s * 1e9));
            return take(std::move(ns)).attr("view")("datetime64[ns]");
          }, "(N,) datetime64[ns] UTC of each row (the utc column), or None without it.")
      .def_property_readonly("t_s", [](const PyMeasured& d) -> py::object {
            if (d.data.t_s.empty()) return py::none();
            return finite_result(take(std::vector<double>(d.data.t_s)), "t_s");
          }, "(N,) seconds since the first stop (a time-dependent source's stops.csv), or None.")
      .def_property_readonly("rig", [](const PyMeasured& d) -> py::object {
            if (!d.rig) return py::none();
            return py::cast(*d.rig);
          }, "The dataset's rig (its rig.yaml, a polrig.Rig; a new copy on each access), or None.")
      .def("__len__", [](const PyMeasured& d) { return d.data.stops.size(); })
      .def("__repr__", [](const PyMeasured& d) {
        return fmt::format("<polrig.MeasuredData {}: {} rows{}{}>", d.data.origin, d.data.stops.size(),
                           d.data.utc.empty() ? "" : ", utc", d.data.rig ? ", rig.yaml" : "");
      });

  m.def("read_measured", [](const std::filesystem::path& path) { return measured_of(read_measured(path)); },
        py::arg("path"),
        "Reads voltages to calibrate, as `polrig calibrate INPUT` does (path: str or os.PathLike): a "
        "folder written by "
        "`polrig simulate` (its stops.csv and rig.yaml) or a CSV with theta_R_deg,V1,V2,V3 "
        "(degrees, volts) and optionally utc (ISO 8601, Z). Returns a MeasuredData. Raises "
        "polrig.DataError naming the file, the line and the column (polrig.RigError for the "
        "dataset's rig.yaml).");
  m.def("read_voltages", [](const std::filesystem::path& path) {
          PyMeasured d = measured_of(read_voltages(path));
          d.have_angles = !d.data.stops.empty() && !std::isnan(d.data.stops.front().theta_R_deg);
          return d;
        }, py::arg("path"),
        "Reads voltages to apply parameters to, as `polrig apply` does (path: str or os.PathLike): a "
        "CSV with V1,V2,V3 "
        "(volts) and optionally theta_R_deg (degrees). Returns a MeasuredData. Raises "
        "polrig.DataError naming the file, the line and the column.");
}

}  // namespace

void bind_calibration(py::module_& m) {
  bind_params(m);
  bind_result(m);
  bind_measured(m);

  m.def("calibrate",
        [](const ArrayLike& theta_R_deg, const ArrayLike& V, const std::string& method,
           std::optional<double> d_a, const py::object& rig, double nc_threshold, int nc_min_points,
           const std::optional<ArrayLike>& film_axes_deg, std::optional<double> volts_per_decade,
           const std::string& drift, const py::object& utc, const std::optional<ArrayLike>& t_s,
           const std::optional<ArrayLike>& site, int max_iterations, int max_evaluations,
           double function_tolerance, double parameter_tolerance, double gradient_tolerance,
           double min_singular_ratio) {
          FitOptions fit;
          fit.max_iterations = max_iterations;
          fit.max_evaluations = max_evaluations;
          fit.function_tolerance = function_tolerance;
          fit.parameter_tolerance = parameter_tolerance;
          fit.gradient_tolerance = gradient_tolerance;
          fit.min_singular_ratio = min_singular_ratio;
          return run_calibrate(theta_R_deg.obj, V.obj, method, d_a, rig, nc_threshold, nc_min_points,
                               or_none(film_axes_deg), volts_per_decade, drift, utc, or_none(t_s),
                               or_none(site), fit);
        },
        py::arg("theta_R_deg"), py::arg("V"), py::kw_only(), py::arg("method") = "cs-nc",
        py::arg("d_a") = py::none(), py::arg("rig") = py::none(),
        py::arg("nc_threshold") = NoncontinuousRule{}.min_relative_slope,
        py::arg("nc_min_points") = NoncontinuousRule{}.min_points,
        py::arg("film_axes_deg") = py::none(), py::arg("volts_per_decade") = py::none(),
        py::arg("drift") = "none", py::arg("utc") = py::none(), py::arg("t_s") = py::none(),
        py::arg("site") = py::none(), py::arg("max_iterations") = FitOptions{}.max_iterations,
        py::arg("max_evaluations") = FitOptions{}.max_evaluations,
        py::arg("function_tolerance") = FitOptions{}.function_tolerance,
        py::arg("parameter_tolerance") = FitOptions{}.parameter_tolerance,
        py::arg("gradient_tolerance") = FitOptions{}.gradient_tolerance,
        py::arg("min_singular_ratio") = FitOptions{}.min_singular_ratio,
        R"doc(Calibrates Eq. 15 on table stops, as `polrig calibrate INPUT --method METHOD`.

theta_R_deg: (N,) table angle of each stop, degrees.
V: (N, 3) pair voltages V1, V2, V3 at each stop, volts (|V| ≤ 100 V). Rows with the same angle are
    repeated measurements of one stop (averaged for the CS methods).
method: one calibration type per call: 'section' (type 1: the raw stops), 'cs' (type 2:
    central-symmetry points), 'cs-nc' (type 3: CS points, noncontinuous selection) or 'nc'
    (outdoors: the raw stops, noncontinuous selection). The CLI's --method all is a loop over
    ('section', 'cs', 'cs-nc').
d_a: the rig's stated degree of polarization for the decoupling, in (0, 1); default: the rig's
    device.d when `rig` is given, else the largest fitted c_m (the best ideal film).
rig: a polrig.Rig describing the sensor (film axes, amplifier scale, d; a sky rig also the site and
    first stop's time for the drift), as the CLI's --rig or a dataset's rig.yaml; default: the
    default rig's sensor and no stated d.
nc_threshold: noncontinuous rule: keep a voltage where |dV/dθ| ≥ this × its largest slope, [0, 1].
nc_min_points: noncontinuous rule: keep at least this many points per voltage, [6, 100000].
film_axes_deg: (6,) film axes in degrees, overriding the rig's device.film_axes_deg.
volts_per_decade: the log amplifier's scale (V per decade), overriding the rig's.
drift: sun-drift correction of an outdoor run (methods 'nc' and 'section' only): 'none',
    'angle', 'per-stop' or 'linear' (--drift). Needs the stops' times, utc= or (a sky rig) t_s=,
    and the observer, site= or a sky rig's site.
utc: (N,) UTC of each stop: ISO 8601 strings with Z, aware datetimes or datetime64.
t_s: (N,) seconds of each stop since the sky rig's sky.first_stop_utc (a sky simulate's t_s).
site: (lat_deg, lon_deg) or (lat_deg, lon_deg, height_m) of the observer (--site): latitude in
    [-90, 90] north positive, longitude in [-180, 180] east positive, height above the WGS-84
    ellipsoid in m (default 0).
max_iterations, max_evaluations, function_tolerance, parameter_tolerance, gradient_tolerance,
min_singular_ratio: the Levenberg–Marquardt limits (calib/fit.h FitOptions; the CLI's defaults).

Returns a CalibrationResult. A fit that fails is data, not an exception: result.usable() is False
and result.fit says why (the CLI refuses such a result instead).
Raises ValueError for bad arguments (shapes, non-finite values, an unknown method or drift, d_a
outside (0, 1), drift with a CS method, a sky rig with a CS method); polrig.DataError for voltages
no ADC gives and for drift without times or site; polrig.CalibrationError when the stops cannot
form the points (a stop without its CS partner). The GIL is released during the fit.)doc");

  m.def("replacement_analysis",
        [](const CalibrationParams& calibrated, const CalibrationParams& theory,
           const ArrayLike& theta_ref_deg, const ArrayLike& V, const std::optional<ArrayLike>& d_ratio,
           double volts_per_decade) {
          const std::vector<EvalPoint> points = eval_points(theta_ref_deg.obj, V.obj, or_none(d_ratio));
          const double v_dec = positive_finite(volts_per_decade, "volts_per_decade");
          std::vector<Replacement> rep;
          {
            py::gil_scoped_release release;
            rep = replacement_analysis(calibrated, theory, v_dec, points);
          }
          return replacement_list(rep);
        },
        py::arg("calibrated"), py::arg("theory"), py::arg("theta_ref_deg"), py::arg("V"),
        py::kw_only(), py::arg("d_ratio") = py::none(),
        py::arg("volts_per_decade") = Electronics{}.volts_per_decade,
        R"doc(The replacement analysis (Wang et al. 2019 §4.6, Fig. 21; replacement.csv).

calibrated, theory: CalibrationParams (theory: CalibrationParams.theory(film_axes_deg)).
theta_ref_deg: (M,) reference angles of the points, degrees; V: (M, 3) their voltages, volts
    (a CalibrationResult's theta_ref_deg and V).
d_ratio: (M,) the light's d over d at the first stop (default 1).
volts_per_decade: the log amplifier's scale, V per decade.
Returns [(label, mask, accuracy_deg)] for the 16 subsets of {α, k, kv, kd} put back to theory:
label 'none', 'α', 'k-kv', ...; mask bit 0 α, 1 k, 2 kv, 3 kd; accuracy_deg θ_sec's, degrees.)doc");
}

}  // namespace polrig::python
