// The plots a command writes show the CSV columns their legends name. gnuplot itself reads each
// folder's plots.gp (switched from PNG to its `set table` text output), and every plotted point
// is compared with the column read by its header name from the CSV beside it.
#include <gtest/gtest.h>
#include <fmt/format.h>

#include <cmath>
#include <map>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "polrig/calib/dofp_polarization.h"
#include "polrig/io/dofp_dataset.h"
#include "polrig/io/exr.h"
#include "support.h"

namespace polrig::test {
namespace {

// One plotted curve as gnuplot tabulated it: its legend and its (x, y) points.
struct Curve {
  std::vector<double> x, y;
};

// The curves of every plot of DIR/plots.gp by title, as gnuplot tabulated them (tests/support.h's
// tabulate_script): x and y of each row.
std::map<std::string, Curve> tabulate(const fs::path& dir) {
  std::map<std::string, Curve> curves;
  for (const auto& [png, plot] : tabulate_script(dir, "plots.gp"))
    for (const auto& [title, rows] : plot)
      for (const std::vector<double>& row : rows) {
        curves[title].x.push_back(row.at(0));
        curves[title].y.push_back(row.at(1));
      }
  return curves;
}

// Column `name` of a CSV, as numbers, times `scale`.
std::vector<double> column(const Csv& csv, const std::string& name, double scale = 1) {
  std::vector<double> v;
  const std::size_t c = csv.col(name);
  for (const auto& row : csv.rows) v.push_back(std::stod(row[c]) * scale);
  return v;
}

std::vector<double> difference(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> d(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) d[i] = a[i] - b[i];
  return d;
}

// gnuplot's table prints 6 significant digits.
void expect_curve(const std::map<std::string, Curve>& curves, const std::string& title,
                  const std::vector<double>& x, const std::vector<double>& y) {
  const auto it = curves.find(title);
  ASSERT_NE(it, curves.end()) << "no curve titled " << title;
  const Curve& c = it->second;
  ASSERT_EQ(c.x.size(), x.size()) << title;
  for (std::size_t i = 0; i < x.size(); ++i) {
    EXPECT_NEAR(c.x[i], x[i], 1e-5 * std::abs(x[i]) + 1e-9) << title << ", point " << i;
    EXPECT_NEAR(c.y[i], y[i], 1e-5 * std::abs(y[i]) + 1e-9) << title << ", point " << i;
  }
}

class Plots : public PolrigTest, public ::testing::WithParamInterface<const char*> {
 protected:
  Plots() : PolrigTest("polrig_test_plots_", "logs") {}
};

class PlotsOfDatasets : public PolrigTest {
 protected:
  PlotsOfDatasets() : PolrigTest("polrig_test_dataset_plots_", "logs") {}
};

// Every shipped six-photodiode rig: indoor, the CS simulation and the four time-dependent
// outdoor runs (whose t_s column once shifted every plotted column by one).
TEST_P(Plots, SimulatePlotsTheStopsColumnsTheirLegendsName) {
  if (!gnuplot_present()) GTEST_SKIP() << "no gnuplot";
  const std::string rig = std::string(POLRIG_SOURCE_DIR "/rigs/") + GetParam();
  ok("simulate " + shell_quote(rig) + " --set schedule.samples_per_stop=4 -o " + shell_quote(tmp / "sim"));
  const std::map<std::string, Curve> curves = tabulate(tmp / "sim");
  const Csv stops = read_csv(tmp / "sim" / "stops.csv");
  const std::vector<double> theta = column(stops, "theta_R_deg");
  for (int i = 1; i <= 3; ++i) {
    const std::string V = fmt::format("V{}", i);
    const std::vector<double> ideal = column(stops, V + "_ideal", 1e3);
    expect_curve(curves, V + " ideal", theta, ideal);
    expect_curve(curves, V + " measured", theta, column(stops, V, 1e3));
    expect_curve(curves, fmt::format("Δ{0} = {0},ecc - {0},ideal", V), theta,
                 difference(column(stops, V + "_ecc", 1e3), ideal));
    expect_curve(curves, V + " measured - " + V + ",ideal", theta,
                 difference(column(stops, V, 1e3), ideal));
  }
}


// A number of a preview's CSV as the dataset's value: shortest round trip, "nan" where none.
std::string csv_value(double v) { return std::isfinite(v) ? fmt::format("{}", v) : std::string("nan"); }

// The curve of `png` titled `title`: gnuplot's rows (x, y, value for an image).
const std::vector<std::vector<double>>& curve_of(const std::vector<std::pair<std::string, TabulatedCurves>>& plots,
                                                 const std::string& png, const std::string& title) {
  static const std::vector<std::vector<double>> none;
  for (const auto& [name, curves] : plots)
    if (name == png)
      for (const auto& [t, rows] : curves)
        if (t == title) return rows;
  ADD_FAILURE() << png << ": no curve titled " << title;
  return none;
}

// Each preview PNG shows its CSV's columns by name: gnuplot's tabulated image is x_px, y_px and
// the column, point for point (6 significant digits).
void expect_previews_plot_their_csv(const fs::path& previews, const std::vector<std::string>& stems) {
  const auto plots = tabulate_script(previews, "previews.gp");
  ASSERT_EQ(plots.size(), 3 * stems.size());
  for (const std::string& stem : stems) {
    const Csv csv = read_csv(previews / (stem + ".csv"));
    for (const auto& [suffix, title, column] : {std::tuple{"aop", "AoP", "aop_deg"}, {"dop", "DoP", "dop"}, {"s0", "S0", "S0"}}) {
      const auto& rows = curve_of(plots, fmt::format("{}_{}.png", stem, suffix), title);
      ASSERT_EQ(rows.size(), csv.rows.size()) << stem << " " << title;
      for (std::size_t i = 0; i < rows.size(); ++i) {
        ASSERT_EQ(rows[i].size(), 3u) << stem << " " << title << ", point " << i;
        const auto at = [&](const char* name) { return std::stod(csv.rows[i][csv.col(name)]); };
        EXPECT_NEAR(rows[i][0], at("x_px"), 1e-5 * at("x_px")) << stem << " " << title << ", point " << i;
        EXPECT_NEAR(rows[i][1], at("y_px"), 1e-5 * at("y_px")) << stem << " " << title << ", point " << i;
        const double v = at(column);
        if (std::isnan(v)) EXPECT_TRUE(std::isnan(rows[i][2])) << stem << " " << title << ", point " << i;
        else EXPECT_NEAR(rows[i][2], v, 1e-5 * std::abs(v) + 1e-12) << stem << " " << title << ", point " << i;
      }
    }
  }
}

// A camera dataset's previews (issue 23 §4): the first and last stop's AoP, DoP and S0, in the
// manifest, drawn from CSVs whose values are the dataset's own: each 2 × 2 cell's polarization of
// the stop's mean frame as read back from the dataset (nominal parameters).
TEST_F(PlotsOfDatasets, DofpDatasetPreviewsShowTheCellsOfTheFirstAndLastMeanFrames) {
  if (!gnuplot_present()) GTEST_SKIP() << "no gnuplot";
  const fs::path dir = tmp / "dofp";
  ok("simulate " + shell_quote(std::string(POLRIG_SOURCE_DIR "/rigs/han2017-indoor.yaml")) +
     " --set device.width_px=32 --set device.height_px=24 --set schedule.step_deg=180 --set schedule.stop_deg=180"
     " --set 'schedule.intensities=[1]' --set 'schedule.unpolarized_levels=[0.5]' -o " + shell_quote(dir));
  const std::string manifest = read_file(dir / "manifest.yaml");
  for (const char* stem : {"stop_0000", "stop_0002"})
    for (const char* file : {".csv", "_aop.png", "_dop.png", "_s0.png"})
      EXPECT_HAS(manifest, fmt::format("previews/{}{}:", stem, file));
  EXPECT_LACKS(manifest, "stop_0001_");
  const DofpDataset d = read_dofp_dataset(dir);
  ASSERT_EQ(d.stops.size(), 3u);
  for (std::size_t s : {std::size_t{0}, std::size_t{2}}) {
    const DofpCellPolarization cells =
        dofp_cell_polarization(read_dofp_mean_frame(d, s), nominal_dofp_parameters(d.width, d.height, d.mosaic_deg));
    const Csv csv = read_csv(dir / "previews" / fmt::format("stop_{:04}.csv", s));
    ASSERT_EQ(csv.rows.size(), static_cast<std::size_t>(cells.cells_x * cells.cells_y));
    for (const auto& row : csv.rows) {
      const int cx = std::stoi(row[csv.col("cell_x")]), cy = std::stoi(row[csv.col("cell_y")]);
      const std::size_t k = static_cast<std::size_t>(cy * cells.cells_x + cx);
      EXPECT_EQ(row[csv.col("x_px")], fmt::format("{}", 2 * cx + 1));
      EXPECT_EQ(row[csv.col("y_px")], fmt::format("{}", 2 * cy + 1));
      EXPECT_EQ(row[csv.col("aop_deg")], csv_value(cells.aop_deg[k])) << s << " " << cx << " " << cy;
      EXPECT_EQ(row[csv.col("dop")], csv_value(cells.dop[k])) << s << " " << cx << " " << cy;
      EXPECT_EQ(row[csv.col("S0")], csv_value(cells.S0[k])) << s << " " << cx << " " << cy;
    }
  }
  expect_previews_plot_their_csv(dir / "previews", {"stop_0000", "stop_0002"});
  // --no-plots: no previews, the rest the same bytes.
  const fs::path bare = tmp / "dofp_bare";
  ok("simulate " + shell_quote(std::string(POLRIG_SOURCE_DIR "/rigs/han2017-indoor.yaml")) +
     " --set device.width_px=32 --set device.height_px=24 --set schedule.step_deg=180 --set schedule.stop_deg=180"
     " --set 'schedule.intensities=[1]' --set 'schedule.unpolarized_levels=[0.5]' --no-plots -o " + shell_quote(bare));
  EXPECT_FALSE(fs::exists(bare / "previews"));
  EXPECT_LACKS(read_file(bare / "manifest.yaml"), "  previews/stop_");
  for (const char* f : {"stops.csv", "truth.exr", "frames/stop_0000.exr", "frames/stop_0002.exr"})
    EXPECT_EQ(read_file(bare / f), read_file(dir / f)) << f;
}

// The four cameras' previews: the fused AoP, DoP and S0 of the first and last stop, as the stop's
// EXR holds them (float), nan where the fused pixel is not valid.
TEST_F(PlotsOfDatasets, FourCameraDatasetPreviewsShowTheFusedImageOfTheFirstAndLastStop) {
  if (!gnuplot_present()) GTEST_SKIP() << "no gnuplot";
  const fs::path dir = tmp / "w16";
  ok("simulate " + shell_quote(std::string(POLRIG_SOURCE_DIR "/rigs/wang2016-static.yaml")) +
     " --layers fused --set schedule.count=3 --set schedule.dwell_s=600 --set device.cameras.width_px=64"
     " --set device.cameras.height_px=48 --set 'device.cameras.fx_px=[48, 48, 48, 48]'"
     " --set 'device.cameras.fy_px=[48, 48, 48, 48]' --set 'device.cameras.cx_px=[32, 32, 32, 32]'"
     " --set 'device.cameras.cy_px=[24, 24, 24, 24]' -o " + shell_quote(dir));
  const std::string manifest = read_file(dir / "manifest.yaml");
  for (const char* stem : {"stop_0000", "stop_0002"})
    for (const char* file : {".csv", "_aop.png", "_dop.png", "_s0.png"})
      EXPECT_HAS(manifest, fmt::format("previews/{}{}:", stem, file));
  for (int s : {0, 2}) {
    const ExrImage image = read_exr_image(dir / fmt::format("frames/stop_{:04}.exr", s));
    const auto layer = [&](const std::string& name) -> const std::vector<float>& {
      for (const ExrChannel& c : image.floats)
        if (c.name == name) return c.pixels;
      ADD_FAILURE() << "no layer " << name;
      return image.floats.at(0).pixels;
    };
    const std::vector<std::uint32_t>* valid = nullptr;
    for (const ExrUintChannel& c : image.uints)
      if (c.name == "valid") valid = &c.pixels;
    ASSERT_NE(valid, nullptr);
    const Csv csv = read_csv(dir / "previews" / fmt::format("stop_{:04}.csv", s));
    ASSERT_EQ(csv.rows.size(), static_cast<std::size_t>(image.width * image.height));
    int shown = 0;
    for (const auto& row : csv.rows) {
      const int col = std::stoi(row[csv.col("col")]), r = std::stoi(row[csv.col("row")]);
      const std::size_t k = static_cast<std::size_t>(r * image.width + col);
      EXPECT_EQ(row[csv.col("x_px")], fmt::format("{}", col + 0.5));
      const bool ok = (*valid)[k] != 0;
      shown += ok;
      for (const auto& [column, name] : {std::pair{"aop_deg", "AoP"}, {"dop", "DoP"}, {"S0", "S0"}})
        EXPECT_EQ(row[csv.col(column)], csv_value(ok ? double(layer(name)[k]) : std::nan(""))) << s << " " << column;
    }
    EXPECT_GT(shown, image.width * image.height / 2);
  }
  expect_previews_plot_their_csv(dir / "previews", {"stop_0000", "stop_0002"});
}

INSTANTIATE_TEST_SUITE_P(ShippedRigs, Plots,
                         ::testing::Values("wang2019-indoor.yaml", "wang2019-cs-simulation.yaml",
                                           "wang2019-outdoor1.yaml", "wang2019-outdoor2.yaml",
                                           "wang2019-sun1.yaml", "wang2019-sun2.yaml"),
                         [](const auto& info) {
                           std::string name = info.param;
                           name = name.substr(0, name.find('.'));
                           for (char& c : name)
                             if (c == '-') c = '_';
                           return name;
                         });

}  // namespace
}  // namespace polrig::test
