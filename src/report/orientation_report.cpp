#include "polrig/report/orientation_report.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "polrig/io/csv.h"
#include "polrig/io/plot.h"
#include "polrig/nav/heading.h"

namespace polrig {

namespace {

std::string cell(std::optional<double> v, const char* column, int frame) {
  if (!v) return "nan";  // not defined (formats.md §5)
  if (!std::isfinite(*v))
    throw std::runtime_error(fmt::format("orientation: column '{}' of frame {} is {}; nothing was "
                                         "written", column, frame, *v));
  return fmt::format("{}", *v);
}

}  // namespace

std::vector<DatasetFile> report_orientation(const std::filesystem::path& dir,
                                            const std::vector<FrameOrientation>& frames, bool plots) {
  std::string text = "frame,method,sun_az_deg,sun_el_deg,heading_deg,heading_error_deg,status\n";
  for (const FrameOrientation& f : frames)
    for (const OrientationEstimate& e : f.estimates) {
      std::optional<double> az, error;
      if (e.solved) az = e.sun_az_deg;
      if (e.heading_deg && f.true_heading_deg)
        error = heading_difference_deg(*e.heading_deg, *f.true_heading_deg);
      // Checked left to right, so an error names the first bad column.
      const std::string az_cell = cell(az, "sun_az_deg", f.frame);
      const std::string el_cell = cell(e.solved ? e.sun_el_deg : std::nullopt, "sun_el_deg", f.frame);
      const std::string heading_cell = cell(e.heading_deg, "heading_deg", f.frame);
      const std::string error_cell = cell(error, "heading_error_deg", f.frame);
      text += fmt::format("{},{},{},{},{},{},{}\n", f.frame, orientation_method_name(e.method),
                          az_cell, el_cell, heading_cell, error_cell, e.status);
    }
  write_text_file(dir / "orientation.csv", text);
  std::vector<DatasetFile> files{
      {"orientation.csv", 1,
       "per sky frame and method (eigenvector, single-point, line-detection): the sun's azimuth "
       "and elevation in the camera frame, the heading, its error against the true heading, the "
       "status"}};
  if (!plots || frames.empty()) return files;
  Plot p;
  p.png = "heading_error.png";
  p.title = "Heading error per frame (H17 Eqs. 6–14 and the comparators of §4.2)";
  p.xlabel = "frame";
  p.ylabel = "heading error (°)";
  const auto only = [](const char* method) {
    return fmt::format("1:(strcol(2) eq '{}' ? $6 : NaN)", method);
  };
  p.series = {{"orientation.csv", only("single-point"), "single point (zenith cells)",
               "linespoints pt 7 ps 0.6 lw 1 lc rgb '#d62728'"},
              {"orientation.csv", only("line-detection"), "line detection (Hough)",
               "linespoints pt 5 ps 0.6 lw 1 lc rgb '#2ca02c'"},
              {"orientation.csv", only("eigenvector"), "eigenvector",
               "linespoints pt 9 ps 0.7 lw 2 lc rgb '#1f77b4'"}};
  p.extra = "set key below horizontal\nset grid";
  render_plots(dir, "plots.gp", {p});
  files.push_back({"heading_error.png", 1, "heading error per frame of the three methods"});
  return files;
}

}  // namespace polrig
