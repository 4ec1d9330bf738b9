#include "polrig/io/four_camera_dataset.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "polrig/io/csv.h"
#include "polrig/io/exr.h"
#include "polrig/io/four_camera_calibration.h"
#include "polrig/io/measured.h"
#include "yaml_load.h"

namespace polrig {

namespace {

// A dataset's board.yaml: read, checked (size, aliases, nesting, keys given twice) and parsed as
// every YAML file polrig reads.
YAML::Node load_yaml_file(const std::filesystem::path& file) {
  const YAML::Node root = load_yaml<DataError>(read_yaml_file<DataError>(file, "dataset's YAML file"), file.string(),
                                               "a dataset's YAML nests 3 levels", kMaxYamlBytes);
  refuse_duplicate_keys<DataError>(root, file.string());
  return root;
}

// A measured dataset: the size from the first stop's EXR (one line block read), the virtual camera
// from its attributes when it holds fused layers.
void measured_size_and_camera(FourCameraDataset& d) {
  if (d.stops.empty())
    throw DataError(fmt::format("{}: no stop, and no truth.yaml to give the cameras' size",
                                         (d.dir / "stops.csv").string()));
  const std::filesystem::path file = d.dir / d.stops.front().file;
  const ExrImage first = read_exr_rows(file, 0, 1, &d.height);
  d.width = first.width;
  const ExrAttributes& a = first.attributes;
  const std::optional<double> f_c = a.number("f_c_px"), cx = a.number("cx_px"), cy = a.number("cy_px");
  if (f_c && cx && cy) d.camera = CameraIntrinsics{*f_c, *cx, *cy};
}

}  // namespace

FourCameraDataset read_four_camera_dataset(const std::filesystem::path& dir) {
  FourCameraDataset d;
  d.dir = dir;
  const std::filesystem::path truth_file = dir / "truth.yaml";
  const bool simulated = std::filesystem::exists(truth_file);
  if (simulated) {
    const std::optional<VirtualCameraSpec> v = read_four_camera_calibration(truth_file).virtual_camera;
    if (!v) throw DataError(fmt::format("{}: no virtual_camera section", truth_file.string()));
    d.width = v->width, d.height = v->height;
    d.camera = v->camera;
  }

  const std::filesystem::path csv = dir / "stops.csv";
  std::ifstream in(csv);
  if (!in) throw DataError(fmt::format("{}: cannot open", csv.string()));
  std::string line;
  std::getline(in, line);
  const std::string header =
      "stop,utc,t_s,theta_R_deg,intensity,polarized,heading_deg,sun_x_cam1,sun_y_cam1,sun_z_cam1,"
      "sun_azimuth_deg,sun_zenith_deg,file";
  if (line != header) throw DataError(fmt::format("{}:1: expected the header {}", csv.string(), header));
  for (int n = 2; std::getline(in, line); ++n) {
    if (line.empty()) continue;
    const std::vector<std::string> c = split_csv_line(line);
    if (c.size() != 13) throw DataError(fmt::format("{}:{}: expected 13 columns, got {}", csv.string(), n, c.size()));
    FourCameraDatasetStop s;
    s.stop = csv_whole_number(c[0], csv, n, "stop", 0, std::numeric_limits<int>::max());
    s.utc = csv_utc(c[1], csv, n, "utc");
    s.t_s = csv_number(c[2], csv, n, "t_s");
    s.theta_R_deg = csv_number(c[3], csv, n, "theta_R_deg");
    s.intensity = csv_nonnegative(c[4], csv, n, "intensity");
    s.polarized = csv_flag(c[5], csv, n, "polarized");
    if (!c[6].empty()) s.heading_deg = csv_number(c[6], csv, n, "heading_deg");
    if (!c[7].empty())
      s.sun_camera1 = Vec3{csv_number(c[7], csv, n, "sun_x_cam1"), csv_number(c[8], csv, n, "sun_y_cam1"),
                           csv_number(c[9], csv, n, "sun_z_cam1")};
    s.file = c[12];
    d.stops.push_back(std::move(s));
  }
  if (!simulated) measured_size_and_camera(d);
  return d;
}

namespace {
const ExrChannel& float_channel(const ExrImage& image, const std::string& name, const std::filesystem::path& file) {
  for (const ExrChannel& c : image.floats)
    if (c.name == name) return c;
  throw DataError(fmt::format("{}: no channel {}", file.string(), name));
}
const ExrUintChannel& uint_channel(const ExrImage& image, const std::string& name, const std::filesystem::path& file) {
  for (const ExrUintChannel& c : image.uints)
    if (c.name == name) return c;
  throw DataError(fmt::format("{}: no channel {} (written with --layers fused or aop?)", file.string(), name));
}
ExrImage stop_image(const FourCameraDataset& d, std::size_t stop_index, std::filesystem::path& file) {
  if (stop_index >= d.stops.size())
    throw DataError(fmt::format("{}: stop {} (the dataset has {})", d.dir.string(), stop_index, d.stops.size()));
  file = d.dir / d.stops[stop_index].file;
  return read_exr_image(file, ExrSize{d.width, d.height}, ExrThreads::ThisThread);
}
}  // namespace

FusedAopDop read_four_camera_fused(const FourCameraDataset& dataset, std::size_t stop_index) {
  std::filesystem::path file;
  const ExrImage image = stop_image(dataset, stop_index, file);
  const ExrChannel& aop = float_channel(image, "AoP", file);
  const ExrChannel& dop = float_channel(image, "DoP", file);
  const ExrUintChannel& valid = uint_channel(image, "valid", file);
  FusedAopDop out{{aop.pixels.begin(), aop.pixels.end()}, {dop.pixels.begin(), dop.pixels.end()}};
  for (std::size_t i = 0; i < valid.pixels.size(); ++i)
    if (!valid.pixels[i]) out.aop_deg[i] = out.dop[i] = std::numeric_limits<double>::quiet_NaN();
  return out;
}

std::array<std::vector<std::uint16_t>, 4> read_four_camera_raw(const FourCameraDataset& dataset, std::size_t stop_index) {
  std::filesystem::path file;
  const ExrImage image = stop_image(dataset, stop_index, file);
  std::array<std::vector<std::uint16_t>, 4> raw;
  for (std::size_t j = 0; j < 4; ++j) {
    const ExrUintChannel& c = uint_channel(image, fmt::format("cam{}", j + 1), file);
    raw[j].reserve(c.pixels.size());
    for (std::uint32_t v : c.pixels) {
      if (v > 65535) throw DataError(fmt::format("{}: cam{} holds {} (expected 16-bit DN)", file.string(), j + 1, v));
      raw[j].push_back(static_cast<std::uint16_t>(v));
    }
  }
  return raw;
}

}  // namespace polrig

namespace polrig {

namespace {
double board_number(const YAML::Node& root, const char* key, const std::filesystem::path& file) {
  const YAML::Node v = root[key];
  double x = 0;
  try {
    if (!v || !v.IsScalar()) throw YAML::Exception(YAML::Mark::null_mark(), "missing");
    x = v.as<double>();
  } catch (const YAML::Exception&) {
    throw DataError(fmt::format("{}: {}: expected a number", file.string(), key));
  }
  if (!std::isfinite(x)) throw DataError(fmt::format("{}: {}: not finite", file.string(), key));
  return x;
}
int board_count(const YAML::Node& root, const char* key, const std::filesystem::path& file, int lo, int hi) {
  const double x = board_number(root, key, file);
  if (x != std::floor(x) || x < lo || x > hi)
    throw DataError(fmt::format("{}: {}: expected an integer in [{}, {}], got {}", file.string(), key, lo, hi, x));
  return static_cast<int>(x);
}
}  // namespace

CheckerboardViews read_checkerboard_views(const std::filesystem::path& dir) {
  CheckerboardViews out;
  out.dir = dir;
  const std::filesystem::path yaml = dir / "checkerboard" / "board.yaml";
  if (!std::filesystem::exists(dir / "checkerboard")) return out;
  const YAML::Node root = load_yaml_file(yaml);
  if (!root.IsMap()) throw DataError(fmt::format("{}: expected a mapping", yaml.string()));
  out.board.views = board_count(root, "views", yaml, 0, 10000);
  out.board.inner_corners = {board_count(root, "inner_cols", yaml, 3, 100), board_count(root, "inner_rows", yaml, 3, 100)};
  out.board.square_mm = board_number(root, "square_mm", yaml);
  out.board.margin_mm = board_number(root, "margin_mm", yaml);
  out.width = board_count(root, "width_px", yaml, 2, 16384);
  out.height = board_count(root, "height_px", yaml, 2, 16384);
  if (!(out.board.square_mm > 0))
    throw DataError(fmt::format("{}: square_mm: expected > 0, got {}", yaml.string(), out.board.square_mm));

  const std::filesystem::path csv = dir / "checkerboard" / "poses.csv";
  std::ifstream in(csv);
  if (!in) throw DataError(fmt::format("{}: cannot open", csv.string()));
  std::string line;
  std::getline(in, line);
  const std::string header = "view,file,R_00,R_01,R_02,R_10,R_11,R_12,R_20,R_21,R_22,t_x_mm,t_y_mm,t_z_mm";
  if (line != header) throw DataError(fmt::format("{}:1: expected the header {}", csv.string(), header));
  static constexpr const char* kR[9] = {"R_00", "R_01", "R_02", "R_10", "R_11", "R_12", "R_20", "R_21", "R_22"};
  for (int n = 2; std::getline(in, line); ++n) {
    if (line.empty()) continue;
    const std::vector<std::string> c = split_csv_line(line);
    if (c.size() != 14) throw DataError(fmt::format("{}:{}: expected 14 columns, got {}", csv.string(), n, c.size()));
    const double view = csv_number(c[0], csv, n, "view");
    if (view != static_cast<double>(out.files.size() + 1))
      throw DataError(fmt::format("{}:{}: view {} (expected {})", csv.string(), n, c[0], out.files.size() + 1));
    out.files.push_back(c[1]);
    if (c[2].empty()) {
      out.poses.emplace_back();
      continue;
    }
    BoardPose p;
    for (std::size_t i = 0; i < 9; ++i) p.R[i] = csv_number(c[2 + i], csv, n, kR[i]);
    p.t = {csv_number(c[11], csv, n, "t_x_mm"), csv_number(c[12], csv, n, "t_y_mm"), csv_number(c[13], csv, n, "t_z_mm")};
    out.poses.emplace_back(p);
  }
  if (static_cast<int>(out.files.size()) != out.board.views)
    throw DataError(fmt::format("{}: {} views (board.yaml says {})", csv.string(), out.files.size(), out.board.views));
  return out;
}

std::array<std::vector<std::uint16_t>, 4> read_checkerboard_view(const CheckerboardViews& views, std::size_t v) {
  if (v >= views.files.size())
    throw DataError(fmt::format("{}: checkerboard view {} (the dataset has {})", views.dir.string(), v + 1,
                                         views.files.size()));
  const std::filesystem::path file = views.dir / views.files[v];
  const ExrImage image = read_exr_image(file, ExrSize{views.width, views.height});
  std::array<std::vector<std::uint16_t>, 4> raw;
  for (std::size_t j = 0; j < 4; ++j) {
    const ExrUintChannel& c = uint_channel(image, fmt::format("cam{}", j + 1), file);
    raw[j].reserve(c.pixels.size());
    for (std::uint32_t x : c.pixels) {
      if (x > 65535) throw DataError(fmt::format("{}: cam{} holds {} (expected 16-bit DN)", file.string(), j + 1, x));
      raw[j].push_back(static_cast<std::uint16_t>(x));
    }
  }
  return raw;
}

std::optional<FourCameraGeometryTruth> read_four_camera_geometry_truth(const std::filesystem::path& dir) {
  const std::filesystem::path file = dir / "truth.yaml";
  if (!std::filesystem::exists(file)) return std::nullopt;  // a measured dataset
  const FourCameraCalibrationFile f = read_four_camera_calibration(file);
  FourCameraGeometryTruth t;
  for (std::size_t j = 0; j < 4; ++j) {
    t.camera[j] = f.model.camera[j];
    if (f.R_j1[j]) t.camera[j].R = *f.R_j1[j];  // as written: rvec_deg rounds it
    t.position_mm[j] = f.position_mm[j];
  }
  return t;
}

}  // namespace polrig
