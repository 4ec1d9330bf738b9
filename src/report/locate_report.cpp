#include "polrig/report/locate_report.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>

#include "polrig/io/csv.h"
#include "polrig/io/measured.h"
#include "polrig/io/plot.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/report/positioning_reports.h"
#include "polrig/rig/rig.h"
#include "polrig/side_by_side.h"

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
  // The stops side by side, each on its own thread (the same work on any thread: the same results
  // for any thread count), collected in stop order; the first failing stop in order is thrown.
  progress.begin("locate: sun vectors", static_cast<long long>(dataset.stops.size()));
  const auto stop_sun = [&](std::size_t s) {
    const FourCameraDatasetStop& st = dataset.stops[s];
    std::optional<StopSun> sun;
    if (st.polarized && !st.utc.empty()) {
      FusedAopDop fused = aop_dop(s);
      const SkyPoints points =
          grid_points(dataset.width, dataset.height, 1.0, std::move(fused.aop_deg), std::move(fused.dop));
      sun = StopSun{st.stop, st.utc, sun_vector_eigen(points, *camera, orientation)};
    }
    progress.advance(1);
    return sun;
  };
  std::size_t s = 0;
  side_by_side_in_order(dataset.stops.size(), stop_sun, [&](std::optional<StopSun>&& sun) {
    const std::size_t stop = s++;
    if (!sun) return;
    if (has_sun(sun->sun.status)) {
      sightings.push_back({parse_utc(sun->utc), sun->sun.sun, 1.0});
      run.true_heading_deg.push_back(dataset.stops[stop].heading_deg.value_or(std::nan("")));
    }
    run.suns.push_back(std::move(*sun));
  });
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

namespace {

constexpr double kKmPerDeg = 111.32;  // W16's, as positioning's km

// map.csv and fix.png, heading.png: the fix among the stops' lines of position, the headings
// against time. A stop's line of position is its circle of equal zenith angle near the fix (the
// intercept method, for the picture only): the points where the sun's zenith angle is the measured
// one lie `residual_deg` of arc from the fix away from the sun's azimuth β, along the line
// perpendicular to β.
std::vector<DatasetFile> location_plots(const std::filesystem::path& dir, const DatasetLocation& run) {
  const PositionRoot& fix = run.location.fix.chosen;
  if (!std::isfinite(fix.lat_deg) || !std::isfinite(fix.lon_deg)) return {};
  const double rad = std::acos(-1.0) / 180.0;
  // The scale of the picture: the fix's distance from the truth, its 1σ, the residuals.
  double span = 0.01;
  if (run.truth) span = std::max(span, great_circle_km(fix.lat_deg, fix.lon_deg, run.truth->lat_deg, run.truth->lon_deg) / kKmPerDeg);
  if (std::isfinite(fix.sd_major_km)) span = std::max(span, 2 * fix.sd_major_km / kKmPerDeg);
  for (const LocateSample& s : run.location.samples)
    if (std::isfinite(s.residual_deg)) span = std::max(span, 2 * std::abs(s.residual_deg));
  const double lat0 = run.truth ? 0.5 * (fix.lat_deg + run.truth->lat_deg) : fix.lat_deg;
  const double lon0 = run.truth ? fix.lon_deg + 0.5 * std::remainder(run.truth->lon_deg - fix.lon_deg, 360.0) : fix.lon_deg;
  const double site_lat = run.truth ? run.truth->lat_deg : fix.lat_deg;
  const double cos_lat = std::max(std::cos(site_lat * rad), 0.05);
  std::string csv = "mark,utc,lat_deg,lon_deg,dlat_deg,dlon_deg\n";
  csv += fmt::format("fix,,{},{},0,0\n", fix.lat_deg, fix.lon_deg);
  if (run.truth) csv += fmt::format("truth,,{},{},0,0\n", run.truth->lat_deg, run.truth->lon_deg);
  const double half = 4 * span;  // each line's half length (degrees of arc): across the picture
  for (const LocateSample& s : run.location.samples) {
    if (!std::isfinite(s.residual_deg) || !std::isfinite(s.beta_deg)) continue;
    const double b = s.beta_deg * rad;
    const double lat = fix.lat_deg - s.residual_deg * std::cos(b);
    const double lon = fix.lon_deg - s.residual_deg * std::sin(b) / cos_lat;
    csv += fmt::format("line,{},{},{},{},{}\n", format_utc(s.utc), lat, lon, -half * std::sin(b),
                       half * std::cos(b) / cos_lat);
  }
  write_text_file(dir / "map.csv", csv);

  const double h = 1.25 * span;
  Plot map{"fix.png",
           fmt::format("The fix (Eq. 17) and each stop's line of position (its measured zenith angle, linearized at "
                       "the fix)\nequal ground scale at {:.4f}°N: the square is {:.3g} km ({:.3g}° of latitude) on a side",
                       site_lat, 2 * h * kKmPerDeg, 2 * h),
           "longitude (°E)", "latitude (°N)"};
  map.series = {{"map.csv", "(@mark eq 'line' ? $lon_deg - $dlon_deg : NaN):($lat_deg - $dlat_deg):(2*$dlon_deg):(2*$dlat_deg)",
                 "each stop's line of position", "vectors nohead lw 1 lc rgb '#9ecae1'"},
                {"map.csv", "(@mark eq 'fix' ? $lon_deg : NaN):$lat_deg", "fix", "points pt 7 ps 2 lc rgb '#1f77b4'"}};
  if (run.truth)
    map.series.push_back({"map.csv", "(@mark eq 'truth' ? $lon_deg : NaN):$lat_deg", "truth",
                          "points pt 3 ps 3 lw 2 lc rgb '#d62728'"});
  map.extra = fmt::format("set xrange [{}:{}]\nset yrange [{}:{}]\nset size ratio 1\nset format x '%.3f'\n"
                          "set format y '%.3f'\nset xtics rotate by -30\nset key below vertical maxrows 1 samplen 2",
                          lon0 - h / cos_lat, lon0 + h / cos_lat, lat0 - h, lat0 + h);
  map.width = 960, map.height = 920;

  const bool truth_heading = std::any_of(run.true_heading_deg.begin(), run.true_heading_deg.end(),
                                         [](double v) { return std::isfinite(v); });
  const std::string day = run.location.samples.empty() ? std::string() : format_utc(run.location.samples[0].utc).substr(0, 10);
  Plot heading{"heading.png", "Heading ψ = β − α_S per stop (Eq. 18)", fmt::format("UTC ({})", day),
               "heading (°, clockwise from north)", "heading error (°)"};
  heading.series = {{"heading.csv", "$utc:$heading_deg", "heading", "points pt 7 ps 1 lc rgb '#1f77b4'"}};
  if (truth_heading) {
    heading.series.push_back({"heading.csv", "$utc:$heading_true_deg", "true heading", "lines lw 2 lc rgb '#d62728'"});
    heading.series.push_back({"heading.csv", "$utc:$heading_error_deg", "heading error (right axis)",
                              "points pt 6 ps 1 lc rgb 'black'", true});
  }
  heading.extra = "set xdata time\nset timefmt '%Y-%m-%dT%H:%M:%SZ'\nset format x '%H:%M:%S'\n"
                  "set xtics rotate by -30\nset key below horizontal maxrows 1\nset offsets 0, 0, graph 0.1, graph 0.1";
  // Without a usable fix every heading is NaN: nothing to draw against time.
  const bool headings = std::any_of(run.location.samples.begin(), run.location.samples.end(),
                                    [](const LocateSample& s) { return std::isfinite(s.heading_deg); });
  std::vector<Plot> plots{map};
  if (headings) plots.push_back(heading);
  render_plots(dir, "plots.gp", plots);
  std::vector<DatasetFile> files{
      {"map.csv", 1, "fix.png's data: the fix, the truth (when known) and per stop its line of position: the "
                     "point (lat_deg, lon_deg) and half the line (dlat_deg, dlon_deg)"},
      {"fix.png", 1, "the fix, the truth and the stops' lines of position on a map"}};
  if (headings)
    files.push_back({"heading.png", 1, "the heading per stop against time, with the truth and the error when known"});
  files.push_back({"plots.gp", 1, "the gnuplot script of fix.png and heading.png"});
  return files;
}

}  // namespace

std::vector<DatasetFile> report_dataset_location(const std::filesystem::path& dir, const DatasetLocation& run,
                                                 bool plots) {
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
  if (plots) {
    const std::vector<DatasetFile> drawn = location_plots(dir, run);
    files.insert(files.end(), drawn.begin(), drawn.end());
  }
  return files;
}

}  // namespace polrig
