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

namespace polrig {

namespace {

double yaml_number(const YAML::Node& node, const char* key, const std::filesystem::path& file) {
  const YAML::Node v = node[key];
  double x = 0;
  try {
    if (!v || !v.IsScalar()) throw YAML::Exception(YAML::Mark::null_mark(), "missing");
    x = v.as<double>();
  } catch (const YAML::Exception&) {
    throw std::runtime_error(fmt::format("{}: virtual_camera.{}: expected a number", file.string(), key));
  }
  if (!std::isfinite(x)) throw std::runtime_error(fmt::format("{}: virtual_camera.{}: not finite", file.string(), key));
  return x;
}

}  // namespace

FourCameraDataset read_four_camera_dataset(const std::filesystem::path& dir) {
  FourCameraDataset d;
  d.dir = dir;
  const std::filesystem::path truth_file = dir / "truth.yaml";
  YAML::Node truth;
  try {
    truth = YAML::LoadFile(truth_file.string());
  } catch (const YAML::Exception& e) {
    throw std::runtime_error(fmt::format("{}: cannot read: {}", truth_file.string(), e.what()));
  }
  const YAML::Node v = truth["virtual_camera"];
  if (!v || !v.IsMap()) throw std::runtime_error(fmt::format("{}: no virtual_camera section", truth_file.string()));
  d.width = static_cast<int>(yaml_number(v, "width_px", truth_file));
  d.height = static_cast<int>(yaml_number(v, "height_px", truth_file));
  d.camera = {yaml_number(v, "f_c_px", truth_file), yaml_number(v, "cx_px", truth_file),
              yaml_number(v, "cy_px", truth_file)};

  const std::filesystem::path csv = dir / "stops.csv";
  std::ifstream in(csv);
  if (!in) throw std::runtime_error(fmt::format("{}: cannot open", csv.string()));
  std::string line;
  std::getline(in, line);
  const std::string header =
      "stop,utc,t_s,theta_R_deg,intensity,polarized,heading_deg,sun_x_cam1,sun_y_cam1,sun_z_cam1,"
      "sun_azimuth_deg,sun_zenith_deg,file";
  if (line != header) throw std::runtime_error(fmt::format("{}:1: expected the header {}", csv.string(), header));
  for (int n = 2; std::getline(in, line); ++n) {
    if (line.empty()) continue;
    const std::vector<std::string> c = split_csv_line(line);
    if (c.size() != 13) throw std::runtime_error(fmt::format("{}:{}: expected 13 columns, got {}", csv.string(), n, c.size()));
    FourCameraDatasetStop s;
    s.stop = static_cast<int>(csv_number(c[0], csv, n, "stop"));
    s.utc = c[1];
    s.t_s = csv_number(c[2], csv, n, "t_s");
    s.theta_R_deg = csv_number(c[3], csv, n, "theta_R_deg");
    s.intensity = csv_number(c[4], csv, n, "intensity");
    s.polarized = csv_number(c[5], csv, n, "polarized") != 0;
    if (!c[6].empty()) s.heading_deg = csv_number(c[6], csv, n, "heading_deg");
    if (!c[7].empty())
      s.sun_camera1 = Vec3{csv_number(c[7], csv, n, "sun_x_cam1"), csv_number(c[8], csv, n, "sun_y_cam1"),
                           csv_number(c[9], csv, n, "sun_z_cam1")};
    s.file = c[12];
    d.stops.push_back(std::move(s));
  }
  return d;
}

namespace {
const ExrChannel& float_channel(const ExrImage& image, const std::string& name, const std::filesystem::path& file) {
  for (const ExrChannel& c : image.floats)
    if (c.name == name) return c;
  throw std::runtime_error(fmt::format("{}: no channel {}", file.string(), name));
}
const ExrUintChannel& uint_channel(const ExrImage& image, const std::string& name, const std::filesystem::path& file) {
  for (const ExrUintChannel& c : image.uints)
    if (c.name == name) return c;
  throw std::runtime_error(fmt::format("{}: no channel {} (written with --layers fused or aop?)", file.string(), name));
}
ExrImage stop_image(const FourCameraDataset& d, std::size_t stop_index, std::filesystem::path& file) {
  if (stop_index >= d.stops.size())
    throw std::runtime_error(fmt::format("{}: stop {} (the dataset has {})", d.dir.string(), stop_index, d.stops.size()));
  file = d.dir / d.stops[stop_index].file;
  ExrImage image = read_exr_image(file);
  if (image.width != d.width || image.height != d.height)
    throw std::runtime_error(fmt::format("{}: {} × {} px (expected {} × {})", file.string(), image.width, image.height,
                                         d.width, d.height));
  return image;
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
      if (v > 65535) throw std::runtime_error(fmt::format("{}: cam{} holds {} (expected 16-bit DN)", file.string(), j + 1, v));
      raw[j].push_back(static_cast<std::uint16_t>(v));
    }
  }
  return raw;
}

}  // namespace polrig
