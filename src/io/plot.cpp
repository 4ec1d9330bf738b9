#include "polrig/io/plot.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "polrig/io/csv.h"

namespace polrig {
namespace fs = std::filesystem;

namespace {
std::string gnuplot_quoted(const std::string& s) {
  std::string q = "\"";
  for (char c : s) {
    if (c == '\n') {  // a line break in a title: gnuplot's escape
      q += "\\n";
      continue;
    }
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

bool is_name_start(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
// Rig key paths (eccentricity.L_IS) head a sweep's columns, so a name may hold dots.
bool is_name_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.'; }

// A CSV's header names, read from its first line (the file is in the plot's folder).
std::vector<std::string> header_of(const fs::path& csv) {
  std::ifstream in(csv);
  std::string line;
  if (!in || !std::getline(in, line))
    throw std::logic_error(fmt::format("plot: {} is missing or empty", csv.string()));
  if (!line.empty() && line.back() == '\r') line.pop_back();
  std::vector<std::string> names;
  std::stringstream ss(line);
  for (std::string name; std::getline(ss, name, ',');) names.push_back(name);
  return names;
}

// One field of a using clause (between top-level colons): a lone $name is gnuplot's "name".
std::string resolve_field(const std::string& field, const std::vector<std::string>& header,
                          const std::string& file) {
  std::string out;
  for (std::size_t i = 0; i < field.size(); ++i) {
    const char c = field[i];
    if ((c != '$' && c != '@') || i + 1 >= field.size() || !is_name_start(field[i + 1])) {
      if (c == '$' && i + 1 < field.size() && std::isdigit(static_cast<unsigned char>(field[i + 1])) &&
          field[i + 1] != '0')
        throw std::logic_error(fmt::format("plot of {}: '{}' names a column by number", file, field));
      out += c;
      continue;
    }
    std::size_t end = i + 1;
    while (end < field.size() && is_name_char(field[end])) ++end;
    while (field[end - 1] == '.') --end;
    const std::string name = field.substr(i + 1, end - i - 1);
    if (std::find(header.begin(), header.end(), name) == header.end())
      throw std::logic_error(fmt::format("plot of {}: no column '{}'", file, name));
    const bool whole = i == 0 && end == field.size() && c == '$';
    out += whole ? gnuplot_quoted(name) : fmt::format("{}({})", c == '$' ? "column" : "strcol", gnuplot_quoted(name));
    i = end - 1;
  }
  const bool number = !out.empty() && out.find_first_not_of("0123456789") == std::string::npos;
  if (number && out != "0")
    throw std::logic_error(fmt::format("plot of {}: '{}' names a column by number", file, field));
  return out;
}

}  // namespace

std::string resolve_columns(const std::string& using_, const std::vector<std::string>& header,
                            const std::string& file) {
  std::string out, field;
  int depth = 0;
  for (char c : using_) {
    depth += (c == '(') - (c == ')');
    if (c == ':' && depth == 0) {
      out += resolve_field(field, header, file) + ':';
      field.clear();
    } else {
      field += c;
    }
  }
  return out + resolve_field(field, header, file);
}

namespace {

std::string script_for(const fs::path& dir, const Plot& p) {
  std::string s;
  s += fmt::format("set terminal pngcairo size {},{} enhanced font 'DejaVu Sans,11'\n", p.width,
                   p.height);
  s += fmt::format("set output {}\n", gnuplot_quoted(p.png));
  s += "set datafile separator ','\nset datafile columnheaders\nset grid\nset key outside right top\n";
  // Axis labels and legends may hold rig key paths (eccentricity.L_IS): no enhanced text there.
  s += fmt::format("set title {} noenhanced\nset xlabel {} noenhanced\nset ylabel {}\n", gnuplot_quoted(p.title),
                   gnuplot_quoted(p.xlabel), gnuplot_quoted(p.ylabel));
  bool any_y2 = false;
  for (const PlotSeries& ps : p.series) any_y2 |= ps.y2;
  if (any_y2) s += fmt::format("set y2label {}\nset y2tics\nset ytics nomirror\n", gnuplot_quoted(p.y2label));
  if (!p.extra.empty()) s += p.extra + "\n";
  s += "plot ";
  for (std::size_t i = 0; i < p.series.size(); ++i) {
    const PlotSeries& ps = p.series[i];
    const std::string using_ = resolve_columns(ps.using_, header_of(dir / ps.file), ps.file);
    s += fmt::format("{}{} using {} axes {} title {} noenhanced with {}", i ? ", \\\n     " : "",
                     gnuplot_quoted(ps.file), using_, ps.y2 ? "x1y2" : "x1y1", gnuplot_quoted(ps.title),
                     ps.style);
  }
  return s + "\nunset output\n";
}
}  // namespace

bool gnuplot_available() { return std::system("gnuplot --version >/dev/null 2>&1") == 0; }

namespace {
// Runs gnuplot in DIR on the script file `script` (a name in DIR); its messages go to `log`, which
// is read and removed. Returns what went wrong, or "" when it exited 0.
std::string gnuplot_problem(const fs::path& dir, const std::string& script, const fs::path& log) {
  const std::string cmd = fmt::format("cd {} && gnuplot {} > {} 2>&1", shell_quoted(dir.string()),
                                      shell_quoted(script), shell_quoted(log.string()));
  const int rc = std::system(cmd.c_str());
  std::ifstream in(log);
  std::stringstream msg;
  msg << in.rdbuf();
  in.close();
  std::error_code ec;
  fs::remove(log, ec);
  if (rc == 0) return {};
  // gnuplot echoes the whole plot command; its last lines say what went wrong.
  std::string text = msg.str();
  if (text.size() > 400) text = "…" + text.substr(text.size() - 400);
  return text.empty() ? fmt::format("it exited with status {} and left no message", rc) : text;
}

// gnuplot does not always notice a failed write (a full disk): every PNG must be there.
void require_pngs(const fs::path& dir, const std::vector<std::string>& pngs) {
  std::error_code ec;
  for (const std::string& name : pngs) {
    const fs::path png = dir / name;
    if (fs::file_size(png, ec) == 0 || ec)
      throw std::runtime_error(fmt::format("{}: gnuplot did not write the plot{}", png.string(),
                                           ec ? ": " + ec.message() : std::string(" (empty file)")));
  }
}
}  // namespace

void render_plots(const fs::path& dir, const std::string& script_name,
                  const std::vector<Plot>& plots, const Progress& progress) {
  std::vector<std::string> scripts;
  std::string script;
  for (const Plot& p : plots) {
    scripts.push_back("reset session\n" + script_for(dir, p) + "\n");
    script += scripts.back();
  }
  write_text_file(dir / script_name, script);
  // Each plot is its own gnuplot process, the plots drawn side by side; the PNGs do not depend on it.
  std::vector<std::string> problems(plots.size());
  progress.begin("plots", static_cast<long long>(plots.size()));
  tbb::parallel_for(std::size_t{0}, plots.size(), [&](std::size_t i) {
    const std::string part = fmt::format(".{}.{}", script_name, i);  // this plot's lines alone
    write_text_file(dir / part, scripts[i]);
    problems[i] = gnuplot_problem(dir, part, dir / (part + ".log"));
    std::error_code ec;
    fs::remove(dir / part, ec);
    progress.advance();
  });
  progress.finish();
  for (std::size_t i = 0; i < plots.size(); ++i)
    if (!problems[i].empty())
      throw std::runtime_error(fmt::format("gnuplot failed on {} ({}): {}", script_name, plots[i].png, problems[i]));
  std::vector<std::string> pngs;
  for (const Plot& p : plots) pngs.push_back(p.png);
  require_pngs(dir, pngs);
}

void run_gnuplot(const fs::path& dir, const std::string& script_name, const std::string& script,
                 const std::vector<std::string>& pngs) {
  write_text_file(dir / script_name, script);
  if (const std::string problem = gnuplot_problem(dir, script_name, dir / (script_name + ".log")); !problem.empty())
    throw std::runtime_error(fmt::format("gnuplot failed on {}: {}", script_name, problem));
  require_pngs(dir, pngs);
}

}  // namespace polrig
