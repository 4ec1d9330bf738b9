#include "polrig/io/dofp_dataset.h"
#include "polrig/quoted.h"

#include <charconv>
#include <cmath>
#include <limits>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "polrig/io/csv.h"
#include "polrig/io/exr.h"
#include "polrig/io/measured.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/rig/rig.h"

namespace polrig {

namespace {

double attribute(const ExrImage& image, const std::string& name, const std::filesystem::path& file) {
  if (const std::optional<double> v = image.attributes.number(name)) return *v;
  throw DataError(fmt::format("{}: the header has no attribute {}", file.string(), name));
}

std::vector<double> channel(const ExrImage& image, const std::string& name, const std::filesystem::path& file) {
  for (const ExrChannel& c : image.floats)
    if (c.name == name) return {c.pixels.begin(), c.pixels.end()};
  throw DataError(fmt::format("{}: no channel {}", file.string(), name));
}

}  // namespace

namespace {

// The camera's size in the dataset's rig.yaml, when it has one for a camera: what its truth.exr
// must be (checked before the image is allocated).
std::optional<ExrSize> rig_camera_size(const std::filesystem::path& dir) {
  if (!std::filesystem::exists(dir / "rig.yaml")) return std::nullopt;
  const LoadedRig r = load_rig(dir / "rig.yaml");
  if (!r.rig.instrument().has(Instrument::kMosaic)) return std::nullopt;
  return ExrSize{r.rig.camera.width_px, r.rig.camera.height_px};
}

// The camera from a simulated dataset's truth.exr (report/dofp_dataset.cpp writes it).
void read_truth(const std::filesystem::path& truth_file, DofpDataset& d) {
  const ExrImage truth = read_exr_image(truth_file, rig_camera_size(truth_file.parent_path()));
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
    throw DataError(fmt::format("{}: {} × {} px: not one 2 × 2 cell", truth_file.string(), d.width, d.height));
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
        throw DataError(fmt::format("{}: attribute mosaic_deg '{}': expected 4 angles", truth_file.string(), quoted_value(text)));
      d.mosaic_deg = m;
    }
}

// The camera from a measured dataset's rig.yaml: the rig reader's camera, from keys the file
// gives (a default would silently be H17's camera, not the researcher's).
void read_rig_camera(const std::filesystem::path& dir, DofpDataset& d) {
  const std::filesystem::path rig_file = dir / "rig.yaml";
  if (!std::filesystem::exists(rig_file))
    throw DataError(fmt::format("{}: no truth.exr and no rig.yaml: a camera dataset needs one of them for the "
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
  if (!in) throw DataError(fmt::format("{}: cannot open the file", csv.string()));
  std::string line;
  const std::string header = "stop,theta_R_deg,t_s,utc,intensity,polarized,heading_deg,frames,file";
  if (!std::getline(in, line) || line != header)
    throw DataError(fmt::format("{}:1: expected the header {}", csv.string(), header));
  int n = 1;
  while (std::getline(in, line)) {
    ++n;
    if (line.empty()) continue;
    const std::vector<std::string> c = split_csv_line(line);
    if (c.size() != 9)
      throw DataError(fmt::format("{}:{}: {} columns (expected 9)", csv.string(), n, c.size()));
    DofpDatasetStop s;
    s.stop = csv_whole_number(c[0], csv, n, "stop", 0, std::numeric_limits<int>::max());
    s.theta_R_deg = csv_number(c[1], csv, n, "theta_R_deg");
    s.t_s = csv_number(c[2], csv, n, "t_s");
    s.utc = csv_utc(c[3], csv, n, "utc");
    s.intensity = csv_nonnegative(c[4], csv, n, "intensity");
    s.polarized = csv_flag(c[5], csv, n, "polarized");
    if (!c[6].empty()) s.heading_deg = csv_number(c[6], csv, n, "heading_deg");
    s.frames = csv_whole_number(c[7], csv, n, "frames", 1, kMaxFramesPerStop);
    s.file = c[8];
    d.stops.push_back(std::move(s));
  }
  return d;
}

namespace {
ExrSize size_of(const DofpDataset& dataset) { return {dataset.width, dataset.height}; }

// The mean of the raw channels of `image` (a stop's file, or rows of it): raw_sum / frames, or
// the frames' sum / frames (the same values: the sum of integers is exact).
// A raw channel's pixels against the ADC's range (device.adc_bits; unchecked when unknown): at most
// 2^bits − 1 DN a frame, `frames` times that for raw_sum.
void check_adc(const ExrUintChannel& c, std::size_t n, int adc_bits, int frames, const std::filesystem::path& file) {
  if (adc_bits <= 0) return;
  const std::uint64_t full = (std::uint64_t{1} << adc_bits) - 1, limit = full * static_cast<std::uint64_t>(frames);
  for (std::size_t i = 0; i < n; ++i)
    if (c.pixels[i] > limit)
      throw DataError(fmt::format("{}: channel {}: pixel {} holds {} DN, above the {}-bit ADC's {} DN{}", file.string(),
                                  c.name, i, c.pixels[i], adc_bits, full,
                                  frames > 1 ? fmt::format(" × {} frames", frames) : std::string()));
}

std::vector<double> mean_of(const ExrImage& image, const DofpDatasetStop& s, const std::filesystem::path& file,
                            int rows, int adc_bits) {
  const std::size_t n = static_cast<std::size_t>(image.width) * static_cast<std::size_t>(rows);
  std::vector<double> mean(n, 0.0);
  int frames = 0;
  for (const ExrUintChannel& c : image.uints) {
    if (c.name == "raw_sum") {
      check_adc(c, n, adc_bits, s.frames, file);
      for (std::size_t i = 0; i < n; ++i) mean[i] = double(c.pixels[i]) / s.frames;
      return mean;
    }
    if (c.name.rfind("raw.", 0) == 0) {
      check_adc(c, n, adc_bits, 1, file);
      for (std::size_t i = 0; i < n; ++i) mean[i] += c.pixels[i];
      ++frames;
    }
  }
  if (frames != s.frames)
    throw DataError(fmt::format("{}: {} raw frames (stops.csv says {})", file.string(), frames, s.frames));
  for (double& v : mean) v /= frames;
  return mean;
}
}  // namespace

std::vector<double> read_dofp_mean_frame(const DofpDataset& dataset, std::size_t stop_index) {
  const DofpDatasetStop& s = dataset.stops.at(stop_index);
  const std::filesystem::path file = dataset.dir / s.file;
  const ExrImage image = read_exr_image(file, size_of(dataset), ExrThreads::ThisThread);
  return mean_of(image, s, file, image.height, dataset.adc_bits);
}

std::vector<double> read_dofp_mean_rows(const DofpDataset& dataset, std::size_t stop_index, int first_row, int rows) {
  const DofpDatasetStop& s = dataset.stops.at(stop_index);
  const std::filesystem::path file = dataset.dir / s.file;
  if (first_row < 0 || rows < 1 || first_row > dataset.height - rows)
    throw std::out_of_range(fmt::format("rows {} to {} of a {}-row camera", first_row, first_row + rows - 1, dataset.height));
  const ExrImage image = read_exr_rows(file, first_row, rows, nullptr, size_of(dataset), ExrThreads::ThisThread);
  return mean_of(image, s, file, rows, dataset.adc_bits);
}

std::vector<std::vector<std::uint16_t>> read_dofp_frames(const DofpDataset& dataset, std::size_t stop_index) {
  const DofpDatasetStop& s = dataset.stops.at(stop_index);
  const std::filesystem::path file = dataset.dir / s.file;
  const ExrImage image = read_exr_image(file, size_of(dataset), ExrThreads::ThisThread);
  std::vector<std::vector<std::uint16_t>> frames;
  for (const ExrUintChannel& c : image.uints)
    if (c.name.rfind("raw.", 0) == 0) {
      std::vector<std::uint16_t> f(c.pixels.size());
      for (std::size_t i = 0; i < f.size(); ++i) {
        if (c.pixels[i] > 65535) throw DataError(fmt::format("{}: channel {}: a DN above 65535", file.string(), c.name));
        f[i] = static_cast<std::uint16_t>(c.pixels[i]);
      }
      frames.push_back(std::move(f));
    }
  if (frames.empty())
    throw DataError(fmt::format("{}: no raw.NNN channels (a dataset of per-stop sums keeps no frames)", file.string()));
  return frames;
}

DofpTruth read_dofp_parameters(const std::filesystem::path& params_exr, const DofpDataset& dataset) {
  const ExrImage image = read_exr_image(params_exr, size_of(dataset));
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
