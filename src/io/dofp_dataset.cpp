#include "polrig/io/dofp_dataset.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "polrig/io/csv.h"
#include "polrig/io/exr.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/rig/rig.h"

namespace polrig {

namespace {

double attribute(const ExrImage& image, const std::string& name, const std::filesystem::path& file) {
  if (const std::optional<double> v = image.attributes.number(name)) return *v;
  throw std::runtime_error(fmt::format("{}: the header has no attribute {}", file.string(), name));
}

std::vector<double> channel(const ExrImage& image, const std::string& name, const std::filesystem::path& file) {
  for (const ExrChannel& c : image.floats)
    if (c.name == name) return {c.pixels.begin(), c.pixels.end()};
  throw std::runtime_error(fmt::format("{}: no channel {}", file.string(), name));
}

}  // namespace

namespace {

// The camera from a simulated dataset's truth.exr (report/dofp_dataset.cpp writes it).
void read_truth(const std::filesystem::path& truth_file, DofpDataset& d) {
  const ExrImage truth = read_exr_image(truth_file);
  d.width = truth.width, d.height = truth.height;
  d.f_c_px = attribute(truth, "f_c_px", truth_file);
  d.cx = attribute(truth, "cx_px", truth_file);
  d.cy = attribute(truth, "cy_px", truth_file);
  for (const auto& [name, value] : truth.attributes.doubles)
    if (name == "adc_bits" && value >= 1 && value <= 16 && value == std::floor(value)) d.adc_bits = static_cast<int>(value);
  DofpTruth& t = d.truth.emplace();
  t.width = d.width, t.height = d.height;
  t.K = channel(truth, "K", truth_file);
  t.b = channel(truth, "b", truth_file);
  t.k = channel(truth, "k", truth_file);
  t.eps_deg = channel(truth, "eps_deg", truth_file);
  t.alpha_deg = channel(truth, "alpha_deg", truth_file);
  if (d.width < 2 || d.height < 2)
    throw std::runtime_error(fmt::format("{}: {} × {} px: not one 2 × 2 cell", truth_file.string(), d.width, d.height));
  // The mosaic as written (the mosaic_deg attribute, exact); the first cell's float alpha_deg
  // for a file without it.
  for (std::size_t j = 0; j < 4; ++j) d.mosaic_deg[j] = t.alpha_deg[(j / 2) * static_cast<std::size_t>(d.width) + j % 2];
  for (const auto& [name, text] : truth.attributes.strings)
    if (name == "mosaic_deg") {
      std::istringstream in(text);
      std::array<double, 4> m{};
      for (double& v : m) in >> v;
      std::string rest;
      if (!in || (in >> rest) || !std::isfinite(m[0] + m[1] + m[2] + m[3]))
        throw std::runtime_error(fmt::format("{}: attribute mosaic_deg '{}': expected 4 angles", truth_file.string(), text));
      d.mosaic_deg = m;
    }
}

// The camera from a measured dataset's rig.yaml: the rig reader's camera, from keys the file
// gives (a default would silently be H17's camera, not the researcher's).
void read_rig_camera(const std::filesystem::path& dir, DofpDataset& d) {
  const std::filesystem::path rig_file = dir / "rig.yaml";
  if (!std::filesystem::exists(rig_file))
    throw std::runtime_error(fmt::format("{}: no truth.exr and no rig.yaml: a camera dataset needs one of them for the "
                                         "camera's intrinsics and mosaic (docs/formats.md §6.14)", dir.string()));
  const LoadedRig r = load_rig(rig_file);
  require_instrument(r.rig, Instrument::kFrames, "a camera dataset without truth.exr", r.origin);
  for (const char* key : {"device.width_px", "device.height_px", "device.pixel_um", "device.focal_mm", "device.mosaic_deg"})
    if (!r.given.count(key))
      throw RigError(fmt::format("{}: key '{}' is not given: without truth.exr the dataset's rig.yaml must give the "
                                 "camera's device.width_px, height_px, pixel_um, focal_mm and mosaic_deg",
                                 rig_file.string(), key));
  const DofpCameraSpec& c = r.rig.camera;
  d.width = c.width_px, d.height = c.height_px;
  d.f_c_px = focal_px(c);
  d.cx = 0.5 * d.width, d.cy = 0.5 * d.height;  // as truth.exr's cx_px, cy_px
  d.adc_bits = r.given.count("device.adc_bits") ? c.adc_bits : 0;
  d.mosaic_deg = c.mosaic_deg;
}

}  // namespace

DofpDataset read_dofp_dataset(const std::filesystem::path& dir) {
  DofpDataset d;
  d.dir = dir;
  const std::filesystem::path truth_file = dir / "truth.exr";
  if (std::filesystem::exists(truth_file))
    read_truth(truth_file, d);
  else
    read_rig_camera(dir, d);

  const std::filesystem::path csv = dir / "stops.csv";
  std::ifstream in(csv);
  if (!in) throw std::runtime_error(fmt::format("{}: cannot open the file", csv.string()));
  std::string line;
  const std::string header = "stop,theta_R_deg,t_s,utc,intensity,polarized,heading_deg,frames,file";
  if (!std::getline(in, line) || line != header)
    throw std::runtime_error(fmt::format("{}:1: expected the header {}", csv.string(), header));
  int n = 1;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty()) continue;
    const std::vector<std::string> c = split_csv_line(line);
    if (c.size() != 9)
      throw std::runtime_error(fmt::format("{}:{}: {} columns (expected 9)", csv.string(), n, c.size()));
    DofpDatasetStop s;
    s.stop = static_cast<int>(csv_number(c[0], csv, n, "stop"));
    s.theta_R_deg = csv_number(c[1], csv, n, "theta_R_deg");
    s.t_s = csv_number(c[2], csv, n, "t_s");
    s.utc = c[3];
    s.intensity = csv_number(c[4], csv, n, "intensity");
    const double polarized = csv_number(c[5], csv, n, "polarized");
    if (polarized != 0 && polarized != 1)
      throw std::runtime_error(fmt::format("{}:{}: column polarized: {} (expected 0 or 1)", csv.string(), n, c[5]));
    s.polarized = polarized == 1;
    if (!c[6].empty()) s.heading_deg = csv_number(c[6], csv, n, "heading_deg");
    const double frames = csv_number(c[7], csv, n, "frames");
    if (frames < 1 || frames != std::floor(frames))
      throw std::runtime_error(fmt::format("{}:{}: column frames: {} (expected a whole number ≥ 1)", csv.string(), n, c[7]));
    s.frames = static_cast<int>(frames);
    s.file = c[8];
    d.stops.push_back(std::move(s));
  }
  return d;
}

namespace {
void check_size(const std::filesystem::path& file, int width, int height, const DofpDataset& dataset) {
  if (width != dataset.width || height != dataset.height)
    throw std::runtime_error(fmt::format("{}: {} × {} px (the dataset's camera: {} × {})", file.string(), width, height,
                                         dataset.width, dataset.height));
}

// The mean of the raw channels of `image` (a stop's file, or rows of it): raw_sum / frames, or
// the frames' sum / frames (the same values: the sum of integers is exact).
std::vector<double> mean_of(const ExrImage& image, const DofpDatasetStop& s, const std::filesystem::path& file,
                            int rows) {
  const std::size_t n = static_cast<std::size_t>(image.width) * static_cast<std::size_t>(rows);
  std::vector<double> mean(n, 0.0);
  int frames = 0;
  for (const ExrUintChannel& c : image.uints) {
    if (c.name == "raw_sum") {
      for (std::size_t i = 0; i < n; ++i) mean[i] = double(c.pixels[i]) / s.frames;
      return mean;
    }
    if (c.name.rfind("raw.", 0) == 0) {
      for (std::size_t i = 0; i < n; ++i) mean[i] += c.pixels[i];
      ++frames;
    }
  }
  if (frames != s.frames)
    throw std::runtime_error(fmt::format("{}: {} raw frames (stops.csv says {})", file.string(), frames, s.frames));
  for (double& v : mean) v /= frames;
  return mean;
}
}  // namespace

std::vector<double> read_dofp_mean_frame(const DofpDataset& dataset, std::size_t stop_index) {
  const DofpDatasetStop& s = dataset.stops.at(stop_index);
  const std::filesystem::path file = dataset.dir / s.file;
  const ExrImage image = read_exr_image(file);
  check_size(file, image.width, image.height, dataset);
  return mean_of(image, s, file, image.height);
}

std::vector<double> read_dofp_mean_rows(const DofpDataset& dataset, std::size_t stop_index, int first_row, int rows) {
  const DofpDatasetStop& s = dataset.stops.at(stop_index);
  const std::filesystem::path file = dataset.dir / s.file;
  if (first_row < 0 || rows < 1 || first_row > dataset.height - rows)
    throw std::out_of_range(fmt::format("rows {} to {} of a {}-row camera", first_row, first_row + rows - 1, dataset.height));
  int height = 0;
  const ExrImage image = read_exr_rows(file, first_row, rows, &height);
  check_size(file, image.width, height, dataset);
  return mean_of(image, s, file, rows);
}

std::vector<std::vector<std::uint16_t>> read_dofp_frames(const DofpDataset& dataset, std::size_t stop_index) {
  const DofpDatasetStop& s = dataset.stops.at(stop_index);
  const std::filesystem::path file = dataset.dir / s.file;
  const ExrImage image = read_exr_image(file);
  std::vector<std::vector<std::uint16_t>> frames;
  for (const ExrUintChannel& c : image.uints)
    if (c.name.rfind("raw.", 0) == 0) {
      std::vector<std::uint16_t> f(c.pixels.size());
      for (std::size_t i = 0; i < f.size(); ++i) {
        if (c.pixels[i] > 65535) throw std::runtime_error(fmt::format("{}: channel {}: a DN above 65535", file.string(), c.name));
        f[i] = static_cast<std::uint16_t>(c.pixels[i]);
      }
      frames.push_back(std::move(f));
    }
  if (frames.empty())
    throw std::runtime_error(fmt::format("{}: no raw.NNN channels (a dataset of per-stop sums keeps no frames)", file.string()));
  return frames;
}

DofpTruth read_dofp_parameters(const std::filesystem::path& params_exr, const DofpDataset& dataset) {
  const ExrImage image = read_exr_image(params_exr);
  if (image.width != dataset.width || image.height != dataset.height)
    throw std::runtime_error(fmt::format("{}: {} × {} px (the dataset {}: {} × {})", params_exr.string(), image.width,
                                         image.height, dataset.dir.string(), dataset.width, dataset.height));
  DofpTruth t;
  t.width = image.width, t.height = image.height;
  t.K = channel(image, "K", params_exr);
  t.b = channel(image, "b", params_exr);
  t.k = channel(image, "k", params_exr);
  t.eps_deg = channel(image, "eps_deg", params_exr);
  t.alpha_deg.resize(t.K.size());
  for (std::size_t p = 0; p < t.alpha_deg.size(); ++p)
    t.alpha_deg[p] = dataset.mosaic_deg[(p / static_cast<std::size_t>(t.width)) % 2 * 2 + p % static_cast<std::size_t>(t.width) % 2];
  return t;
}

}  // namespace polrig
