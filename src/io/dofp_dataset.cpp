#include "polrig/io/dofp_dataset.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "polrig/io/exr.h"

namespace polrig {

namespace {

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) out.push_back(cell);
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

double number(const std::string& text, const std::filesystem::path& file, int line, const char* column) {
  double v = 0;
  const char* end = text.data() + text.size();
  const auto r = std::from_chars(text.data(), end, v);
  if (r.ec != std::errc() || r.ptr != end || !std::isfinite(v))
    throw std::runtime_error(fmt::format("{}:{}: column {}: '{}' is not a finite number", file.string(), line, column, text));
  return v;
}

double attribute(const ExrImage& image, const std::string& name, const std::filesystem::path& file) {
  for (const auto& [n, v] : image.attributes.doubles)
    if (n == name) return v;
  throw std::runtime_error(fmt::format("{}: the header has no attribute {}", file.string(), name));
}

std::vector<double> channel(const ExrImage& image, const std::string& name, const std::filesystem::path& file) {
  for (const ExrChannel& c : image.floats)
    if (c.name == name) return {c.pixels.begin(), c.pixels.end()};
  throw std::runtime_error(fmt::format("{}: no channel {}", file.string(), name));
}

}  // namespace

DofpDataset read_dofp_dataset(const std::filesystem::path& dir) {
  DofpDataset d;
  d.dir = dir;
  const std::filesystem::path truth_file = dir / "truth.exr";
  const ExrImage truth = read_exr_image(truth_file);
  d.width = truth.width, d.height = truth.height;
  d.f_c_px = attribute(truth, "f_c_px", truth_file);
  d.cx = attribute(truth, "cx_px", truth_file);
  d.cy = attribute(truth, "cy_px", truth_file);
  for (const auto& [name, value] : truth.attributes.doubles)
    if (name == "adc_bits" && value >= 1 && value <= 16 && value == std::floor(value)) d.adc_bits = static_cast<int>(value);
  d.truth.width = d.width, d.truth.height = d.height;
  d.truth.K = channel(truth, "K", truth_file);
  d.truth.b = channel(truth, "b", truth_file);
  d.truth.k = channel(truth, "k", truth_file);
  d.truth.eps_deg = channel(truth, "eps_deg", truth_file);
  d.truth.alpha_deg = channel(truth, "alpha_deg", truth_file);

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
    const std::vector<std::string> c = split(line);
    if (c.size() != 9)
      throw std::runtime_error(fmt::format("{}:{}: {} columns (expected 9)", csv.string(), n, c.size()));
    DofpDatasetStop s;
    s.stop = static_cast<int>(number(c[0], csv, n, "stop"));
    s.theta_R_deg = number(c[1], csv, n, "theta_R_deg");
    s.t_s = number(c[2], csv, n, "t_s");
    s.utc = c[3];
    s.intensity = number(c[4], csv, n, "intensity");
    const double polarized = number(c[5], csv, n, "polarized");
    if (polarized != 0 && polarized != 1)
      throw std::runtime_error(fmt::format("{}:{}: column polarized: {} (expected 0 or 1)", csv.string(), n, c[5]));
    s.polarized = polarized == 1;
    if (!c[6].empty()) s.heading_deg = number(c[6], csv, n, "heading_deg");
    const double frames = number(c[7], csv, n, "frames");
    if (frames < 1 || frames != std::floor(frames))
      throw std::runtime_error(fmt::format("{}:{}: column frames: {} (expected a whole number ≥ 1)", csv.string(), n, c[7]));
    s.frames = static_cast<int>(frames);
    s.file = c[8];
    d.stops.push_back(std::move(s));
  }
  return d;
}

std::vector<double> read_dofp_mean_frame(const DofpDataset& dataset, std::size_t stop_index) {
  const DofpDatasetStop& s = dataset.stops.at(stop_index);
  const std::filesystem::path file = dataset.dir / s.file;
  const ExrImage image = read_exr_image(file);
  const std::size_t n = static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height);
  if (image.width != dataset.width || image.height != dataset.height)
    throw std::runtime_error(fmt::format("{}: {} × {} px (the dataset's truth.exr: {} × {})", file.string(), image.width,
                                         image.height, dataset.width, dataset.height));
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
  t.alpha_deg = dataset.truth.alpha_deg;
  return t;
}

}  // namespace polrig
