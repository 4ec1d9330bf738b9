// Commands that calibrate: calibrate, apply, study calibration.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <optional>
#include <utility>

#include <fmt/format.h>

#include "cli.h"
#include "polrig/calib/angles.h"
#include "polrig/calib/pipeline.h"
#include "polrig/calib/rig_options.h"
#include "polrig/calib/stop_corrections.h"
#include "polrig/io/csv.h"
#include "polrig/io/measured.h"
#include "polrig/io/params_yaml.h"
#include "polrig/io/plot.h"
#include "polrig/report/calibration_reports.h"
#include "polrig/report/dofp_calibration_report.h"
#include "polrig/report/four_camera_calibration_report.h"
#include "polrig/io/dofp_dataset.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/sky/drift.h"
#include "polrig/study/calibration_trials.h"
#include "polrig/units.h"

namespace polrig::cli {
namespace fs = std::filesystem;

namespace {

// Settings of the calibration itself, shared by calibrate and study calibration.
struct CalibrationSettings {
  std::optional<double> d_a;
  double nc_threshold = NoncontinuousRule{}.min_relative_slope;
  int nc_min_points = NoncontinuousRule{}.min_points;
  // The noncontinuous rule's options, to tell whether they were given (--method dofp refuses them).
  CLI::Option* nc_threshold_option = nullptr;
  CLI::Option* nc_min_points_option = nullptr;

  void add_to(CLI::App& app) {
    app.add_option("--d-a", d_a, "the rig's stated degree of polarization d_a for decoupling")
        ->check(CLI::Validator(
            [](const std::string& s) -> std::string {
              double v = 0;
              if (!CLI::detail::lexical_cast(s, v) || !(v > 0 && v < 1))
                return "expected a degree of polarization in (0, 1), got " + s;
              return {};
            },
            "(0, 1)"));
    nc_threshold_option = app.add_option("--nc-threshold", nc_threshold,
                   "noncontinuous rule: keep a voltage where |dV/dθ| ≥ this × its largest slope")
        ->check(finite_range(kNcThresholdMin, kNcThresholdMax))
        ->capture_default_str();
    nc_min_points_option = app.add_option("--nc-min-points", nc_min_points,
                   "noncontinuous rule: keep at least this many points per voltage")
        ->check(CLI::Range(kNcMinPointsMin, kNcMinPointsMax))
        ->capture_default_str();
  }
  CalibrationOptions options(const Rig& rig, std::optional<double> rig_d) const {
    CalibrationOptions o = calibration_options(rig, d_a ? d_a : rig_d, {nc_threshold, nc_min_points});
    o.d_a_source = d_a ? "--d-a" : "the rig's device.d";
    return o;
  }
};

// A DataError naming the file, line, column and value for a voltage no ADC can give.
void check_adc_range(const StopVoltages& s) {
  const std::string problem = adc_range_problem(s.V);
  if (!problem.empty()) throw DataError(fmt::format("{}: {}", s.label, problem));
}

// --method four-camera's geometry: a file, or the geometric calibration's option.
struct FourCameraGeometrySettings {
  std::string file;
  int distortion_terms = GeometryFitOptions{}.distortion_terms;
  CLI::Option* distortion_terms_option = nullptr;
  static bool given(const CLI::Option* o) { return o && o->count() > 0; }
};

// The sun-drift settings of an outdoor calibration (spec sky-and-compasses.md §1.4).
struct DriftSettings {
  std::string mode = "none";
  std::string site;  // "LAT,LON" in degrees, north and east positive
};

Site parse_drift_site(const std::string& text) {
  const auto comma = text.find(',');
  Site s;
  if (comma == std::string::npos || !CLI::detail::lexical_cast(text.substr(0, comma), s.lat_deg) ||
      !CLI::detail::lexical_cast(text.substr(comma + 1), s.lon_deg) || site_problem(s))
    throw DataError(fmt::format("--site {}: expected LAT,LON in degrees (north and east positive, "
                                "|LAT| ≤ 90, |LON| ≤ 180), e.g. 38.879167,121.543889", text));
  return s;
}

// The per-stop corrections for --drift: the stops' times from the data's utc column, or from a
// sky rig's sky.first_stop_utc plus the data's t_s column (a simulate folder of a sky rig); the
// sun from the ephemeris at --site, else at the sky rig's site. Empty for --drift none.
StopCorrections drift_of(const MeasuredData& data, const Rig& rig, const DriftSettings& drift) {
  const std::optional<DriftMode> mode = parse_drift_mode(drift.mode);
  if (!mode)
    throw DataError(fmt::format("--drift {}: expected none, angle, per-stop or linear", drift.mode));
  if (*mode == DriftMode::None) return {};
  DriftRequest request;
  request.mode = *mode;
  request.utc = data.utc;
  request.t_s = data.t_s;
  request.origin = data.origin;
  request.drift_option = "--drift " + drift.mode;
  request.site_option = "--site LAT,LON";
  request.times_missing = fmt::format("{} has no 'utc' column giving each stop's time (ISO 8601, "
                                      "Z; see docs/formats.md, \"Measured data\")", data.origin);
  try {
    const StopTimes times = drift_stop_times(request, rig);
    std::optional<Site> site;
    if (!drift.site.empty()) site = parse_drift_site(drift.site);
    return sun_drift_corrections(request, times, site, "--site " + drift.site, rig);
  } catch (const std::invalid_argument& e) {
    throw DataError(e.what());
  }
}

// `calibrate DIR --method dofp`: H17's two-step calibration of a camera dataset (report/
// dofp_calibration_report.h), whose rig.yaml must describe an instrument that takes frames.
void run_calibrate_dofp(const std::string& input, const std::string& rig_path, const CalibrationSettings& settings,
                        const DriftSettings& drift, bool view_projection, const OutputOptions& out) {
  if (!rig_path.empty()) throw DataError("--rig: --method dofp reads the camera from the dataset (its truth.exr and rig.yaml)");
  if (drift.mode != "none") throw DataError(fmt::format("--drift {}: --method dofp calibrates indoors (no sun drift)", drift.mode));
  if (!drift.site.empty()) throw DataError(fmt::format("--site {}: --method dofp calibrates indoors (no sun)", drift.site));
  if (settings.d_a) throw DataError(fmt::format("--d-a {}: --method dofp fits the source's DoP itself", *settings.d_a));
  for (const auto& [name, option] : {std::pair{"--nc-threshold", settings.nc_threshold_option},
                                     std::pair{"--nc-min-points", settings.nc_min_points_option}})
    if (option && option->count() > 0)
      throw DataError(fmt::format("{} {}: --method dofp has no noncontinuous rule (it applies to nc and cs-nc)",
                                  name, option->as<std::string>()));
  DofpCalibrationOptions options;
  options.step2.view_projection = view_projection;
  const DofpCalibration c = calibrate_dofp_folder(input, options, progress());
  OutputDir d = out.open();
  write_manifest(d.staging(), {command_line(), nullptr, report_dofp_calibration(d.staging(), c, out.plots()), {input}});
  finish(d);
  std::cout << fmt::format("dofp: {} of {} cells usable; Table 1 at intensity {} (max / mean / std, deg):\n",
                           c.step2.usable_cells, c.step2.cells.size(), c.table1.intensity);
  for (const DofpOrientationRow& row : c.table1.rows)
    std::cout << fmt::format("  {:6s} {:.4f} / {:.4f} / {:.4f}\n", row.name, row.max_deg, row.mean_deg, row.std_deg);
  if (view_projection)
    std::cout << fmt::format("  psi0 {:.9g} deg for the image: {}\n", c.step2.psi0_deg, c.step2.psi0_fit.brief_report());
}

// `calibrate DIR --method four-camera`: W16's radiometric and polarizer-angle calibration of a
// four-camera dataset with raw frames (report/four_camera_calibration_report.h).
void run_calibrate_four_camera(const std::string& input, const std::string& rig_path,
                               const CalibrationSettings& settings, const DriftSettings& drift, bool view_projection,
                               const FourCameraGeometrySettings& geometry, const OutputOptions& out) {
  const std::string m = "--method four-camera";
  if (!rig_path.empty())
    throw DataError(fmt::format("--rig {}: {} reads the sensor from the dataset (its rig.yaml and truth.yaml)", rig_path, m));
  if (drift.mode != "none") throw DataError(fmt::format("--drift {}: {} calibrates indoors (no sun drift)", drift.mode, m));
  if (!drift.site.empty()) throw DataError(fmt::format("--site {}: {} calibrates indoors (no sun)", drift.site, m));
  if (settings.d_a) throw DataError(fmt::format("--d-a {}: {} fits the source's DoP itself", *settings.d_a, m));
  for (const auto& [name, option] : {std::pair{"--nc-threshold", settings.nc_threshold_option},
                                     std::pair{"--nc-min-points", settings.nc_min_points_option}})
    if (option && option->count() > 0)
      throw DataError(fmt::format("{} {}: {} has no noncontinuous rule (it applies to nc and cs-nc)", name,
                                  option->as<std::string>(), m));
  if (view_projection)
    throw DataError(fmt::format("--view-projection: a DoFP camera's step-2 option; {} always projects the port "
                                "polarizer along each view",
                                m));
  std::optional<fs::path> geometry_file;
  if (!geometry.file.empty()) geometry_file = geometry.file;
  GeometryFitOptions geometry_options;
  geometry_options.distortion_terms = geometry.distortion_terms;
  if (geometry_file && geometry.given(geometry.distortion_terms_option))
    throw DataError(fmt::format("--distortion-terms {}: the geometric calibration's option, but --geometry {} gives the "
                                "geometry",
                                geometry.distortion_terms, geometry.file));
  OutputDir d = out.open();
  const FourCameraCalibrationRun run =
      calibrate_four_camera_folder(input, geometry_file, {}, progress(), geometry_options);
  std::vector<std::string> inputs{input};
  if (geometry_file) inputs.push_back(geometry.file);
  write_manifest(d.staging(), {command_line(), nullptr, report_four_camera_calibration(d.staging(), run, out.plots()), inputs});
  finish(d);
  const FourCameraCalibration& c = run.calibration;
  std::cout << fmt::format("four-camera: {} unpolarized levels, {} polarized stops; geometry from {}\n", run.levels,
                           run.polarized, run.file.geometry_from);
  if (run.geometry) std::cout << run.geometry->fit.summary.brief_report();
  for (std::size_t j = 0; j < 4; ++j) {
    const CameraRadiometry& r = c.radiometry.camera[j];
    std::cout << fmt::format("  camera {}: K = {:.3f} ± {:.3f} DN, b = {:.3f} ± {:.3f} DN ({} levels, rms {:.3g} DN); "
                             "eps = {:.4f} ± {:.4f}°\n",
                             j + 1, r.K, r.K_se, r.b, r.b_se, r.levels_used, r.residual_rms_DN, c.polarizer.eps_deg[j],
                             c.polarizer.eps_se_deg[j]);
  }
  const PolarizerFit& p = c.polarizer;
  std::cout << fmt::format("  polarizer fit: {}, {} iterations, rank {} of {}; AoP residual rms {:.4f}° (nominal axes "
                           "{:.4f}°); psi_0 = {:.4f}°, source DoP {:.5f}\n",
                           termination_name(p.summary.termination), p.summary.iterations, p.rank, p.unknowns,
                           p.residual_rms_deg, p.residual_rms_before_deg, p.psi0_deg, p.dop);
  if (run.truth && run.truth->radiometric && run.truth->polarizer) {
    const FourCameraCalibrationFile& t = *run.truth;
    double worst_K = 0, worst_b = 0, worst_eps = 0;
    for (std::size_t j = 0; j < 4; ++j) {
      worst_K = std::max(worst_K, std::abs(c.radiometry.camera[j].K / t.model.K[j] - 1));
      worst_b = std::max(worst_b, std::abs(c.radiometry.camera[j].b - t.model.b[j]));
      worst_eps = std::max(worst_eps, std::abs(p.eps_deg[j] - (t.eps_deg[j] - t.eps_deg[0])));
    }
    std::cout << fmt::format("  against truth.yaml: |ΔK/K| ≤ {:.2e}, |Δb| ≤ {:.3f} DN, |Δeps| ≤ {:.4f}° (errors.csv)\n",
                             worst_K, worst_b, worst_eps);
  }
}

void run_calibrate(const std::string& input, const std::string& method_text,
                   const std::string& rig_path, const CalibrationSettings& settings,
                   const DriftSettings& drift, bool view_projection, const FourCameraGeometrySettings& geometry,
                   const OutputOptions& out) {
  if (method_text == "four-camera")
    return run_calibrate_four_camera(input, rig_path, settings, drift, view_projection, geometry, out);
  if (method_text == "unit-array") {
    const std::string m = "--method unit-array";
    if (drift.mode != "none") throw DataError(fmt::format("--drift {}: {} fits against the ephemeris sun itself", drift.mode, m));
    if (!drift.site.empty()) throw DataError(fmt::format("--site {}: {} takes the site from the dataset's rig", drift.site, m));
    if (settings.d_a) throw DataError(fmt::format("--d-a {}: {} reads each unit's own DoP", *settings.d_a, m));
    if (view_projection) throw DataError(fmt::format("--view-projection: a DoFP camera's step-2 option, not {}", m));
    if (!geometry.file.empty()) throw DataError(fmt::format("--geometry {}: the four cameras' geometry, not {}", geometry.file, m));
    if (geometry.given(geometry.distortion_terms_option))
      throw DataError(fmt::format("--distortion-terms {}: the four cameras' geometric calibration, not {}",
                                  geometry.distortion_terms, m));
    for (const auto& [name, option] : {std::pair{"--nc-threshold", settings.nc_threshold_option},
                                       std::pair{"--nc-min-points", settings.nc_min_points_option}})
      if (option && option->count() > 0)
        throw DataError(fmt::format("{} {}: {} has no noncontinuous rule (it applies to nc and cs-nc)", name,
                                    option->as<std::string>(), m));
    return run_calibrate_unit_array(input, rig_path, out);
  }
  if (!geometry.file.empty())
    throw DataError(fmt::format("--geometry {}: the four cameras' geometry (--method four-camera), not --method {}",
                                geometry.file, method_text));
  if (geometry.given(geometry.distortion_terms_option))
    throw DataError(fmt::format("--distortion-terms {}: the four cameras' geometric calibration (--method four-camera), "
                                "not --method {}",
                                geometry.distortion_terms, method_text));
  if (method_text == "dofp") return run_calibrate_dofp(input, rig_path, settings, drift, view_projection, out);
  if (view_projection)
    throw DataError(fmt::format("--view-projection: a DoFP camera's step-2 model (--method dofp), not --method {}",
                                method_text));
  std::vector<CalibrationMethod> methods;
  if (method_text == "all") {
    methods.assign(kAllMethods.begin(), kAllMethods.end());
  } else if (auto m = parse_method(method_text)) {
    methods.push_back(*m);
  } else {
    throw DataError(fmt::format("--method {}: expected section, cs, cs-nc, nc, all, dofp, four-camera or unit-array", method_text));
  }
  if (drift.mode != "none")
    for (CalibrationMethod m : methods)
      if (!uses_raw_stops(m))
        throw DataError(fmt::format("--drift {} needs --method nc or section (the raw stops), not "
                                    "{}: a CS point mixes two times", drift.mode, method_text));
  const MeasuredData data = read_measured(input, "calibrate --method " + method_text);
  for (const StopVoltages& s : data.stops) check_adc_range(s);
  // The sensor description (film axes, amplifier scale): --rig, else the dataset's rig.yaml,
  // else the default rig. d_a: --d-a, else the dataset rig's d.
  std::optional<LoadedRig> given;
  if (!rig_path.empty()) {
    given = load_rig(rig_path);
    require_instrument(given->rig, Instrument::kPairVoltages, "calibrate --method " + method_text,
                       given->origin);
  }
  const Rig rig = given ? given->rig : data.rig ? *data.rig : Rig{};
  // A sky dataset's light turns with the sun during the run: a CS point would mix two times.
  if (rig.light->has(Source::kTimeDependent))
    for (CalibrationMethod m : methods)
      if (!uses_raw_stops(m))
        throw DataError(fmt::format("--method {} on {}: its rig's light is the sky, which drifts "
                                    "with the sun during the run; use --method nc --drift per-stop "
                                    "(or angle, linear, none)", method_text, data.origin));
  const StopCorrections corrections = drift_of(data, rig, drift);
  const std::optional<double> rig_d =
      given ? std::optional<double>(given->rig.device.d)
            : data.rig ? std::optional<double>(data.rig->device.d) : std::nullopt;

  OutputDir dir = out.open();
  std::vector<CalibrationResult> results;
  for (CalibrationMethod m : methods) {
    CalibrationOptions o = settings.options(rig, rig_d);
    o.method = m;
    o.corrections = corrections;
    CalibrationResult r;
    try {
      r = calibrate(data.stops, o);
    } catch (const CalibrationError& e) {
      throw CalibrationError(fmt::format("method {}: {}", method_name(m), e.what()));
    }
    if (!r.usable())
      throw CalibrationError(fmt::format("method {}: the fit is not usable: {}", method_name(m),
                                         r.fit.summary.brief_report()));
    results.push_back(std::move(r));
  }
  Manifest base{command_line(), given ? &*given : nullptr, {}, {data.origin}};
  if (!given && data.rig) base.inputs.push_back(data.rig_origin);
  const auto options_of = [&](CalibrationMethod m) {
    CalibrationOptions o = settings.options(rig, rig_d);
    o.method = m;
    return o;
  };
  if (results.size() == 1) {
    Manifest m = base;
    m.files = report_calibration(dir.staging(), results[0], options_of(results[0].method), out.plots());
    write_manifest(dir.staging(), m);
  } else {
    for (const CalibrationResult& r : results) {
      const fs::path sub = dir.staging() / std::string(method_name(r.method));
      fs::create_directory(sub);
      Manifest m = base;
      m.files = report_calibration(sub, r, options_of(r.method), out.plots());
      write_manifest(sub, m);
    }
    Manifest m = base;
    m.files = report_calibration_comparison(dir.staging(), results, out.plots());
    write_manifest(dir.staging(), m);
  }
  finish(dir);
  for (const CalibrationResult& r : results)
    if (r.fit.summary.observations <= FitParams::kCount)
      std::cerr << fmt::format("polrig: note: {} fitted {} voltages to 18 unknowns: no redundancy, so "
                               "its accuracy on the fitted points and its standard errors say "
                               "nothing\n", method_name(r.method), r.fit.summary.observations);
  for (const CalibrationResult& r : results)
    std::cout << fmt::format("{:8s} accuracy θ_sec ±{:.5f}°  (θ12 ±{:.5f}, θ13 ±{:.5f}, θ23 ±{:.5f}); "
                             "{} observations, residual RMS {:.4f} mV, d_a = {} ({})\n",
                             method_name(r.method), r.accuracy[kThetaSec].accuracy_deg(),
                             r.accuracy[kTheta12].accuracy_deg(), r.accuracy[kTheta13].accuracy_deg(),
                             r.accuracy[kTheta23].accuracy_deg(), r.fit.summary.observations,
                             r.fit.residual_rms_V * 1e3, r.d_a, r.d_a_source)
              << fmt::format("{:8s} fit: {}\n", "", r.fit.summary.brief_report());
}

// The angles of one voltage row and the d of the section's pair; a DataError naming the file,
// line, column and value for a voltage no ADC can give, one that no light ratio can give, or a
// row without a finite angle.
MeasuredAngles angles_of_row(const StopVoltages& s, const LoadedParams& p, const Electronics& e) {
  MeasuredAngles a = measured_angles(p.params, e, s.V);
  if (!a.problem.empty()) throw DataError(fmt::format("{}: {}", s.label, a.problem));
  return a;
}

void run_apply(const std::string& params_path, const std::string& voltages_path,
               const OutputOptions& out) {
  const LoadedParams p = read_params_yaml(params_path);
  const MeasuredData data = read_voltages(voltages_path);
  const bool have_reference = !std::isnan(data.stops.front().theta_R_deg);
  OutputDir dir = out.open(have_reference);
  Electronics e;
  e.volts_per_decade = p.volts_per_decade;
  std::string text = "row,theta_R_deg,theta12_deg,theta13_deg,theta23_deg,theta_sec_deg,section,d,error_deg\n";
  for (std::size_t n = 0; n < data.stops.size(); ++n) {
    const StopVoltages& s = data.stops[n];
    const MeasuredAngles m = angles_of_row(s, p, e);
    const SensorAngles& a = m.angles;
    const double err = have_reference ? axis_difference_deg(a.theta_sec_deg, s.theta_R_deg)
                                      : std::numeric_limits<double>::quiet_NaN();
    const double d = m.d;
    text += fmt::format("{},{},{},{},{},{},{},{},{}\n", n, s.theta_R_deg, a.theta12.theta_deg,
                        a.theta13.theta_deg, a.theta23.theta_deg, a.theta_sec_deg, a.section, d, err);
  }
  write_text_file(dir.staging() / "angles.csv", text);
  std::vector<DatasetFile> files{{"angles.csv", 1,
                                  "θ12, θ13, θ23, θ_sec, section and d for every row; error_deg = "
                                  "θ_sec − theta_R_deg when the input has theta_R_deg"}};
  if (have_reference && out.plots()) {
    Plot fig{"errors.png", "θ_sec − θ_R with the calibrated parameters", "θ_R (°)", "error (°)"};
    fig.series = {{"angles.csv", "$theta_R_deg:$error_deg", "θ_sec − θ_R", "linespoints lw 1.5 pt 7 ps 0.7"}};
    render_plots(dir.staging(), "plots.gp", {fig});
    files.push_back({"errors.png", 1, "θ_sec − θ_R against θ_R"});
  }
  write_manifest(dir.staging(), {command_line(), nullptr, files, {params_path, data.origin}});
  finish(dir);
}

}  // namespace

std::vector<Command> add_calibration_commands(CLI::App& root, CLI::App& study, int& threads) {
  std::vector<Command> commands;
  {
    auto* app = root.add_subcommand(
        "calibrate", "calibrate a simulate dataset or measured voltages (Eq. 15, three types; nc outdoors)");
    auto input = std::make_shared<std::string>();
    auto method = std::make_shared<std::string>("cs-nc");
    auto rig = std::make_shared<std::string>();
    auto settings = std::make_shared<CalibrationSettings>();
    auto drift = std::make_shared<DriftSettings>();
    auto out = std::make_shared<OutputOptions>();
    app->add_option("INPUT", *input, "a folder written by polrig simulate, or a CSV with "
                                     "theta_R_deg,V1,V2,V3 (volts) and optionally utc")->required();
    app->add_option("--method", *method, "section | cs | cs-nc | nc | all (nc: the raw stops, "
                                         "noncontinuous + section, as outdoors) | dofp (a DoFP camera "
                                         "dataset: H17's two steps) | four-camera (a four-camera dataset "
                                         "with raw frames: W16's gains, offsets and polarizer angles) | unit-array (a "
                                         "unit-array dataset: Z21's installation calibration of every unit's mounting)")->capture_default_str();
    app->add_option("--drift", drift->mode, "sun-drift correction of an outdoor run: none | angle | "
                                            "per-stop | linear (needs the stops' times and the site: a utc column and --site, or a sky rig's simulate folder)")
        ->capture_default_str();
    app->add_option("--site", drift->site, "the observer for --drift: LAT,LON in degrees (north, "
                                           "east positive)");
    app->add_option("--rig", *rig, "rig file describing the sensor (film axes, amplifier); "
                                   "default: the dataset's rig.yaml, else the default rig");
    auto view_projection = std::make_shared<bool>(false);
    app->add_flag("--view-projection", *view_projection,
                  "--method dofp: step 2's cells see the port polarizer along their views (a plane "
                  "polarizer's AoP off the axis) and Table 1 maps each cell's AoP back to the port "
                  "plane; off: H17's model (docs/physics.md §14)");
    auto geometry = std::make_shared<FourCameraGeometrySettings>();
    app->add_option("--geometry", geometry->file,
                    "--method four-camera: each camera's geometry from this calibration.yaml (or truth.yaml); "
                    "default: the geometric calibration of the dataset's checkerboard views, else (no views) "
                    "its truth.yaml");
    geometry->distortion_terms_option =
        app->add_option("--distortion-terms", geometry->distortion_terms,
                        "--method four-camera: the Kannala–Brandt terms k1 … kN the geometric calibration fits "
                        "(0–4; the rest held at 0: fewer extrapolate better beyond the boards, docs/physics.md §16.2)")
            ->check(CLI::Range(0, 4))
            ->capture_default_str();
    settings->add_to(*app);
    out->add_to(*app);
    add_threads_option(*app, threads);
    commands.push_back(
        {app, [=] {
           require_file_name(*app, "--rig", *rig);
           require_file_name(*app, "--geometry", geometry->file);
           run_calibrate(*input, *method, *rig, *settings, *drift, *view_projection, *geometry, *out);
         }});
  }
  {
    auto* app = root.add_subcommand("apply", "turn voltages into θ and d with calibrated parameters");
    auto params = std::make_shared<std::string>();
    auto voltages = std::make_shared<std::string>();
    auto out = std::make_shared<OutputOptions>();
    app->add_option("PARAMS", *params, "params.yaml written by polrig calibrate")->required();
    app->add_option("VOLTAGES", *voltages, "CSV with V1,V2,V3 (volts), optionally theta_R_deg")->required();
    out->add_to(*app);
    add_threads_option(*app, threads);
    commands.push_back({app, [=] { run_apply(*params, *voltages, *out); }});
  }
  {
    auto* app = study.add_subcommand(
        "calibration", "Monte-Carlo calibrations over noise and eccentricity, all three types");
    auto rig = std::make_shared<RigInput>();
    auto out = std::make_shared<OutputOptions>();
    auto trials = std::make_shared<int>(TrialSettings{}.trials);
    auto L_IS_max = std::make_shared<std::optional<double>>();
    auto L_S_max = std::make_shared<std::optional<double>>();
    auto settings = std::make_shared<CalibrationSettings>();
    rig->add_to(*app, true);
    out->add_to(*app);
    app->add_option("--trials", *trials, "number of simulated calibration runs")
        ->check(CLI::Range(1, kMaxTrials))->capture_default_str();
    app->add_option("--L-IS-max", *L_IS_max, "largest port offset drawn, mm (default: 2 × the rig's L_IS, at most 100)")
        ->check(finite_range(0.0, kMaxTrialOffsetMm, "mm"));  // the range of eccentricity.L_IS and L_S
    app->add_option("--L-S-max", *L_S_max, "largest sensor offset drawn, mm (default: 2 × the rig's L_S, at most 100)")
        ->check(finite_range(0.0, kMaxTrialOffsetMm, "mm"));  // the range of eccentricity.L_IS and L_S
    settings->add_to(*app);
    add_threads_option(*app, threads);
    commands.push_back({app, [=] {
      std::optional<LoadedRig> loaded;
      std::optional<TrialSettings> checked;
      on_every_rank([&] {  // a rank that cannot read the rig (another node's files) stops all
        loaded.emplace(rig->load());
        require_instrument(loaded->rig, Instrument::kPairVoltages, "study calibration", loaded->origin);
        checked.emplace(trial_settings_for(loaded->rig, *trials, *L_IS_max, *L_S_max,
                                           settings->options(loaded->rig, loaded->rig.device.d)));
      });
      const LoadedRig& r = *loaded;
      const TrialSettings& s = *checked;
      // Every rank checks the same input; rank 0 alone opens and writes the output, and
      // receives every trial in index order (docs/scale.md).
      std::optional<OutputDir> dir;
      on_rank_0([&] { dir.emplace(made_by{[&] { return out->open(); }}); });
      const std::vector<Trial> result = calibration_trials(r.rig, s, progress(), &ranks());
      on_rank_0([&] {
        write_manifest(dir->staging(), {command_line(), &r, report_calibration_trials(dir->staging(), result, out->plots())});
        finish(*dir);
      });
      if (!ranks().is_root()) return;
      for (const TrialSummary& t : summarize_trials(result)) {
        std::string ends;
        for (std::size_t k = 0; k < t.terminations.size(); ++k)
          if (t.terminations[k] > 0)
            ends += fmt::format("{}{} {}", ends.empty() ? "" : ", ", t.terminations[k],
                                termination_name(kAllTerminations[k]));
        std::cout << fmt::format("{:8s} median ±{:.5f}°  (5%: {:.5f}, 95%: {:.5f}; {} failed; fits: {})\n",
                                 method_name(t.method), t.median_deg, t.p05_deg, t.p95_deg,
                                 t.failed, ends);
      }
    }, true});
  }
  return commands;
}

}  // namespace polrig::cli
