#include "polrig/io/plot.h"

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "polrig/io/csv.h"

namespace polrig {
namespace fs = std::filesystem;

namespace {
std::string quoted(const std::string& s) {
  std::string q = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') q += '\\';
    q += c;
  }
  return q + "\"";
}

std::string shell_quoted(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += (c == '\'') ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string script_for(const Plot& p) {
  std::string s;
  s += fmt::format("set terminal pngcairo size {},{} enhanced font 'DejaVu Sans,11'\n", p.width,
                   p.height);
  s += fmt::format("set output {}\n", quoted(p.png));
  s += "set datafile separator ','\nset grid\nset key outside right top\n";
  // Axis labels and legends may hold rig key paths (eccentricity.L_IS): no enhanced text there.
  s += fmt::format("set title {} noenhanced\nset xlabel {} noenhanced\nset ylabel {}\n", quoted(p.title),
                   quoted(p.xlabel), quoted(p.ylabel));
  bool any_y2 = false;
  for (const PlotSeries& ps : p.series) any_y2 |= ps.y2;
  if (any_y2) s += fmt::format("set y2label {}\nset y2tics\nset ytics nomirror\n", quoted(p.y2label));
  if (!p.extra.empty()) s += p.extra + "\n";
  s += "plot ";
  for (std::size_t i = 0; i < p.series.size(); ++i) {
    const PlotSeries& ps = p.series[i];
    s += fmt::format("{}{} skip 1 using {} axes {} title {} noenhanced with {}", i ? ", \\\n     " : "",
                     quoted(ps.file), ps.using_, ps.y2 ? "x1y2" : "x1y1", quoted(ps.title),
                     ps.style);
  }
  return s + "\nunset output\n";
}
}  // namespace

bool gnuplot_available() { return std::system("gnuplot --version >/dev/null 2>&1") == 0; }

void render_plots(const fs::path& dir, const std::string& script_name,
                  const std::vector<Plot>& plots) {
  std::string script;
  std::vector<std::string> pngs;
  for (const Plot& p : plots) {
    script += "reset session\n" + script_for(p) + "\n";
    pngs.push_back(p.png);
  }
  run_gnuplot(dir, script_name, script, pngs);
}

void run_gnuplot(const fs::path& dir, const std::string& script_name, const std::string& script,
                 const std::vector<std::string>& pngs) {
  write_text_file(dir / script_name, script);
  const fs::path log = dir / (script_name + ".log");
  const std::string cmd = fmt::format("cd {} && gnuplot {} > {} 2>&1", shell_quoted(dir.string()),
                                      shell_quoted(script_name), shell_quoted(log.string()));
  const int rc = std::system(cmd.c_str());
  std::ifstream in(log);
  std::stringstream msg;
  msg << in.rdbuf();
  in.close();
  std::error_code ec;
  fs::remove(log, ec);
  if (rc != 0) {
    // gnuplot echoes the whole plot command; its last lines say what went wrong.
    std::string text = msg.str();
    if (text.size() > 400) text = "…" + text.substr(text.size() - 400);
    if (text.empty()) text = fmt::format("it exited with status {} and left no message", rc);
    throw std::runtime_error(fmt::format("gnuplot failed on {}: {}", script_name, text));
  }
  // gnuplot does not always notice a failed write (a full disk): every PNG must be there.
  for (const std::string& name : pngs) {
    const fs::path png = dir / name;
    if (fs::file_size(png, ec) == 0 || ec)
      throw std::runtime_error(fmt::format("{}: gnuplot did not write the plot{}", png.string(),
                                           ec ? ": " + ec.message() : std::string(" (empty file)")));
  }
}

}  // namespace polrig
