// The camera dataset's readers and the calibration on it (io/dofp_dataset.h,
// report/dofp_calibration_report.h, report/orientation_report.h): steps 1 and 2 on bands of rows
// give the whole frames' results bit for bit, and a measured dataset (no truth.exr; its camera in
// rig.yaml) calibrates and orients as the same dataset with its truth.exr.
#include <gtest/gtest.h>
#include <unistd.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "polrig/calib/dofp.h"
#include "polrig/io/dofp_dataset.h"
#include "polrig/io/exr.h"
#include "polrig/io/measured.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/report/dofp_calibration_report.h"
#include "polrig/report/dofp_dataset.h"
#include "polrig/report/orientation_report.h"

namespace {
using namespace polrig;
namespace fs = std::filesystem;

const std::string kSource = POLRIG_SOURCE_DIR;

fs::path fresh_dir(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / fmt::format("polrig_dofp_dataset_{}_{}", name, ::getpid());
  fs::remove_all(p);
  return p;
}

std::string text_of(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void write_text(const fs::path& file, const std::string& text) {
  std::ofstream(file, std::ios::binary) << text;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no error)";
}

#define EXPECT_HAS(text, part) EXPECT_NE(std::string(text).find(part), std::string::npos) << (text)

// The han2017 indoor rig on a 24 × 20 camera, 9 table angles at two intensities, 3 levels.
LoadedRig small_indoor() {
  return load_rig(kSource + "/rigs/han2017-indoor.yaml",
                  {{"device.width_px", "24"}, {"device.height_px", "20"}, {"schedule.step_deg", "40"},
                   {"schedule.stop_deg", "320"}, {"schedule.intensities", "[1, 0.5]"},
                   {"schedule.unpolarized_levels", "[0, 0.5, 1]"}, {"device.gain_spread", "0.03"},
                   {"device.misregistration_dx_px", "0.05"}, {"device.misregistration_rotation_deg", "0.5"}});
}

// The same bits, NaN included (a fit that never ran keeps NaN residuals).
bool same(double a, double b) { return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b); }
bool same(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (!same(a[i], b[i])) return false;
  return true;
}

void expect_same(const DofpCalibration& a, const DofpCalibration& b) {
  EXPECT_TRUE(same(a.step1.K, b.step1.K));
  EXPECT_TRUE(same(a.step1.b, b.step1.b));
  EXPECT_TRUE(same(a.step1.residual_rms_DN, b.step1.residual_rms_DN));
  EXPECT_EQ(a.step1.rank, b.step1.rank);
  EXPECT_EQ(a.step1.levels_used, b.step1.levels_used);
  EXPECT_EQ(a.step1.rank_deficient_pixels, b.step1.rank_deficient_pixels);
  EXPECT_EQ(a.step2.cells_x, b.step2.cells_x);
  EXPECT_EQ(a.step2.cells_y, b.step2.cells_y);
  EXPECT_EQ(a.step2.usable_cells, b.step2.usable_cells);
  ASSERT_EQ(a.step2.cells.size(), b.step2.cells.size());
  for (std::size_t i = 0; i < a.step2.cells.size(); ++i) {
    const DofpCellFit &x = a.step2.cells[i], &y = b.step2.cells[i];
    SCOPED_TRACE(fmt::format("cell {}", i));
    for (int j = 0; j < 4; ++j) EXPECT_TRUE(same(x.k[j], y.k[j]) && same(x.eps_deg[j], y.eps_deg[j]));
    EXPECT_TRUE(same(x.psi0_deg, y.psi0_deg) && same(x.dop, y.dop));
    EXPECT_TRUE(same(x.initial_rms_deg, y.initial_rms_deg) && same(x.final_rms_deg, y.final_rms_deg));
    EXPECT_EQ(x.termination, y.termination);
    EXPECT_EQ(x.message, y.message);
    EXPECT_EQ(x.iterations, y.iterations);
    EXPECT_EQ(x.rank, y.rank);
    EXPECT_EQ(x.observations, y.observations);
  }
  EXPECT_TRUE(same(a.table1.intensity, b.table1.intensity));
  EXPECT_TRUE(same(a.table1.theta_R_deg, b.table1.theta_R_deg));
  EXPECT_EQ(a.table1.cells_used, b.table1.cells_used);
  for (int r = 0; r < 3; ++r) {
    EXPECT_EQ(a.table1.rows[r].name, b.table1.rows[r].name);
    EXPECT_TRUE(same(a.table1.rows[r].error_deg, b.table1.rows[r].error_deg));
    EXPECT_TRUE(same(a.table1.rows[r].max_deg, b.table1.rows[r].max_deg));
    EXPECT_TRUE(same(a.table1.rows[r].mean_deg, b.table1.rows[r].mean_deg));
    EXPECT_TRUE(same(a.table1.rows[r].std_deg, b.table1.rows[r].std_deg));
  }
}

// Both steps on whole mean frames, as calibrate_dofp_dataset did before it read bands.
DofpCalibration whole_frames(const DofpDataset& d, bool view_projection = false) {
  DofpCalibrationOptions o;
  o.step2.mosaic_deg = d.mosaic_deg;
  if (view_projection) {
    o.step2.view_projection = true;
    o.step2.focal_px = d.f_c_px, o.step2.principal_x_px = d.cx, o.step2.principal_y_px = d.cy;
  }
  o.step1.saturation_DN = std::ldexp(1.0, d.adc_bits) - 1.0;
  std::vector<std::vector<double>> frames;
  for (std::size_t s = 0; s < d.stops.size(); ++s) frames.push_back(read_dofp_mean_frame(d, s));
  std::vector<DofpUnpolarizedLevel> levels;
  std::vector<DofpPolarizedStop> stops;
  for (std::size_t s = 0; s < d.stops.size(); ++s)
    if (d.stops[s].polarized)
      stops.push_back({d.stops[s].theta_R_deg, d.stops[s].intensity, frames[s]});
    else
      levels.push_back({d.stops[s].intensity, frames[s]});
  return calibrate_dofp(d.width, d.height, levels, stops, o);
}

// Sets pixel (col, row) of a per-stop-sum stop file to the ADC's top in every frame (clipped).
void saturate(const fs::path& file, int col, int row, int frames) {
  ExrImage image = read_exr_image(file);
  image.attributes = {};  // OpenEXR's own (pixelAspectRatio…) are not doubles to write back
  for (ExrUintChannel& c : image.uints)
    if (c.name == "raw_sum") c.pixels[static_cast<std::size_t>(row) * image.width + col] = 4095u * frames;
  write_exr_image(file, image, ExrCompression::Piz);
}

}  // namespace

TEST(DofpDatasetCalibration, BandsOfRowsGiveTheWholeFramesResultsBitForBit) {
  const fs::path dir = fresh_dir("bands");
  DofpDatasetOptions o;
  o.storage = DofpFrameStorage::Sum;
  write_dofp_dataset(small_indoor(), dir, o, "test", false);
  DofpDataset d = read_dofp_dataset(dir);
  ASSERT_EQ(d.adc_bits, 12);
  // Two pixels clipped at two of the three levels: step 1 leaves them undetermined (rank 1), and
  // step 2 names them in its cells' messages by their frame row (9 lies in a band's middle).
  for (int s = 0; s < 2; ++s) {
    saturate(dir / d.stops[s].file, 5, 9, d.stops[s].frames);
    saturate(dir / d.stops[s].file, 12, 0, d.stops[s].frames);
  }
  const DofpCalibration whole = whole_frames(d);
  ASSERT_EQ(whole.step1.rank_deficient_pixels, 2);
  EXPECT_EQ(whole.step2.cells[4 * 12 + 2].message, "step 1 left pixel (column 5, row 9) undetermined (rank 1)");
  EXPECT_GT(whole.step2.usable_cells, 100);
  for (int band : {2, 6, 20, 0}) {
    SCOPED_TRACE(fmt::format("bands of {} rows", band));
    expect_same(calibrate_dofp_dataset(d, {}, {}, band), whole);
  }
  EXPECT_HAS(error_of([&] { calibrate_dofp_dataset(d, {}, {}, 3); }), "bands of 3 rows");
  fs::remove_all(dir);
}

// With the view's projection each cell's model depends on where its rows are in the whole frame
// (its view): a band must see its cells' views, not those of a frame of its own height.
TEST(DofpDatasetCalibration, BandsOfRowsKeepEachCellsViewWithTheViewProjection) {
  const fs::path dir = fresh_dir("bands_projected");
  DofpDatasetOptions o;
  o.storage = DofpFrameStorage::Sum;
  write_dofp_dataset(small_indoor(), dir, o, "test", false);
  const DofpDataset d = read_dofp_dataset(dir);
  const DofpCalibration whole = whole_frames(d, true);
  EXPECT_GT(whole.step2.usable_cells, 100);
  DofpCalibrationOptions projected;
  projected.step2.view_projection = true;
  for (int band : {2, 6}) {
    SCOPED_TRACE(fmt::format("bands of {} rows", band));
    expect_same(calibrate_dofp_dataset(d, projected, {}, band), whole);
  }
  fs::remove_all(dir);
}

TEST(DofpDatasetCalibration, ARowBandOfAFileIsThoseRowsOfItsMeanFrame) {
  const fs::path dir = fresh_dir("rows");
  write_dofp_dataset(small_indoor(), dir, {}, "test", false);  // every frame
  const DofpDataset d = read_dofp_dataset(dir);
  const std::vector<double> whole = read_dofp_mean_frame(d, 4);
  const std::vector<double> band = read_dofp_mean_rows(d, 4, 6, 10);
  EXPECT_EQ(band, std::vector<double>(whole.begin() + 6 * 24, whole.begin() + 16 * 24));
  EXPECT_THROW(read_dofp_mean_rows(d, 4, 16, 6), std::out_of_range);
  fs::remove_all(dir);
}

// A measured dataset: the researcher's frames, stops.csv and rig.yaml, no truth.exr.
TEST(DofpMeasuredDataset, WithoutTruthExrCalibratesAsWithIt) {
  const fs::path with = fresh_dir("with"), without = fresh_dir("without");
  DofpDatasetOptions o;
  o.storage = DofpFrameStorage::Sum;
  write_dofp_dataset(small_indoor(), with, o, "test", false);
  fs::copy(with, without, fs::copy_options::recursive);
  fs::remove(without / "truth.exr");
  const DofpDataset a = read_dofp_dataset(with), b = read_dofp_dataset(without);
  ASSERT_TRUE(a.truth);
  EXPECT_FALSE(b.truth);
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  EXPECT_EQ(a.f_c_px, b.f_c_px);
  EXPECT_EQ(a.cx, b.cx);
  EXPECT_EQ(a.cy, b.cy);
  EXPECT_EQ(a.mosaic_deg, b.mosaic_deg);
  EXPECT_EQ(a.adc_bits, b.adc_bits);
  // Calibration never reads the truth: the same files, byte for byte.
  for (const fs::path& d : {with, without}) {
    const DofpCalibration c = calibrate_dofp_folder(d);
    fs::create_directory(d / "cal");
    report_dofp_calibration(d / "cal", c, false);
  }
  for (const char* f : {"params.exr", "table1.csv", "errors.csv", "cells.csv", "summary.csv"})
    EXPECT_EQ(text_of(with / "cal" / f), text_of(without / "cal" / f)) << f;
  // params.exr against a dataset without truth.exr takes the mosaic from rig.yaml.
  const DofpTruth p = read_dofp_parameters(without / "cal" / "params.exr", b);
  EXPECT_EQ(p.alpha_deg, a.truth->alpha_deg);
  fs::remove_all(with);
  fs::remove_all(without);
}

TEST(DofpMeasuredDataset, WithoutTruthExrOrientsAsWithItAndWithoutHeadingsHasNoErrors) {
  const fs::path with = fresh_dir("sky_with"), without = fresh_dir("sky_without");
  const LoadedRig rig = load_rig(kSource + "/rigs/han2017-outdoor.yaml",
                                 {{"device.width_px", "160"}, {"device.height_px", "120"}, {"device.focal_mm", "0.75"}});
  write_dofp_dataset(rig, with, {}, "test", false);
  fs::copy(with, without, fs::copy_options::recursive);
  fs::remove(without / "truth.exr");
  for (const fs::path& d : {with, without}) {
    fs::create_directory(d / "or");
    report_orientation(d / "or", orient_dofp_folder(d, ""), false);
  }
  const std::string csv = text_of(with / "or" / "orientation.csv");
  EXPECT_EQ(text_of(without / "or" / "orientation.csv"), csv);
  EXPECT_EQ(csv.find(",nan,ok"), std::string::npos);  // every solved frame has its heading error

  // The same frames without true headings (a researcher's stops.csv may not have them).
  std::istringstream in(text_of(without / "stops.csv"));
  std::string out, line;
  std::getline(in, line);
  out = line + "\n";
  while (std::getline(in, line)) {
    std::vector<std::string> c;
    std::istringstream cells(line);
    for (std::string v; std::getline(cells, v, ',');) c.push_back(v);
    ASSERT_EQ(c.size(), 9u);
    c[6].clear();
    out += fmt::format("{}\n", fmt::join(c, ","));
  }
  write_text(without / "stops.csv", out);
  const std::vector<FrameOrientation> frames = orient_dofp_folder(without, "");
  ASSERT_EQ(frames.size(), 40u);
  int headings = 0;
  for (const FrameOrientation& f : frames) {
    EXPECT_FALSE(f.true_heading_deg);
    for (const OrientationEstimate& e : f.estimates) headings += e.heading_deg.has_value();
  }
  EXPECT_GT(headings, 40);  // headings are still found; their errors are not defined
  fs::remove_all(without / "or");
  fs::create_directory(without / "or");
  report_orientation(without / "or", frames, false);
  std::istringstream rows(text_of(without / "or" / "orientation.csv"));
  std::getline(rows, line);
  while (std::getline(rows, line)) {
    std::vector<std::string> c;
    std::istringstream cells(line);
    for (std::string v; std::getline(cells, v, ',');) c.push_back(v);
    ASSERT_EQ(c.size(), 7u);
    EXPECT_EQ(c[5], "nan") << line;
  }
  fs::remove_all(with);
  fs::remove_all(without);
}

TEST(DofpMeasuredDataset, WithoutTruthExrTheRigMustGiveTheCamera) {
  const fs::path dir = fresh_dir("measured");
  DofpDatasetOptions o;
  o.storage = DofpFrameStorage::Sum;
  write_dofp_dataset(small_indoor(), dir, o, "test", false);
  fs::remove(dir / "truth.exr");
  fs::remove(dir / "rig.yaml");
  EXPECT_HAS(error_of([&] { read_dofp_dataset(dir); }), "no truth.exr and no rig.yaml");
  EXPECT_HAS(error_of([&] { calibrate_dofp_folder(dir); }), "no truth.exr and no rig.yaml");

  // A researcher's rig.yaml: the camera's keys, nothing else. Each one missing is named.
  const std::string camera =
      "device:\n  kind: dofp-camera\n  width_px: 24\n  height_px: 20\n  pixel_um: 7.4\n  focal_mm: 3\n"
      "  mosaic_deg: [0, 90, 45, 135]\n";
  write_text(dir / "rig.yaml", camera);
  const DofpDataset d = read_dofp_dataset(dir);
  EXPECT_EQ(d.adc_bits, 0);  // not given: no saturation level is assumed
  EXPECT_EQ(d.f_c_px, 3 / 7.4 * 1000);
  EXPECT_EQ(d.cx, 12);
  EXPECT_EQ(d.cy, 10);
  EXPECT_NO_THROW(calibrate_dofp_folder(dir));
  for (const char* key : {"width_px", "height_px", "pixel_um", "focal_mm", "mosaic_deg"}) {
    std::string without;
    std::istringstream in(camera);
    for (std::string line; std::getline(in, line);)
      if (line.find(std::string(key) + ":") == std::string::npos) without += line + "\n";
    write_text(dir / "rig.yaml", without);
    const std::string e = error_of([&] { read_dofp_dataset(dir); });
    EXPECT_HAS(e, (dir / "rig.yaml").string());
    EXPECT_HAS(e, fmt::format("key 'device.{}' is not given", key));
  }
  // Another frame size than the rig's: the stop's file is named.
  write_text(dir / "rig.yaml", "device:\n  kind: dofp-camera\n  width_px: 26\n  height_px: 20\n  pixel_um: 7.4\n"
                               "  focal_mm: 3\n  mosaic_deg: [0, 90, 45, 135]\n");
  EXPECT_HAS(error_of([&] { calibrate_dofp_folder(dir); }), "stop_0000.exr: 24 × 20 px (expected 26 × 20)");
  // A rig without frames.
  write_text(dir / "rig.yaml", "device:\n  d: 0.9\n");
  EXPECT_HAS(error_of([&] { read_dofp_dataset(dir); }), "device.kind six-photodiode");
  fs::remove_all(dir);
}

// Issue 23 §5.8: a pixel above the ADC's range (device.adc_bits: 12 bits here) is refused, naming
// the file, the channel and the pixel; calibrate --method dofp took it.
TEST(DofpDatasetCalibration, PixelsAboveTheAdcsRangeAreRefused) {
  const fs::path dir = fresh_dir("above_adc");
  DofpDatasetOptions o;
  o.storage = DofpFrameStorage::Sum;
  write_dofp_dataset(small_indoor(), dir, o, "test", false);
  const DofpDataset d = read_dofp_dataset(dir);
  ASSERT_EQ(d.adc_bits, 12);
  const fs::path file = dir / d.stops[1].file;
  saturate(file, 7, 0, d.stops[1].frames);  // 4095 DN a frame: the top, accepted
  EXPECT_NO_THROW(read_dofp_mean_frame(d, 1));
  ExrImage image = read_exr_image(file);
  image.attributes = {};
  for (ExrUintChannel& c : image.uints)
    if (c.name == "raw_sum") c.pixels[7] = 4096u * static_cast<std::uint32_t>(d.stops[1].frames);
  write_exr_image(file, image, ExrCompression::Piz);
  const std::string e = error_of([&] { calibrate_dofp_folder(dir); });
  EXPECT_HAS(e, file.string() + ": channel raw_sum: pixel 7 holds");
  EXPECT_HAS(e, "above the 12-bit ADC's 4095 DN");
  fs::remove_all(dir);
}
