#include <unistd.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <vector>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string_view>

#include <fmt/format.h>

#include "cli.h"
#include "polrig/io/measured.h"
#include "polrig/quoted.h"
#include "polrig/io/plot.h"
#include "polrig/calib/fit.h"
#include "polrig/rig/error.h"
#include "polrig/rig/keys.h"

namespace polrig::cli {
namespace {
std::string g_command_line;
bool g_quiet = false;
bool g_line_open = false;  // a progress line without its newline yet
const Ranks* g_ranks = nullptr;

std::string shell_word(const std::string& w) {
  if (!w.empty() && w.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                        "0123456789_-./:=+,@%") == std::string::npos)
    return w;
  std::string q = "'";
  for (char c : w) q += (c == '\'') ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}
}  // namespace

const std::string& command_line() { return g_command_line; }

const Ranks& ranks() { return g_ranks ? *g_ranks : this_process_only(); }
void set_ranks(const Ranks& r) { g_ranks = &r; }

Failure failure_of(std::exception_ptr error) {
  try {
    std::rethrow_exception(error);
  } catch (const RanksFailure& e) {
    return {e.exit_code, e.what()};
  } catch (const RigError& e) {
    return {2, e.what()};
  } catch (const DataError& e) {
    return {2, e.what()};
  } catch (const CalibrationError& e) {
    return {3, std::string("cannot calibrate: ") + e.what()};
  } catch (const std::exception& e) {
    return {1, e.what()};
  }
}

namespace {
// Runs `step` on this rank if `here`; then every rank learns the lowest failing rank's failure
// (its exit code and message, as text) and throws it as RanksFailure.
void run_and_agree(const std::function<void()>& step, bool here) {
  std::optional<std::string> mine;
  if (here) {
    try {
      step();
    } catch (...) {
      const Failure failure = failure_of(std::current_exception());
      mine = std::to_string(failure.exit_code) + "\n" + failure.message;
    }
  }
  const std::optional<std::string> first = ranks().first_failure(mine);
  if (!first) return;
  const auto newline = first->find('\n');
  throw RanksFailure({std::stoi(first->substr(0, newline)), first->substr(newline + 1)});
}
}  // namespace

void on_every_rank(const std::function<void()>& step) {
  if (ranks().size() == 1) return step();
  run_and_agree(step, true);
}

void on_rank_0(const std::function<void()>& step) { run_and_agree(step, ranks().is_root()); }

void set_command_line(int argc, char** argv) {
  g_command_line = "polrig";
  for (int i = 1; i < argc; ++i) g_command_line += " " + shell_word(argv[i]);
}

void OutputOptions::add_to(CLI::App& app, bool plots) {
  app.add_option("-o,--out", out, "output folder (written whole or not at all)")->required();
  app.add_flag("--force", force, "replace the output folder if it exists");
  if (plots) app.add_flag("--no-plots", no_plots, "write the CSV files only, no PNG plots");
}

OutputDir OutputOptions::open(bool plots_needed) const {
  if (plots_needed && !no_plots && !gnuplot_available())
    throw std::runtime_error(
        "gnuplot is needed for the PNG plots and was not found; install it "
        "(scripts/setup-deps.sh) or pass --no-plots");
  if (out.empty()) throw std::runtime_error("-o/--out '': expected the output folder's name");
  try {
    return OutputDir(out, force);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(fmt::format("-o/--out {}: {}", out, e.what()));
  }
}

namespace {
// The named options that take a file or folder (the positional arguments all do: DIR, INPUT, RIG,
// PARAMS, VOLTAGES, SCENE). Any other option's value is a number, a word or a list, which may
// happen to name a folder (`--mode sins -o sins`) without being an input.
constexpr std::string_view kPathOptions[] = {"rig", "calibration", "params", "geometry", "films", "response", "sun"};

bool takes_a_path(const CLI::Option& o) {
  if (!o.nonpositional()) return true;
  for (std::string_view name : kPathOptions)
    if (o.check_lname(std::string(name))) return true;
  return false;
}

// A --set KEY=VALUE whose key takes a file (rig/keys.h: "a path to …"): its value.
std::optional<std::string> set_path(const std::string& assignment) {
  const std::size_t eq = assignment.find('=');
  if (eq == std::string::npos) return std::nullopt;
  const RigKey* k = find_rig_key(std::string_view(assignment).substr(0, eq));
  if (!k || !k->expects.starts_with("a path")) return std::nullopt;
  return assignment.substr(eq + 1);
}
}  // namespace

void refuse_output_over_inputs(const CLI::App& command) {
  const CLI::Option* out = command.get_option_no_throw("--out");
  if (!out || out->count() == 0) return;
  std::vector<std::filesystem::path> inputs;
  for (const CLI::Option* o : command.get_options()) {
    if (o == out) continue;
    const bool set = o->check_lname("set");
    if (!set && !takes_a_path(*o)) continue;
    for (const std::string& value : o->results()) {
      if (!set) inputs.emplace_back(value);
      else if (const std::optional<std::string> path = set_path(value)) inputs.emplace_back(*path);
    }
  }
  try {
    polrig::refuse_output_over_inputs(out->results().front(), inputs);
  } catch (const std::invalid_argument& e) {
    throw DataError(fmt::format("-o/--out: {}", e.what()));
  }
}

void RigInput::add_to(CLI::App& app, bool required) {
  auto* r = app.add_option("RIG", path, "rig file (YAML), e.g. rigs/wang2019-indoor.yaml");
  if (required) r->required();
  add_set_option(app, sets);
}

std::vector<double> parse_number_list(const std::string& text, const char* option, bool empty_ok) {
  std::vector<double> values;
  if (text.empty() && empty_ok) return values;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t comma = std::min(text.find(',', pos), text.size());
    try {
      values.push_back(parse_finite_number(std::string_view(text).substr(pos, comma - pos), "value"));
    } catch (const RigError& e) {
      throw DataError(fmt::format("{} {}: {} (expected a comma-separated list of numbers)", option, text, e.what()));
    }
    pos = comma + 1;
  }
  return values;
}

namespace {
std::vector<std::string> parse_comma_parts(const std::string& text) {
  std::vector<std::string> parts;
  for (std::size_t pos = 0;;) {
    const std::size_t comma = text.find(',', pos);
    parts.push_back(text.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos));
    if (comma == std::string::npos) return parts;
    pos = comma + 1;
  }
}
}  // namespace

std::vector<double> parse_elevations(const std::string& text) {
  const auto bad = [&](const std::string& why) {
    return DataError(fmt::format("--sun-el-deg {}: {} (expected X, X,Y,… or A:B:N, degrees)", text, why));
  };
  std::vector<std::string> parts;
  for (std::size_t pos = 0;;) {
    const std::size_t colon = text.find(':', pos);
    parts.push_back(text.substr(pos, colon == std::string::npos ? std::string::npos : colon - pos));
    if (colon == std::string::npos) break;
    pos = colon + 1;
  }
  const auto number = [&](const std::string& t) {
    std::size_t used = 0;
    double v = 0;
    try {
      v = std::stod(t, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != t.size() || !std::isfinite(v)) throw bad("'" + t + "' is not a number");
    return v;
  };
  if (text.find(',') != std::string::npos) {
    std::vector<double> out;
    for (const std::string& t : parse_comma_parts(text)) out.push_back(number(t));
    return out;
  }
  if (parts.size() == 1) return {number(parts[0])};
  if (parts.size() != 3) throw bad("expected one value or three");
  const double a = number(parts[0]), b = number(parts[1]), n = number(parts[2]);
  if (!(n >= 2 && n <= 1000 && n == std::floor(n))) throw bad("N must be a whole number in [2, 1000]");
  std::vector<double> out;
  for (int k = 0; k < static_cast<int>(n); ++k) out.push_back(a + (b - a) * k / (n - 1));
  return out;
}


void add_set_option(CLI::App& app, std::vector<std::string>& sets) {
  // A value that is not KEY=VALUE is refused here, so `--set -o out` names --set, not a missing -o.
  const CLI::Validator key_value(
      [](const std::string& s) -> std::string {
        const auto eq = s.find('=');
        const bool ok = eq != std::string::npos && eq > 0 &&
                        s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_.") == eq;
        return ok ? std::string() : fmt::format("expected key.path=value (e.g. eccentricity.L_S=0.05), got '{}'", s);
      },
      "KEY=VALUE");
  app.add_option("--set", sets, "override a rig value: key.path=value (repeatable)")
      ->type_name("KEY=VALUE")
      ->check(key_value)
      ->allow_extra_args(false);
}

LoadedRig RigInput::load() const {
  std::vector<RigOverride> overrides;
  for (const std::string& s : sets) overrides.push_back(RigOverride::parse(s));
  if (path.empty()) return parse_rig("", "(default rig)", overrides);
  return load_rig(path, overrides);
}

CLI::Validator finite_range(double lo, double hi, const std::string& unit) {
  const std::string range = fmt::format("[{}, {}]{}{}", lo, hi, unit.empty() ? "" : " ", unit);
  return CLI::Validator(
      [=](const std::string& s) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(s, v) || !std::isfinite(v) || v < lo || v > hi)
          return fmt::format("expected a finite number in {}, got {}", range, quoted_value(s));
        return {};
      },
      range);
}

void require_file_name(const CLI::App& app, const std::string& option, const std::string& value) {
  if (app.count(option) > 0 && value.empty()) throw DataError(fmt::format("{} '': expected a file name", option));
}

Site parse_site(const std::string& text, const std::string& option) {
  const auto number = [](std::string_view s, double& v) {
    const char* b = s.data();
    const char* e = s.data() + s.size();
    if (b != e && *b == '+') ++b;
    const auto [end, err] = std::from_chars(b, e, v);
    return !s.empty() && err == std::errc() && end == e && std::isfinite(v);
  };
  const auto comma = text.find(',');
  Site site;
  if (comma == std::string::npos || text.find(',', comma + 1) != std::string::npos ||
      !number(std::string_view(text).substr(0, comma), site.lat_deg) ||
      !number(std::string_view(text).substr(comma + 1), site.lon_deg))
    throw DataError(fmt::format("{} '{}': expected LAT,LON in degrees (finite numbers), e.g. "
                                "38.879167,121.543889", option, quoted_value(text)));
  if (const auto problem = site_problem(site))
    throw DataError(fmt::format("{} '{}': {}", option, quoted_value(text), *problem));
  return site;
}

UtcTime parse_utc_option(const std::string& text, const std::string& option) {
  try {
    return parse_utc(text);
  } catch (const std::invalid_argument& e) {
    throw DataError(fmt::format("{} {}: {}", option, quoted_value(text), e.what()));
  }
}

void add_sun_options(CLI::App& app, SunSettings& sun) {
  app.add_flag("--refraction", sun.refraction,
               "refract the sun (Saemundsson, 1010 hPa, 10 °C); off: geometric");
  app.add_option("--ut1-minus-utc", sun.ut1_minus_utc_s,
                 "UT1 - UTC in seconds (IERS Bulletin A; 1 s turns the sky by 0.004°)")
      ->check(finite_range(-1, 1, "s"))->capture_default_str();
}

void add_threads_option(CLI::App& app, int& threads) {
  app.add_option("--threads", threads,
                 "worker threads (default: all cores); results do not depend on it")
      ->check(CLI::Range(1, 1024));
}

void add_quiet_option(CLI::App& app) {
  app.add_flag("--quiet", g_quiet, "no progress line on stderr (there is none when stderr is not a terminal)");
  for (CLI::App* sub : app.get_subcommands({})) add_quiet_option(*sub);
}

namespace {
std::mutex g_stage_mutex;
std::vector<StageTime> g_stage_times;

const char* stage_times_path() {
  const char* path = std::getenv("POLRIG_STAGE_TIMES");
  return path && *path && ranks().is_root() ? path : nullptr;
}
}  // namespace

Progress progress() {
  const bool show = !g_quiet && ::isatty(2) && ranks().is_root();
  ProgressSink line;
  if (show)
    line = [](const ProgressReport& r) {
      const bool done = r.fraction >= 1;
      std::fprintf(stderr, "\rpolrig: %s\033[K%s", format_progress(r).c_str(), done ? "\n" : "");
      std::fflush(stderr);
      g_line_open = !done;
    };
  if (!stage_times_path()) return show ? Progress(line, 0.5) : Progress();
  return Progress(line, 0.5, [](const StageTime& t) {
    const std::lock_guard lock(g_stage_mutex);
    g_stage_times.push_back(t);
  });
}

void write_stage_times(double total_wall_s, double total_cpu_s) {
  const char* path = stage_times_path();
  if (!path) return;
  const std::lock_guard lock(g_stage_mutex);
  std::FILE* f = std::fopen(path, "w");
  if (!f) {
    end_progress_line();
    std::cerr << "polrig: warning: POLRIG_STAGE_TIMES: cannot write " << path << "\n";
    return;
  }
  std::fputs("stage,wall_s,cpu_s\n", f);
  for (const StageTime& t : g_stage_times) {
    std::string name = t.stage;  // quoted (RFC 4180) only when it must be
    if (name.find_first_of(",\"\n") != std::string::npos) {
      std::string q = "\"";
      for (char c : name) q += c == '"' ? std::string("\"\"") : std::string(1, c);
      name = q + "\"";
    }
    std::fputs(fmt::format("{},{:.6f},{:.6f}\n", name, t.wall_s, t.cpu_s).c_str(), f);
  }
  std::fputs(fmt::format("(total),{:.6f},{:.6f}\n", total_wall_s, total_cpu_s).c_str(), f);
  if (std::fclose(f) != 0) std::cerr << "polrig: warning: POLRIG_STAGE_TIMES: cannot write " << path << "\n";
}

void end_progress_line() {
  if (!g_line_open) return;
  std::fputc('\n', stderr);
  g_line_open = false;
}

void finish(OutputDir& out) {
  end_progress_line();
  out.commit();
  std::cout << "wrote " << out.destination().string() << "\n";
}

}  // namespace polrig::cli
