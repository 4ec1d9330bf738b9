#include "polrig/report/dataset_previews.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "polrig/io/csv.h"
#include "polrig/io/plot.h"

namespace polrig {

namespace fs = std::filesystem;

namespace {

// A value for the CSV: shortest round trip, `nan` where the sample measures none (formats.md).
std::string value(double v) { return std::isfinite(v) ? fmt::format("{}", v) : std::string("nan"); }

}  // namespace

std::vector<DatasetFile> report_stop_previews(const fs::path& dir, const std::vector<PreviewStop>& stops,
                                              const PreviewOptions& options) {
  std::vector<DatasetFile> files;
  if (stops.empty()) return files;
  fs::create_directory(dir / "previews");
  std::vector<Plot> plots;
  for (const PreviewStop& st : stops) {
    const std::size_t n = static_cast<std::size_t>(st.cols) * static_cast<std::size_t>(st.rows);
    if (st.cols <= 0 || st.rows <= 0 || st.pixels <= 0 || st.aop_deg.size() != n || st.dop.size() != n ||
        st.S0.size() != n || (!st.valid.empty() && st.valid.size() != n))
      throw std::invalid_argument(fmt::format("report_stop_previews: {}: layers of another size than {} × {}", st.stem,
                                              st.cols, st.rows));
    // Every stride-th sample in each direction, the top-left one of its block (no average).
    const int stride = (std::max(st.cols, st.rows) + options.max_samples - 1) / options.max_samples;
    const int p = st.pixels;
    std::string csv = fmt::format("x_px,y_px,{},{},aop_deg,dop,S0\n", options.grid_columns[0], options.grid_columns[1]);
    for (int j = 0; j < st.rows; j += stride)
      for (int i = 0; i < st.cols; i += stride) {
        const std::size_t k = static_cast<std::size_t>(j) * static_cast<std::size_t>(st.cols) + static_cast<std::size_t>(i);
        const bool ok = st.valid.empty() || st.valid[k] != 0;
        const double nan = std::nan("");
        csv += fmt::format("{},{},{},{},{},{},{}\n", p * i + 0.5 * p, p * j + 0.5 * p, i, j,
                           value(ok ? st.aop_deg[k] : nan), value(ok ? st.dop[k] : nan), value(ok ? st.S0[k] : nan));
      }
    const std::string data = fmt::format("{}.csv", st.stem);
    write_text_file(dir / "previews" / data, csv);
    const std::string sampled =
        stride > 1 ? fmt::format(", every {}th {} in each direction", stride, options.grid_text) : std::string();
    files.push_back({"previews/" + data, 1,
                     fmt::format("the previews' data: per {}{}: x_px, y_px (its centre in image pixels), {}, {}, "
                                 "aop_deg, dop, S0 (nan where it measures none)",
                                 options.grid_text, sampled, options.grid_columns[0], options.grid_columns[1])});

    const int W = st.cols * p, H = st.rows * p;
    // The image about 640 px wide, its height in proportion, room for the titles and the colour bar
    // with its label (clipped at 860 px wide for 5-character ticks).
    const int width = 920, height = 150 + static_cast<int>(std::lround(640.0 * H / W));
    const std::string frame = fmt::format(
        "unset key\nset size ratio -1\nset tics out\nset xrange [0:{}]\nset yrange [{}:0]\nset grid front\n", W, H);
    const auto image = [&](const char* suffix, const char* what, const std::string& column, const std::string& cb,
                           const std::string& extra) {
      Plot plot{fmt::format("{}_{}.png", st.stem, suffix), fmt::format("{}\n{}", what, st.title), "pixel column",
                "pixel row"};
      plot.series = {{data, fmt::format("$x_px:$y_px:${}", column), what, "image"}};
      plot.extra = frame + fmt::format("set cblabel \"{}\"\n", cb) + extra;
      plot.width = width, plot.height = height;
      plots.push_back(plot);
      files.push_back({"previews/" + plot.png, 1,
                       fmt::format("the {} preview of {} (one value per {}; axes in image pixels)", what, st.stem, options.grid_text)});
    };
    image("aop", "AoP", "aop_deg", fmt::format("AoP (°, {})", options.frame_text),
          "set cbrange [0:180]\nset cbtics 30\nset palette model HSV defined (0 0 1 1, 1 1 1 1)");
    image("dop", "DoP", "dop", "DoP",
          "set cbrange [0:1]\nset palette defined (0 '#000004', 0.25 '#51127c', 0.5 '#b73779', 0.75 '#fc8961', 1 "
          "'#fcfdbf')");
    image("s0", "S0", "S0", options.s0_label, "set palette gray");
  }
  render_plots(dir / "previews", "previews.gp", plots);
  files.push_back({"previews/previews.gp", 1, "the gnuplot script of the previews"});
  return files;
}

}  // namespace polrig
