#pragma once
// PNG plots through gnuplot (pngcairo). Each folder gets its gnuplot script beside the PNGs,
// so a user can restyle a figure from the CSVs without polrig.
#include <filesystem>
#include <string>
#include <vector>

#include "polrig/progress.h"

namespace polrig {

struct PlotSeries {
  std::string file;    // CSV in the same folder
  // gnuplot "using" clause naming the CSV's columns by its header, never by position (a writer's
  // new column must not shift a plot): $name is a number, @name a string, $0 the row index.
  // "$theta_R_deg:($V1_ideal_V*1e3)", "$theta_R_deg:(@method eq 'cs' ? $err_deg : NaN)"
  std::string using_;
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
// The using clause as gnuplot reads it: a lone $name becomes "name", $name in an expression
// column("name"), @name strcol("name"). Throws std::logic_error on a name the header lacks or a
// column given by number.
std::string resolve_columns(const std::string& using_, const std::vector<std::string>& header,
                            const std::string& file);
// Writes DIR/<script_name> and draws its plots in DIR, one gnuplot process each, in parallel
// (stage "plots" on `progress`); throws std::runtime_error with gnuplot's message when one fails.
void render_plots(const std::filesystem::path& dir, const std::string& script_name,
                  const std::vector<Plot>& plots, const Progress& progress = {});
// The same for a script written by hand (images, maps): writes DIR/<script_name>, runs gnuplot in
// DIR and checks that every PNG named in `pngs` was written.
void run_gnuplot(const std::filesystem::path& dir, const std::string& script_name,
                 const std::string& script, const std::vector<std::string>& pngs);

}  // namespace polrig
