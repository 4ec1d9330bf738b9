// The plots a command writes show the CSV columns their legends name. gnuplot itself reads each
// folder's plots.gp (switched from PNG to its `set table` text output), and every plotted point
// is compared with the column read by its header name from the CSV beside it.
#include <gtest/gtest.h>
#include <fmt/format.h>

#include <cmath>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "support.h"

namespace polrig::test {
namespace {

// One plotted curve as gnuplot tabulated it: its legend and its (x, y) points.
struct Curve {
  std::vector<double> x, y;
};

// plots.gp with each PNG replaced by a table file; returns the curves of all plots by title.
std::map<std::string, Curve> tabulate(const fs::path& dir) {
  std::string script;
  for (const std::string& line : lines_of(read_file(dir / "plots.gp"))) {
    if (line.rfind("set terminal", 0) == 0) continue;
    if (line.rfind("set output", 0) == 0) {
      script += "set table 'curves.txt' append\n";
    } else if (line == "unset output") {
      script += "unset table\n";
    } else {
      script += line + "\n";
    }
  }
  write_file(dir / "tabulate.gp", script);
  const std::string cmd = "cd " + shell_quote(dir) + " && gnuplot tabulate.gp 2>/dev/null";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::map<std::string, Curve> curves;
  Curve* current = nullptr;
  for (const std::string& line : lines_of(read_file(dir / "curves.txt"))) {
    const std::string tag = "# Curve title: \"";
    if (line.rfind(tag, 0) == 0) {
      current = &curves[line.substr(tag.size(), line.size() - tag.size() - 1)];
      continue;
    }
    if (line.empty() || line[0] == '#' || current == nullptr) continue;
    std::stringstream ss(line);
    double x = 0, y = 0;
    std::string y_text;
    ss >> x >> y_text;
    y = y_text == "NaN" ? NAN : std::stod(y_text);
    current->x.push_back(x);
    current->y.push_back(y);
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
