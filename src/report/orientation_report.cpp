#include "polrig/report/orientation_report.h"

#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "polrig/calib/dofp_polarization.h"
#include "polrig/io/csv.h"
#include "polrig/io/measured.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/rig/rig.h"
#include "polrig/io/plot.h"
#include "polrig/compass/heading.h"
#include "polrig/side_by_side.h"

namespace polrig {

namespace {

std::string cell(std::optional<double> v, const char* column, int frame) {
  if (!v) return "nan";  // not defined (formats.md §5)
  if (!std::isfinite(*v))
    throw std::runtime_error(fmt::format("orientation: column '{}' of frame {} is {}; nothing was "
                                         "written", column, frame, *v));
  return fmt::format("{}", *v);
}

}  // namespace

std::vector<DatasetFile> report_orientation(const std::filesystem::path& dir,
                                            const std::vector<FrameOrientation>& frames, bool plots) {
  std::string text = "frame,method,sun_az_deg,sun_el_deg,heading_deg,heading_error_deg,status\n";
  for (const FrameOrientation& f : frames)
    for (const OrientationEstimate& e : f.estimates) {
      std::optional<double> az, error;
      if (e.solved) az = e.sun_az_deg;
      if (e.heading_deg && f.true_heading_deg)
        error = heading_difference_deg(*e.heading_deg, *f.true_heading_deg);
      // Checked left to right, so an error names the first bad column.
      const std::string az_cell = cell(az, "sun_az_deg", f.frame);
      const std::string el_cell = cell(e.solved ? e.sun_el_deg : std::nullopt, "sun_el_deg", f.frame);
      const std::string heading_cell = cell(e.heading_deg, "heading_deg", f.frame);
      const std::string error_cell = cell(error, "heading_error_deg", f.frame);
      text += fmt::format("{},{},{},{},{},{},{}\n", f.frame, orientation_method_name(e.method),
                          az_cell, el_cell, heading_cell, error_cell, e.status);
    }
  write_text_file(dir / "orientation.csv", text);
  std::vector<DatasetFile> files{
      {"orientation.csv", 1,
       "per sky frame and method (eigenvector, single-point, line-detection): the sun's azimuth "
       "and elevation in the camera frame, the heading, its error against the true heading, the "
       "status"}};
  if (!plots || frames.empty()) return files;
  Plot p;
  p.png = "heading_error.png";
  p.title = "Heading error per frame (H17 Eqs. 6–14 and the comparators of §4.2)";
  p.xlabel = "frame";
  p.ylabel = "heading error (°)";
  const auto only = [](const char* method) {
    return fmt::format("$frame:(@method eq '{}' ? $heading_error_deg : NaN)", method);
  };
  p.series = {{"orientation.csv", only("single-point"), "single point (zenith cells)",
               "linespoints pt 7 ps 0.6 lw 1 lc rgb '#d62728'"},
              {"orientation.csv", only("line-detection"), "line detection (Hough)",
               "linespoints pt 5 ps 0.6 lw 1 lc rgb '#2ca02c'"},
              {"orientation.csv", only("eigenvector"), "eigenvector",
               "linespoints pt 9 ps 0.7 lw 2 lc rgb '#1f77b4'"}};
  p.extra = "set key below horizontal spacing 1.4\nset grid";
  render_plots(dir, "plots.gp", {p});
  files.push_back({"heading_error.png", 1, "heading error per frame of the three methods"});
  return files;
}

std::vector<FrameOrientation> orient_dofp_dataset(const DofpDataset& dataset, const std::optional<Sky>& sky,
                                                  const DofpTruth* parameters,
                                                  const OrientationSettings& settings,
                                                  std::optional<double> heading_prior_deg,
                                                  const Progress& progress) {
  const int W = dataset.width, H = dataset.height;
  DofpTruth nominal;
  if (!parameters) {
    nominal = nominal_dofp_parameters(W, H, dataset.mosaic_deg);
    parameters = &nominal;
  }
  if (parameters->width != W || parameters->height != H)
    throw std::invalid_argument(fmt::format("parameters of {} × {} px for the dataset {} of {} × {} px",
                                            parameters->width, parameters->height, dataset.dir.string(), W, H));
  const CameraIntrinsics camera{dataset.f_c_px, dataset.cx, dataset.cy};
  check_intrinsics(camera);
  std::vector<FrameOrientation> out;
  // The frames side by side, each read and oriented on one thread, collected in stop order (the
  // first failing frame in order thrown): the same results for any thread count.
  progress.begin("orient: frames", static_cast<long long>(dataset.stops.size()));
  const auto orient_stop = [&](std::size_t s) {
    const DofpDatasetStop& st = dataset.stops[s];
    std::optional<FrameOrientation> frame_orientation;
    if (st.polarized) {
      const std::vector<double> frame = read_dofp_mean_frame(dataset, s);
      DofpCellPolarization cells = dofp_cell_polarization(frame, *parameters);
      const SkyPoints points =
          grid_points(cells.cells_x, cells.cells_y, 2.0, std::move(cells.aop_deg), std::move(cells.dop));
      std::optional<double> sun_azimuth;
      OrientationSettings s = settings;
      if (sky && !st.utc.empty()) {
        const SunPosition sun = sun_position(parse_utc(st.utc), sky->site, sky->sun);
        sun_azimuth = sun.azimuth_deg;
        if (heading_prior_deg) s.prior_sun = sun_in_level_camera(sun.azimuth_deg, sun.elevation_deg,
                                                             *heading_prior_deg + st.theta_R_deg);
      }
      frame_orientation = FrameOrientation{st.stop, orient_frame(points, camera, sun_azimuth, s), st.heading_deg};
    }
    progress.advance(1);
    return frame_orientation;
  };
  side_by_side_in_order(dataset.stops.size(), orient_stop, [&](std::optional<FrameOrientation>&& o) {
    if (o) out.push_back(std::move(*o));
  });
  progress.finish();
  return out;
}

std::vector<FrameOrientation> orient_dofp_folder(const std::filesystem::path& dir, const std::filesystem::path& params,
                                                 const OrientationSettings& settings,
                                                 std::optional<double> heading_prior_deg, const Progress& progress) {
  std::optional<Sky> sky;
  if (std::filesystem::exists(dir / "rig.yaml")) {
    const LoadedRig r = load_rig(dir / "rig.yaml");
    require_instrument(r.rig, Instrument::kMosaic, "orient", r.origin);
    sky = rig_sky(r.rig);
  }
  if (heading_prior_deg && !sky)
    throw DataError(fmt::format("heading prior: {} has no sky rig (rig.yaml with source.model sky) to place the sun",
                                dir.string()));
  DofpDataset dataset;
  std::optional<DofpTruth> parameters;
  try {
    dataset = read_dofp_dataset(dir);
    if (!params.empty()) parameters = read_dofp_parameters(params, dataset);
  } catch (const std::runtime_error& e) {
    throw DataError(e.what());
  }
  try {
    return orient_dofp_dataset(dataset, sky, parameters ? &*parameters : nullptr, settings, heading_prior_deg, progress);
  } catch (const std::invalid_argument& e) {
    throw DataError(fmt::format("{}: {}", dir.string(), e.what()));
  }
}

}  // namespace polrig
