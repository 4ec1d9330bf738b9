#include "polrig/report/four_camera_calibration_report.h"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "polrig/io/csv.h"
#include "polrig/io/four_camera_dataset.h"
#include "polrig/io/measured.h"
#include "polrig/io/plot.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/rig/rig.h"
#include "polrig/side_by_side.h"
#include "polrig/units.h"
#include "csv_cells.h"

namespace polrig {

namespace {

// The number of checkerboard views DIR holds (0 without checkerboard/).
std::size_t dataset_views(const std::filesystem::path& dir) {
  try {
    return read_checkerboard_views(dir).files.size();
  } catch (const std::runtime_error& e) {
    throw DataError(e.what());
  }
}

}  // namespace

FourCameraCalibrationRun calibrate_four_camera_folder(const std::filesystem::path& dir,
                                                      const std::optional<std::filesystem::path>& geometry_file,
                                                      FourCameraCalibrationOptions options, const Progress& progress,
                                                      const GeometryFitOptions& geometry_options) {
  FourCameraCalibrationRun run;
  std::string intensity_unit = "the level itself (no rig.yaml: intensity per level 1)";
  if (std::filesystem::exists(dir / "rig.yaml")) {
    const LoadedRig r = load_rig(dir / "rig.yaml");
    require_instrument(r.rig, Instrument::kCameraArray, "calibrate --method four-camera", r.origin);
    options.radiometric.saturation_DN = std::ldexp(1.0, r.rig.four_camera.adc_bits) - 1;
    if (r.rig.source.model == "cos4") {
      options.radiometric.intensity_per_level = r.rig.source.cos4.E_0;
      intensity_unit = fmt::format("source.E_0 = {} of {} (the sphere's intensity at level 1)", r.rig.source.cos4.E_0,
                                   r.origin);
    }
    run.truth_dop = r.rig.device.d;
  }
  FourCameraDataset ds;
  try {
    ds = read_four_camera_dataset(dir);
  } catch (const std::runtime_error& e) {
    throw DataError(e.what());
  }
  if (std::filesystem::exists(dir / "truth.yaml")) run.truth = read_four_camera_calibration(dir / "truth.yaml");
  FourCameraCalibrationFile geometry;
  std::string geometry_from;
  // The geometry: a file given, else the dataset's checkerboard views, else (a simulated dataset
  // without views) its truth.
  if (geometry_file) {
    geometry = read_four_camera_calibration(*geometry_file);
    geometry_from = geometry_file->string();
    if (!geometry.geometry_from.empty()) geometry_from += fmt::format(" (its geometry from: {})", geometry.geometry_from);
  } else if (const std::size_t views = dataset_views(dir); views > 0) {
    if (!four_camera_geometry_available())
      throw DataError(fmt::format("{}: {} checkerboard views, but this polrig was built without OpenCV, which the "
                                  "geometric calibration needs (-DPOLRIG_OPENCV=ON, Debian's libopencv-dev); give the "
                                  "geometry with --geometry FILE{}",
                                  dir.string(), views,
                                  run.truth ? fmt::format(" (e.g. {})", (dir / "truth.yaml").string()) : ""));
    try {
      run.geometry = calibrate_four_camera_geometry_folder(dir, geometry_options, progress);
    } catch (const std::invalid_argument& e) {
      throw DataError(fmt::format("{}: {}", dir.string(), e.what()));
    } catch (const DataError&) {
      throw;
    } catch (const std::runtime_error& e) {
      throw DataError(e.what());
    }
    const FourCameraGeometryFit& g = run.geometry->fit;
    if (!g.summary.usable())
      throw CalibrationError(fmt::format("{}: the geometric calibration is not usable:\n{}", dir.string(),
                                         g.summary.brief_report()));
    geometry.model.width = run.geometry->views.width;
    geometry.model.height = run.geometry->views.height;
    geometry.model.camera = g.camera;
    geometry.position_mm = g.position_mm;
    geometry_from = fmt::format("{}: the geometric calibration of its {} checkerboard views (OpenCV's fisheye model, "
                                "{} distortion terms; geometry.csv)",
                                (dir / "checkerboard").string(), views, geometry_options.distortion_terms);
  } else if (run.truth) {
    geometry = *run.truth;
    geometry_from = fmt::format("{}: the simulation's truth (no geometric calibration given: --geometry)",
                                (dir / "truth.yaml").string());
  } else {
    throw DataError(fmt::format("{}: no truth.yaml and no --geometry FILE: the calibration needs each camera's geometry",
                                dir.string()));
  }
  if (geometry.model.width != ds.width || geometry.model.height != ds.height)
    throw DataError(fmt::format("{}: {} × {} px, but the dataset {} has {} × {} px",
                                geometry_file  ? geometry_file->string()
                                : run.geometry ? (dir / "checkerboard" / "board.yaml").string()
                                               : (dir / "truth.yaml").string(),
                                geometry.model.width, geometry.model.height, dir.string(), ds.width, ds.height));

  // The raw frames, every stop's (a dataset without them is refused at its first stop), read side
  // by side and kept in stop order.
  std::vector<std::array<std::vector<std::uint16_t>, 4>> raw;
  std::vector<FourCameraFrames<std::uint16_t>> levels, polarized;
  progress.begin("calibrate four-camera: reading frames", static_cast<long long>(ds.stops.size()));
  raw.reserve(ds.stops.size());
  side_by_side_in_order(
      ds.stops.size(),
      [&](std::size_t s) {
        try {
          auto frames = read_four_camera_raw(ds, s);
          progress.advance();
          return frames;
        } catch (const std::runtime_error& e) {
          throw DataError(fmt::format(
              "{}: the calibration needs each stop's raw frames (`polrig simulate --layers all`): {}", dir.string(),
              e.what()));
        }
      },
      [&](std::array<std::vector<std::uint16_t>, 4>&& frames) { raw.push_back(std::move(frames)); });
  progress.finish();
  for (std::size_t s = 0; s < ds.stops.size(); ++s) {
    const FourCameraDatasetStop& st = ds.stops[s];
    FourCameraFrames<std::uint16_t> f{st.stop, st.theta_R_deg, st.intensity, {}};
    for (std::size_t j = 0; j < 4; ++j) f.f[j] = raw[s][j];
    (st.polarized ? polarized : levels).push_back(f);
  }
  run.levels = static_cast<int>(levels.size());
  run.polarized = static_cast<int>(polarized.size());
  if (levels.empty())
    throw DataError(fmt::format("{}: no unpolarized stop (schedule.unpolarized_levels): the radiometric calibration "
                                "needs the sphere's levels",
                                dir.string()));
  if (polarized.empty())
    throw DataError(fmt::format("{}: no polarized stop: the polarizer-angle calibration needs the polarized source "
                                "turned by the table",
                                dir.string()));
  try {
    run.calibration = calibrate_four_camera<std::uint16_t>(geometry.model.camera, ds.width, ds.height, levels, polarized,
                                                           options, progress);
  } catch (const std::invalid_argument& e) {
    throw DataError(fmt::format("{}: {}", dir.string(), e.what()));
  }
  const FourCameraCalibration& c = run.calibration;
  if (!c.polarizer.usable())
    throw CalibrationError(fmt::format("{}: the polarizer-angle fit is not usable: {}: {}", dir.string(),
                                       termination_name(c.polarizer.summary.termination), c.polarizer.summary.message));
  FourCameraCalibrationFile& f = run.file;
  f.model = c.model;
  f.polarizer_deg = c.options.nominal_deg;
  f.eps_deg = c.polarizer.eps_deg;
  f.position_mm = geometry.position_mm;
  f.radiometric = f.polarizer = true;
  const RadiometricOptions& ro = c.radiometry.options;
  f.radiometric_from = fmt::format(
      "{}: {} unpolarized stops, the mean over {} x {} px about each camera's principal point against the level; "
      "intensity = level x {}",
      dir.string(), run.levels, 2 * ro.window_half_px + 1, 2 * ro.window_half_px + 1, intensity_unit);
  double lo = 1e300, hi = -1e300;
  for (const auto& p : polarized) lo = std::min(lo, p.theta_R_deg), hi = std::max(hi, p.theta_R_deg);
  f.polarizer_from = fmt::format(
      "{}: {} polarized stops, theta_R {} to {} deg, {} virtual pixels near the principal point; gauge eps_1 = 0",
      dir.string(), run.polarized, lo, hi, c.polarizer.stops.empty() ? 0 : c.polarizer.summary.observations / run.polarized);
  f.geometry_from = geometry_from;
  return run;
}

std::vector<DatasetFile> report_four_camera_calibration(const std::filesystem::path& dir,
                                                        const FourCameraCalibrationRun& run, bool plots) {
  const FourCameraCalibration& c = run.calibration;
  write_text_file(dir / "calibration.yaml", four_camera_calibration_yaml(run.file));
  (void)read_four_camera_calibration(dir / "calibration.yaml");  // a file polrig writes is one it reads

  std::string rad = "camera,stop,level,intensity,mean_DN,sd_DN,pixels,clipped,used,fit_DN,residual_DN\n";
  for (std::size_t j = 0; j < 4; ++j) {
    const CameraRadiometry& r = c.radiometry.camera[j];
    for (const RadiometricLevel& l : r.levels) {
      const double fit = r.K * l.intensity + r.b;
      rad += fmt::format("{},{},{},{},{},{},{},{},{},{},{}\n", j + 1, l.stop, csv_number(l.level), csv_number(l.intensity),
                         csv_number(l.mean_DN), csv_number(l.sd_DN), l.pixels, l.clipped, l.used ? 1 : 0, csv_number(fit),
                         csv_number(l.mean_DN - fit));
    }
  }
  write_text_file(dir / "radiometric.csv", rad);

  std::string pol =
      "stop,theta_R_deg,aop_before_deg,aop_after_deg,residual_before_deg,residual_after_deg,dop_before,dop_after\n";
  for (const PolarizerStopRow& s : c.polarizer.stops)
    pol += fmt::format("{},{},{},{},{},{},{},{}\n", s.stop, csv_number(s.theta_R_deg), csv_number(s.aop_before_deg),
                       csv_number(s.aop_after_deg), csv_number(s.residual_before_deg), csv_number(s.residual_after_deg), csv_number(s.dop_before),
                       csv_number(s.dop_after));
  write_text_file(dir / "polarizer.csv", pol);

  std::string sum = "fit,camera,termination,iterations,rank,unknowns,observations,residual_rms,residual_unit,usable,message\n";
  for (std::size_t j = 0; j < 4; ++j) {
    const CameraRadiometry& r = c.radiometry.camera[j];
    sum += fmt::format("radiometric,{},{},0,{},2,{},{},DN,{},{}\n", j + 1, r.usable() ? "converged" : "rank_deficient",
                       r.rank, r.levels_used, csv_number(r.residual_rms_DN), r.usable() ? 1 : 0, csv_quoted(r.message));
  }
  const PolarizerFit& p = c.polarizer;
  sum += fmt::format("polarizer,,{},{},{},{},{},{},deg,{},{}\n", termination_name(p.summary.termination),
                     p.summary.iterations, p.rank, p.unknowns, p.summary.observations, csv_number(p.residual_rms_deg),
                     p.usable() ? 1 : 0, csv_quoted(p.summary.message));
  sum += fmt::format("polarizer_nominal_axes,,,,,,{},{},deg,,\"the nominal axes, psi_0 refitted\"\n",
                     p.summary.observations, csv_number(p.residual_rms_before_deg));
  write_text_file(dir / "summary.csv", sum);

  std::vector<DatasetFile> files{
      {"calibration.yaml", 1, "the calibrated model: per camera K_DN, b_DN, polarizer_deg, eps_deg, axis_deg and the "
                              "geometry used (fx_px, fy_px, cx_px, cy_px, k, rvec_deg, position_mm), the image size, "
                              "and where each part came from (sources)"},
      {"radiometric.csv", 1, "per camera and unpolarized level: the window's mean and SD (DN), pixels, clipped "
                             "pixels, used (1/0), the fitted line K·I + b and the residual (DN)"},
      {"polarizer.csv", 1, "per polarized stop: the window's circular-mean fused AoP and mean DoP with the nominal "
                           "axes (before) and the fitted ones (after), and the mean AoP residual of each (deg)"},
      {"summary.csv", 1, "per fit: termination, iterations, rank, unknowns, observations, residual RMS, usable, "
                         "message; and the nominal axes' residual RMS"}};

  if (run.truth && run.truth->radiometric && run.truth->polarizer) {
    const FourCameraCalibrationFile& t = *run.truth;
    std::string err = "quantity,camera,fitted,standard_error,truth,error,error_over_se\n";
    const auto row = [&](const char* q, int camera, double fit, double se, double truth) {
      err += fmt::format("{},{},{},{},{},{},{}\n", q, camera, csv_number(fit), csv_number(se), csv_number(truth), csv_number(fit - truth),
                         csv_number(se > 0 ? (fit - truth) / se : std::nan("")));
    };
    for (std::size_t j = 0; j < 4; ++j)
      row("K_DN", static_cast<int>(j + 1), c.radiometry.camera[j].K, c.radiometry.camera[j].K_se, t.model.K[j]);
    for (std::size_t j = 0; j < 4; ++j)
      row("b_DN", static_cast<int>(j + 1), c.radiometry.camera[j].b, c.radiometry.camera[j].b_se, t.model.b[j]);
    for (std::size_t j = 1; j < 4; ++j)  // the gauge: the truth's ε_j − ε_1
      row("eps_deg", static_cast<int>(j + 1), p.eps_deg[j], p.eps_se_deg[j], t.eps_deg[j] - t.eps_deg[0]);
    if (run.truth_dop && !std::isnan(p.dop)) row("dop", 0, p.dop, p.dop_se, *run.truth_dop);
    write_text_file(dir / "errors.csv", err);
    files.push_back({"errors.csv", 1, "against the dataset's truth.yaml: K_DN, b_DN per camera, eps_deg of cameras 2-4 "
                                      "(truth: eps_j - eps_1, the gauge), the source's DoP (rig.yaml's device.d): "
                                      "fitted, standard error, truth, error, error / standard error"});
  }
  if (run.geometry) {
    const std::vector<DatasetFile> g = report_four_camera_geometry(dir, *run.geometry);
    files.insert(files.end(), g.begin(), g.end());
  }
  if (!plots) return files;
  Plot r{"radiometric.png", "Radiometric calibration: window mean against the sphere's intensity",
         "intensity I (source units)", "window mean (DN)", "residual (DN)"};
  const char* colours[4] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd"};
  for (int j = 1; j <= 4; ++j) {
    r.series.push_back({"radiometric.csv", fmt::format("$intensity:($camera=={}?$mean_DN:NaN)", j), fmt::format("camera {} mean", j),
                        fmt::format("points pt 7 ps 0.8 lc rgb '{}'", colours[j - 1])});
    r.series.push_back({"radiometric.csv", fmt::format("$intensity:($camera=={}?$fit_DN:NaN)", j), fmt::format("K_{}·I + b_{}", j, j),
                        fmt::format("lines lw 1.5 lc rgb '{}'", colours[j - 1])});
    r.series.push_back({"radiometric.csv", fmt::format("$intensity:($camera=={}?$residual_DN:NaN)", j), fmt::format("camera {} residual", j),
                        fmt::format("linespoints lw 1 dt 2 pt 4 ps 0.8 lc rgb '{}'", colours[j - 1]), true});
  }
  r.extra = "set grid\nset ytics nomirror\nset y2tics";  // the legend outside, clear of the points
  Plot a{"polarizer.png", "Polarizer-angle calibration: fused AoP residual over the table's turn", "table angle θ_R (°)",
         "mean AoP residual over the window (°)"};
  a.series = {{"polarizer.csv", "$theta_R_deg:$residual_before_deg", "nominal axes (ψ_0 refitted)", "linespoints lw 1.5 pt 6 ps 0.8 lc rgb '#d62728'"},
              {"polarizer.csv", "$theta_R_deg:$residual_after_deg", "fitted ε_2..ε_4", "linespoints lw 2 pt 7 ps 0.8 lc rgb '#000000'"}};
  a.extra = "set key inside bottom right opaque box\nset grid\nset xtics 45";
  render_plots(dir, "plots.gp", {r, a});
  files.push_back({"radiometric.png", 1, "each camera's window means against the intensity, the fitted lines and the "
                                         "residuals (right axis)"});
  files.push_back({"polarizer.png", 1, "the window's mean AoP residual per table angle, nominal and fitted axes"});
  return files;
}

}  // namespace polrig
