#include "polrig/report/four_camera_dataset.h"

#include <fmt/format.h>

#include "polrig/io/csv.h"
#include "polrig/io/exr.h"
#include "polrig/io/output_dir.h"
#include "polrig/report/dataset_previews.h"
#include "polrig/report/four_camera_geometry.h"
#include "polrig/sky/sensor_view.h"
#include "polrig/sky/sun.h"
#include "polrig/units.h"
#include "polrig/side_by_side.h"

namespace polrig {

std::string_view four_camera_layers_name(FourCameraLayers layers) {
  switch (layers) {
    case FourCameraLayers::All: return "all";
    case FourCameraLayers::Fused: return "fused";
    case FourCameraLayers::Aop: return "aop";
  }
  return "all";
}

FourCameraLayers default_four_camera_layers(const Rig& rig) {
  const bool calibration = !rig.schedule.unpolarized_levels.empty() || rig.checkerboard.views > 0;
  return calibration ? FourCameraLayers::All : FourCameraLayers::Aop;
}

std::optional<FourCameraLayers> parse_four_camera_layers(std::string_view name) {
  for (const FourCameraLayers l : {FourCameraLayers::All, FourCameraLayers::Fused, FourCameraLayers::Aop})
    if (four_camera_layers_name(l) == name) return l;
  return std::nullopt;
}

std::string four_camera_truth_yaml(const FourCameraSpec& spec, const FourCameraModel& truth,
                                   const VirtualCamera& grid) {
  // Plain numbers, shortest round-trip text ({}): the file reads back to the same doubles.
  std::string y =
      "# The four-camera sensor's truth (docs/formats.md \"Four-camera dataset\"). Camera j's frame: X_j image +x\n"
      "# (columns), Y_j image +y (rows), Z_j the optical axis; angles from X towards Y. Pixel (col, row)'s\n"
      "# centre at (col + 0.5, row + 0.5). R_j1 maps camera 1's coordinates to camera j's (v_j = R_j1 v_1).\n"
      "# The lens: Kannala-Brandt (OpenCV fisheye), theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8),\n"
      "# u = fx theta_d cos(alpha) + cx, v = fy theta_d sin(alpha) + cy. Eq. 1: f_j = K_j I [1 + d cos(2 phi - 2 (phi_j + eps_j))] + b_j.\n";
  y += fmt::format("width_px: {}\nheight_px: {}\npixel_um: {}\nadc_bits: {}\nbaseline_mm: {}\n", spec.width_px,
                   spec.height_px, spec.pixel_um, spec.adc_bits, spec.baseline_mm);
  y += fmt::format("virtual_camera:  # camera 1's undistorted pinhole grid: the fused layers' image\n"
                   "  width_px: {}\n  height_px: {}\n  f_c_px: {}\n  cx_px: {}\n  cy_px: {}\n",
                   grid.width, grid.height, grid.f_c, grid.cx, grid.cy);
  y += "cameras:\n";
  for (std::size_t j = 0; j < 4; ++j) {
    const CameraGeometry& c = truth.camera[j];
    const Vec3 p = camera_position_mm(spec, static_cast<int>(j));
    y += fmt::format("  - camera: {}\n", j + 1);
    y += fmt::format("    K_DN: {}\n    b_DN: {}\n    polarizer_deg: {}\n    eps_deg: {}\n    axis_deg: {}\n", truth.K[j],
                     truth.b[j], spec.polarizer_deg[j], spec.eps_deg[j], truth.axis_deg[j]);
    y += fmt::format("    fx_px: {}\n    fy_px: {}\n    cx_px: {}\n    cy_px: {}\n    focal_mm: {}\n", c.fx, c.fy, c.cx,
                     c.cy, c.fx * spec.pixel_um / 1000.0);
    y += fmt::format("    k: [{}, {}, {}, {}]\n", c.k[0], c.k[1], c.k[2], c.k[3]);
    y += fmt::format("    rvec_deg: [{}, {}, {}]\n", spec.rot_x_deg[j], spec.rot_y_deg[j], spec.rot_z_deg[j]);
    y += fmt::format("    R_j1: [{}, {}, {}, {}, {}, {}, {}, {}, {}]\n", c.R[0], c.R[1], c.R[2], c.R[3], c.R[4], c.R[5],
                     c.R[6], c.R[7], c.R[8]);
    y += fmt::format("    position_mm: [{}, {}, {}]\n", p[0], p[1], p[2]);
  }
  return y;
}

std::vector<DatasetFile> report_four_camera_dataset(const std::filesystem::path& dir, const Rig& rig,
                                                    const FourCameraDatasetOptions& options,
                                                    const Progress& progress) {
  const FourCameraSimulator sim(rig);
  // The checkerboard views (the geometric calibration's), placed before anything is written.
  std::optional<CheckerboardRenderer> board;
  if (rig.checkerboard.views > 0) board.emplace(rig);
  const std::optional<Sky> sky = rig_sky(rig);
  const SkyMount mount = rig.source.sky.resolved_mount();
  const VirtualCamera grid = sim.fusion().grid();
  std::filesystem::create_directory(dir / "frames");
  write_text_file(dir / "truth.yaml", four_camera_truth_yaml(rig.four_camera, sim.truth(), grid));

  progress.begin("simulate: stops", static_cast<long long>(sim.stops().size()));
  std::string csv =
      "stop,utc,t_s,theta_R_deg,intensity,polarized,heading_deg,sun_x_cam1,sun_y_cam1,sun_z_cam1,"
      "sun_azimuth_deg,sun_zenith_deg,file\n";
  // The previews' stops: the first and the last (one when they are the same).
  const std::size_t last = sim.stops().empty() ? 0 : sim.stops().size() - 1;
  std::vector<PreviewStop> previews;
  // One stop whole on one thread: its frames and fusion, its EXR compressed and written, its CSV
  // row and preview.
  const auto do_stop = [&](std::size_t index) {
    const DofpStop& stop = sim.stops()[index];
    const std::string file = fmt::format("frames/stop_{:04}.exr", stop.index);
    ExrImage image;
    image.width = sim.width(), image.height = sim.height();
    const FourCameraSignal signal = sim.signal(stop);
    std::array<std::vector<std::uint16_t>, kFourCameras> raw = sim.frames(signal, 0);
    FusedImage fused = sim.fuse(raw);
    DatasetStopRow row;
    if (options.previews && (index == 0 || index == last)) {
      // The fused layers as the stop's EXR holds them (float), on the virtual camera 1 grid.
      PreviewStop p;
      p.stem = fmt::format("stop_{:04}", stop.index);
      p.cols = grid.width, p.rows = grid.height, p.pixels = 1;
      p.aop_deg.assign(fused.AoP.begin(), fused.AoP.end());
      p.dop.assign(fused.DoP.begin(), fused.DoP.end());
      p.S0.assign(fused.S0.begin(), fused.S0.end());
      p.valid = fused.valid;
      row.preview = std::move(p);
    }
    if (options.layers == FourCameraLayers::All)
      for (std::size_t j = 0; j < 4; ++j)
        image.uints.push_back({fmt::format("cam{}", j + 1), std::vector<std::uint32_t>(raw[j].begin(), raw[j].end())});
    if (options.layers != FourCameraLayers::Aop) {
      image.floats.push_back({"S0", std::move(fused.S0)});
      image.floats.push_back({"S1", std::move(fused.S1)});
      image.floats.push_back({"S2", std::move(fused.S2)});
    }
    image.floats.push_back({"AoP", std::move(fused.AoP)});
    image.floats.push_back({"DoP", std::move(fused.DoP)});
    image.uints.push_back({"valid", std::vector<std::uint32_t>(fused.valid.begin(), fused.valid.end())});
    ExrAttributes& a = image.attributes;
    a.doubles = {{"stop", stop.index},         {"theta_R_deg", stop.theta_R_deg}, {"t_s", stop.t_s},
                 {"intensity", stop.intensity}, {"polarized", stop.polarized ? 1.0 : 0.0},
                 {"f_c_px", grid.f_c},          {"cx_px", grid.cx},                {"cy_px", grid.cy}};
    a.strings = {{"layers", std::string(four_camera_layers_name(options.layers))},
                 {"fused_grid", "virtual camera 1: camera 1's undistorted pinhole grid (f_c_px, cx_px, cy_px); "
                                "AoP from X towards Y of camera 1, degrees [0, 180)"}};
    std::string utc, heading, sun_cols = ",,,,";
    if (sky) {
      const UtcTime t = sky->first_stop.plus_seconds(stop.t_s + mount.time_offset_s);
      const SunPosition sun = sun_position(t, sky->site, sky->sun);
      const Vec3 s = sun_direction_enu(sun);
      const Vec3 sc = *sim.sun_in_camera1(stop);
      utc = format_utc(sky->first_stop.plus_seconds(stop.t_s));
      const double h = *dofp_true_heading_deg(rig, stop);
      heading = fmt::format("{}", h);
      sun_cols = fmt::format("{},{},{},{},{}", sc[0], sc[1], sc[2], sun.azimuth_deg, 90.0 - sun.elevation_deg);
      a.strings.push_back({"utc", utc});
      a.doubles.push_back({"site_lat_deg", sky->site.lat_deg});
      a.doubles.push_back({"site_lon_deg", sky->site.lon_deg});
      a.doubles.push_back({"sun_azimuth_deg", sun.azimuth_deg});
      a.doubles.push_back({"sun_elevation_deg", sun.elevation_deg});
      a.doubles.push_back({"P_max", sky->model.P_max.at(sun.elevation_deg)});
      a.doubles.push_back({"heading_deg", h});
      a.vectors.push_back({"sun_enu", s});
      a.vectors.push_back({"sun_camera1", sc});
    }
    if (row.preview)
      row.preview->title = fmt::format("stop {}: {}t = {:.6g} s, θ_R = {:.6g}°{}\nthe fused image on the virtual camera 1 grid (white: not valid)",
                                          stop.index, utc.empty() ? std::string() : fmt::format("{} UTC, ", utc),
                                          stop.t_s, stop.theta_R_deg,
                                          heading.empty() ? std::string() : fmt::format(", true heading {:.4f}°",
                                                                                        std::stod(heading)));
    write_exr_image(dir / file, image, ExrCompression::Zip, ExrThreads::ThisThread);
    row.csv = fmt::format("{},{},{},{},{},{},{},{},{}\n", stop.index, utc, stop.t_s, stop.theta_R_deg, stop.intensity,
                          stop.polarized ? 1 : 0, heading, sun_cols, file);
    progress.advance();
    return row;
  };
  side_by_side_in_order(sim.stops().size(), do_stop, [&](DatasetStopRow&& row) {
    csv += row.csv;
    if (row.preview) previews.push_back(std::move(*row.preview));
  });
  progress.finish();
  write_text_file(dir / "stops.csv", csv);
  PreviewOptions po;
  po.grid_text = "fused pixel";
  po.s0_label = "S0 (fused, (f - b)/K)";
  po.frame_text = "camera 1's X towards Y";
  const std::vector<DatasetFile> shown = report_stop_previews(dir, previews, po);
  std::vector<DatasetFile> files;
  if (board) files = report_checkerboard_views(dir, *board, progress);
  std::vector<DatasetFile> own = {{"stops.csv", 1,
           "one row per stop: stop, utc (sky rigs), t_s, theta_R_deg, intensity, polarized (0/1), heading_deg (true "
           "geographic azimuth of camera 1's X), sun_x/y/z_cam1 (the true sun in camera 1's frame), sun_azimuth_deg, "
           "sun_zenith_deg, file"},
          {"truth.yaml", 1,
           "the cameras' truth: K, b, polarizer axes and errors, intrinsics, Kannala-Brandt k, R_j1, positions; the "
           "virtual camera 1"},
          {"frames", 1,
           "frames/stop_NNNN.exr: raw DN of cameras 1-4 as UINT channels cam1..cam4 (layers all), the fused S0, S1, "
           "S2 (layers all, fused), AoP, DoP (float) and valid (UINT 0/1) on the virtual camera 1 grid"}};
  own.insert(own.end(), shown.begin(), shown.end());
  own.insert(own.end(), files.begin(), files.end());
  return own;
}

void write_four_camera_dataset(const LoadedRig& rig, const std::filesystem::path& destination,
                               const FourCameraDatasetOptions& options, const std::string& command, bool replace,
                               const Progress& progress) {
  OutputDir dir(destination, replace);
  const std::vector<DatasetFile> files = report_four_camera_dataset(dir.staging(), rig.rig, options, progress);
  write_manifest(dir.staging(), {command, &rig, files});
  dir.commit();
}

}  // namespace polrig
