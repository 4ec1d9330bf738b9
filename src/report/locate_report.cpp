#include "polrig/report/locate_report.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "polrig/io/csv.h"
#include "polrig/io/measured.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/report/positioning_reports.h"
#include "polrig/rig/rig.h"

namespace polrig {

DatasetLocation locate_four_camera_dataset(const FourCameraDataset& dataset, const Site& prior,
                                           const std::optional<Site>& truth,
                                           const OrientationSettings& orientation,
                                           const PositionOptions& options, const Progress& progress,
                                           const std::optional<FourCameraModel>& calibration) {
  // With a calibration: its fusion and its virtual camera 1 (f_c and the principal point of its
  // camera 1), each stop's raw frames re-fused (NaN where not valid, as read_four_camera_fused).
  std::optional<FourCameraFusion> fusion;
  std::optional<CameraIntrinsics> camera = dataset.camera;
  if (!calibration && !camera)
    throw std::invalid_argument(
        "no fused layers to locate from: the dataset has no truth.yaml and its frames no virtual camera (f_c_px, "
        "cx_px, cy_px; a measured dataset of raw frames); give --calibration CAL.yaml to fuse its raw frames");
  if (calibration) {
    if (calibration->width != dataset.width || calibration->height != dataset.height)
      throw std::invalid_argument(fmt::format("the calibration is for {} × {} px cameras, the dataset's are {} × {} px",
                                              calibration->width, calibration->height, dataset.width, dataset.height));
    fusion.emplace(*calibration);
    camera = CameraIntrinsics{fusion->grid().f_c, fusion->grid().cx, fusion->grid().cy};
  }
  const auto aop_dop = [&](std::size_t s) {
    if (!fusion) return read_four_camera_fused(dataset, s);
    std::array<std::vector<std::uint16_t>, 4> raw;
    try {
      raw = read_four_camera_raw(dataset, s);
    } catch (const std::runtime_error& e) {
      throw std::invalid_argument(fmt::format("--calibration re-fuses each stop's raw frames, which this dataset does not "
                                              "hold (write it with `polrig simulate --layers all`): {}",
                                              e.what()));
    }
    const FusedImage f = fusion->fuse<std::uint16_t>({raw[0], raw[1], raw[2], raw[3]});
    FusedAopDop out{std::vector<double>(f.AoP.begin(), f.AoP.end()), std::vector<double>(f.DoP.begin(), f.DoP.end())};
    for (std::size_t i = 0; i < f.valid.size(); ++i)
      if (!f.valid[i]) out.aop_deg[i] = out.dop[i] = std::numeric_limits<double>::quiet_NaN();
    return out;
  };
  check_intrinsics(*camera);
  check_orientation_settings(orientation);
  DatasetLocation run;
  run.truth = truth;
  std::vector<SunSighting> sightings;
  progress.begin("locate: sun vectors", static_cast<long long>(dataset.stops.size()));
  for (std::size_t s = 0; s < dataset.stops.size(); ++s) {
    const FourCameraDatasetStop& st = dataset.stops[s];
    if (st.polarized && !st.utc.empty()) {
      FusedAopDop fused = aop_dop(s);
      const SkyPoints points =
          grid_points(dataset.width, dataset.height, 1.0, std::move(fused.aop_deg), std::move(fused.dop));
      StopSun sun{st.stop, st.utc, sun_vector_eigen(points, *camera, orientation)};
      if (has_sun(sun.sun.status)) {
        sightings.push_back({parse_utc(st.utc), sun.sun.sun, 1.0});
        run.true_heading_deg.push_back(st.heading_deg.value_or(std::nan("")));
      }
      run.suns.push_back(std::move(sun));
    }
    progress.advance(1);
  }
  progress.finish();
  if (run.suns.empty())
    throw std::invalid_argument("no polarized stop with a UTC time: nothing to locate from (a sky dataset's stops.csv "
                                "gives utc)");
  // Eq. 17 has two unknowns (latitude, longitude): fewer sightings leave the fix undetermined
  // (its cost and residuals NaN).
  if (sightings.size() < 2)
    throw std::invalid_argument(fmt::format("{} of {} polarized stops gave a sun vector: the position fix (W16 Eq. 17) "
                                            "needs at least 2 sightings at different times", sightings.size(),
                                            run.suns.size()));
  run.location = locate(sightings, prior, options);
  return run;
}

DatasetLocation locate_four_camera_folder(const std::filesystem::path& dir, const Site& prior,
                                          const OrientationSettings& orientation, PositionOptions options,
                                          const Progress& progress,
                                          const std::optional<FourCameraModel>& calibration) {
  std::optional<Site> truth;
  if (std::filesystem::exists(dir / "rig.yaml")) {
    const LoadedRig r = load_rig(dir / "rig.yaml");
    require_instrument(r.rig, Instrument::kCameraArray, "locate", r.origin);
    if (const std::optional<Sky> sky = rig_sky(r.rig)) {
      truth = sky->site;
      options.sun = sky->sun;  // the ephemeris the data were made with (refraction, UT1 − UTC)
    }
  }
  FourCameraDataset dataset;
  try {
    dataset = read_four_camera_dataset(dir);
  } catch (const std::runtime_error& e) {
    throw DataError(e.what());
  }
  try {
    return locate_four_camera_dataset(dataset, prior, truth, orientation, options, progress, calibration);
  } catch (const std::invalid_argument& e) {
    throw DataError(fmt::format("{}: {}", dir.string(), e.what()));
  }
}

std::vector<DatasetFile> report_dataset_location(const std::filesystem::path& dir, const DatasetLocation& run) {
  std::vector<DatasetFile> files = report_location(dir, run.location, run.truth, run.true_heading_deg);
  std::string csv = "stop,utc,status,root,sun_az_deg,sun_el_deg,vectors_used,rms_residual\n";
  for (const StopSun& s : run.suns) {
    const bool solved = has_sun(s.sun.status);
    const auto value = [&](double v) { return solved ? fmt::format("{}", v) : std::string("nan"); };
    if (solved && !(std::isfinite(s.sun.sun_az_deg) && std::isfinite(s.sun.sun_el_deg)))
      throw std::runtime_error(fmt::format("stop {}: the sun vector is not finite; nothing was written", s.stop));
    csv += fmt::format("{},{},{},{},{},{},{},{}\n", s.stop, s.utc, sun_vector_status_name(s.sun.status),
                       sun_root_name(s.sun.root), value(s.sun.sun_az_deg), value(s.sun.sun_el_deg),
                       s.sun.vectors_used, value(s.sun.rms_residual));
  }
  write_text_file(dir / "sun.csv", csv);
  files.push_back({"sun.csv", 1, "per polarized stop: the eigenvector method's status and root (sun or antisun), "
                                 "the sun in camera 1's frame (azimuth from X towards Y, elevation above the "
                                 "image plane), the points used and the RMS of e·s"});
  return files;
}

}  // namespace polrig
