#pragma once
// PNG plots through gnuplot (pngcairo). Each folder gets its gnuplot script beside the PNGs,
// so a user can restyle a figure from the CSVs without polrig.
#include <filesystem>
#include <string>
#include <vector>

namespace polrig {

struct PlotSeries {
  std::string file;    // CSV in the same folder
  std::string using_;  // gnuplot "using" clause, columns 1-based: "1:3", "1:($2==1?$3:NaN)"
  std::string title;
  std::string style = "lines lw 2";
  bool y2 = false;     // on the right-hand axis
};

struct Plot {
  std::string png;  // file name in the folder
  std::string title, xlabel, ylabel, y2label;
  std::vector<PlotSeries> series;
  std::string extra;  // further gnuplot commands (ranges, log scales…), one per line
  int width = 960, height = 600;
};

bool gnuplot_available();
// Writes DIR/<script_name> and runs gnuplot in DIR; throws std::runtime_error with gnuplot's
// message when it fails.
void render_plots(const std::filesystem::path& dir, const std::string& script_name,
                  const std::vector<Plot>& plots);
// The same for a script written by hand (images, maps): writes DIR/<script_name>, runs gnuplot in
// DIR and checks that every PNG named in `pngs` was written.
void run_gnuplot(const std::filesystem::path& dir, const std::string& script_name,
                 const std::string& script, const std::vector<std::string>& pngs);

}  // namespace polrig
