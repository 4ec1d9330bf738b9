#include "polrig/report/dofp_dataset.h"

#include <fmt/format.h>

#include "polrig/calib/dofp_polarization.h"
#include "polrig/io/csv.h"
#include "polrig/io/exr.h"
#include "polrig/io/output_dir.h"
#include "polrig/report/dataset_previews.h"
#include "polrig/sky/sensor_view.h"
#include "polrig/sky/sun.h"
#include "polrig/units.h"
#include "polrig/side_by_side.h"

namespace polrig {

namespace {

std::string mosaic_text(const DofpCameraSpec& c) {
  return fmt::format("{} {} {} {}", c.mosaic_deg[0], c.mosaic_deg[1], c.mosaic_deg[2], c.mosaic_deg[3]);
}

void write_truth(const std::filesystem::path& path, const Rig& rig, const DofpTruth& t) {
  ExrImage image;
  image.width = t.width, image.height = t.height;
  auto layer = [&](const char* name, const std::vector<double>& v) {
    image.floats.push_back({name, std::vector<float>(v.begin(), v.end())});
  };
  layer("K", t.K), layer("b", t.b), layer("k", t.k), layer("eps_deg", t.eps_deg), layer("alpha_deg", t.alpha_deg);
  image.attributes.doubles = {{"f_c_px", focal_px(rig.camera)},
                              {"cx_px", 0.5 * t.width},
                              {"cy_px", 0.5 * t.height},
                              {"pixel_um", rig.camera.pixel_um},
                              {"focal_mm", rig.camera.focal_mm},
                              {"adc_bits", rig.camera.adc_bits}};
  image.attributes.strings = {{"mosaic_deg", mosaic_text(rig.camera)},
                              {"frame", "l: X_l image +x (columns), Y_l image +y (rows), Z_l the optical axis; "
                                        "angles from X_l towards Y_l"}};
  write_exr_image(path, image);
}

}  // namespace

std::vector<DatasetFile> report_dofp_dataset(const std::filesystem::path& dir, const Rig& rig,
                                             const DofpDatasetOptions& options, const Progress& progress) {
  const DofpSimulator sim(rig, options.analyzer);
  const std::optional<Sky> sky = rig_sky(rig);
  const SkyMount mount = rig.source.sky.resolved_mount();
  std::filesystem::create_directory(dir / "frames");
  write_truth(dir / "truth.exr", rig, sim.truth());

  long long total = 0;
  for (const DofpStop& s : sim.stops()) total += s.frames;
  progress.begin("simulate: frames", total);
  const std::size_t n = static_cast<std::size_t>(sim.width()) * static_cast<std::size_t>(sim.height());
  std::string csv = "stop,theta_R_deg,t_s,utc,intensity,polarized,heading_deg,frames,file\n";
  // The previews' stops: the first and the last (one when they are the same).
  const std::size_t last = sim.stops().empty() ? 0 : sim.stops().size() - 1;
  std::vector<PreviewStop> previews;
  const DofpTruth nominal = nominal_dofp_parameters(sim.width(), sim.height(), rig.camera.mosaic_deg);
  // One stop whole on one thread: its frames, its EXR compressed and written, its CSV row and
  // preview.
  const auto do_stop = [&](std::size_t index) {
    const DofpStop& stop = sim.stops()[index];
    const bool preview = options.previews && (index == 0 || index == last);
    std::vector<std::uint32_t> preview_sum(preview ? n : 0);
    const std::string file = fmt::format("frames/stop_{:04}.exr", stop.index);
    ExrImage image;
    image.width = sim.width(), image.height = sim.height();
    DofpTruthLayers layers;
    std::vector<std::uint32_t> sum(options.storage == DofpFrameStorage::Sum ? n : 0);
    const DofpSimulator::StopSignal signal = sim.signal(stop, options.truth_layers ? &layers : nullptr);
    for (int f = 0; f < stop.frames; ++f) {
      const std::vector<std::uint16_t> raw = sim.frame(signal, f);
      if (options.storage == DofpFrameStorage::Every)
        image.uints.push_back({fmt::format("raw.{:03}", f), std::vector<std::uint32_t>(raw.begin(), raw.end())});
      else
        for (std::size_t i = 0; i < n; ++i) sum[i] += raw[i];
      for (std::size_t i = 0; i < preview_sum.size(); ++i) preview_sum[i] += raw[i];
      progress.advance();
    }
    if (options.storage == DofpFrameStorage::Sum) image.uints.push_back({"raw_sum", std::move(sum)});
    if (options.truth_layers) {
      image.floats.push_back({"S0", std::move(layers.S0)});
      image.floats.push_back({"S1", std::move(layers.S1)});
      image.floats.push_back({"S2", std::move(layers.S2)});
      image.floats.push_back({"AoP", std::move(layers.AoP)});
      image.floats.push_back({"DoP", std::move(layers.DoP)});
    }
    ExrAttributes& a = image.attributes;
    a.doubles = {{"stop", stop.index},         {"theta_R_deg", stop.theta_R_deg}, {"t_s", stop.t_s},
                 {"intensity", stop.intensity}, {"polarized", stop.polarized ? 1.0 : 0.0},
                 {"frames", stop.frames}};
    a.strings = {{"raw_storage", options.storage == DofpFrameStorage::Every ? "frames" : "sum"},
                 {"analyzer", options.analyzer == DofpAnalyzer::ImagePlane ? "image-plane" : "in-front"}};
    std::string utc, heading;
    if (sky) {
      const UtcTime t = sky->first_stop.plus_seconds(stop.t_s + mount.time_offset_s);
      const SunPosition sun = sun_position(t, sky->site, sky->sun);
      const Vec3 s = sun_direction_enu(sun);
      const SensorAxesEnu axes = sensor_axes_enu(mount, stop.theta_R_deg);
      utc = format_utc(sky->first_stop.plus_seconds(stop.t_s));
      const double h = *dofp_true_heading_deg(rig, stop);
      heading = fmt::format("{}", h);
      a.strings.push_back({"utc", utc});
      a.doubles.push_back({"site_lat_deg", sky->site.lat_deg});
      a.doubles.push_back({"site_lon_deg", sky->site.lon_deg});
      a.doubles.push_back({"site_height_m", sky->site.height_m});
      a.doubles.push_back({"sun_azimuth_deg", sun.azimuth_deg});
      a.doubles.push_back({"sun_elevation_deg", sun.elevation_deg});
      a.doubles.push_back({"P_max", sky->model.P_max.at(sun.elevation_deg)});
      a.doubles.push_back({"heading_deg", h});
      a.vectors.push_back({"sun_enu", s});
      a.vectors.push_back({"sun_camera", {vec3::dot(s, axes.x), vec3::dot(s, axes.y), vec3::dot(s, axes.z)}});
    }
    // PIZ: the smallest lossless form of noisy frames, 0.79× ZIP's bytes (docs/formats.md §6.14).
    write_exr_image(dir / file, image, ExrCompression::Piz, ExrThreads::ThisThread);
    DatasetStopRow row{fmt::format("{},{},{},{},{},{},{},{},{}\n", stop.index, stop.theta_R_deg, stop.t_s, utc,
                            stop.intensity, stop.polarized ? 1 : 0, heading, stop.frames, file),
                std::nullopt};
    if (preview && stop.frames > 0) {
      // The mean frame as read_dofp_mean_frame reads it back (the sum over the frames), its cells'
      // polarization with the nominal parameters (as `orient` without --params).
      std::vector<double> mean(n);
      for (std::size_t i = 0; i < n; ++i) mean[i] = double(preview_sum[i]) / stop.frames;
      DofpCellPolarization cells = dofp_cell_polarization(mean, nominal);
      PreviewStop p;
      p.stem = fmt::format("stop_{:04}", stop.index);
      p.title = fmt::format("stop {}: θ_R = {:.6g}°, t = {:.6g} s{}, {}, intensity {:.6g}\nthe mean of {} frame{}, per "
                            "2 × 2 cell, nominal parameters", stop.index, stop.theta_R_deg, stop.t_s,
                            utc.empty() ? std::string() : fmt::format(" ({})", utc),
                            stop.polarized ? "polarized" : "unpolarized", stop.intensity, stop.frames,
                            stop.frames == 1 ? "" : "s");
      p.cols = cells.cells_x, p.rows = cells.cells_y, p.pixels = 2;
      p.aop_deg = std::move(cells.aop_deg), p.dop = std::move(cells.dop), p.S0 = std::move(cells.S0);
      row.preview = std::move(p);
    }
    return row;
  };
  side_by_side_in_order(sim.stops().size(), do_stop, [&](DatasetStopRow&& row) {
    csv += row.csv;
    if (row.preview) previews.push_back(std::move(*row.preview));
  });
  progress.finish();
  write_text_file(dir / "stops.csv", csv);
  PreviewOptions po;
  po.grid_columns[0] = "cell_x", po.grid_columns[1] = "cell_y";
  po.grid_text = "2 × 2 cell";
  po.s0_label = "S0 (DN)";
  po.frame_text = "from the image +x towards +y";
  std::vector<DatasetFile> files = {{"stops.csv", 1,
           "one row per stop: stop, theta_R_deg, t_s, utc (sky rigs), intensity, polarized (0/1), heading_deg "
           "(true geographic azimuth of X_l, sky rigs), frames, file"},
          {"truth.exr", 1, "per-pixel truth K, b, k, eps_deg, alpha_deg (float) and the intrinsics"},
          {"frames", 1,
           "frames/stop_NNNN.exr: raw DN as UINT channels raw.NNN (every frame) or raw_sum (the frames' sum), "
           "optional truth layers S0, S1, S2, AoP, DoP"}};
  const std::vector<DatasetFile> shown = report_stop_previews(dir, previews, po);
  files.insert(files.end(), shown.begin(), shown.end());
  return files;
}

void write_dofp_dataset(const LoadedRig& rig, const std::filesystem::path& destination,
                        const DofpDatasetOptions& options, const std::string& command, bool replace,
                        const Progress& progress) {
  OutputDir dir(destination, replace);
  const std::vector<DatasetFile> files = report_dofp_dataset(dir.staging(), rig.rig, options, progress);
  write_manifest(dir.staging(), {command, &rig, files});
  dir.commit();
}

}  // namespace polrig
