#pragma once
// Shared pieces of the polrig commands. Every command follows one pattern: parse and check all
// input, open the output (a staging folder, so nothing appears on failure), compute, write,
// commit.
#include <cstring>
#include <exception>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <type_traits>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "polrig/io/manifest.h"
#include "polrig/io/output_dir.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/progress.h"
#include "polrig/ranks.h"
#include "polrig/sky/sun.h"

namespace polrig::cli {

// The command line as typed, shell-quoted, for manifests.
const std::string& command_line();
void set_command_line(int argc, char** argv);

// The processes of this run: the MPI job's ranks when mpirun or srun started polrig (built with
// -DPOLRIG_MPI=ON; docs/scale.md), else this process alone. Every rank parses and checks the
// same input with the same code, so all reach the same verdict; rank 0 alone prints (progress,
// notes, errors, results) and alone opens and writes the output folder.
const Ranks& ranks();
void set_ranks(const Ranks& ranks);

// What main prints for an error and the exit code it returns: 2 for bad input (RigError,
// DataError), 3 for a calibration that cannot be done, 1 otherwise.
struct Failure {
  int exit_code = 1;
  std::string message;  // after "polrig: error: "
};
Failure failure_of(std::exception_ptr error);
// A command-line mistake in words (exit 2): an unknown command or option with the nearest known
// name ("did you mean"), else CLI11's own message.
std::string usage_error(const CLI::App& app, int argc, char** argv, const CLI::ParseError& e);
// A failure every rank has learnt at a collective point: each throws it, rank 0 prints it.
class RanksFailure : public std::runtime_error {
 public:
  explicit RanksFailure(Failure f) : std::runtime_error(f.message), exit_code(f.exit_code) {}
  int exit_code;
};
// Collective: runs `step` on rank 0 alone (opening, writing or committing the output), then
// every rank learns whether it failed and, if so, throws RanksFailure with rank 0's message and
// exit code (on rank 0 as well, after `step`'s own clean-up).
void on_rank_0(const std::function<void()>& step);
// Collective: runs `step` on every rank (loading and checking the input), then every rank
// learns whether any failed and, if so, throws RanksFailure with the lowest failing rank's
// message and exit code. Alone, `step`'s own error passes through unchanged.
void on_every_rank(const std::function<void()>& step);
// Collective: rank 0's value on every rank (e.g. where a resumed sweep starts).
template <class T>
T from_rank_0(const T& value) {
  static_assert(std::is_trivially_copyable_v<T>);
  std::vector<std::byte> bytes(sizeof(T));
  std::memcpy(bytes.data(), &value, sizeof(T));
  ranks().broadcast(bytes);
  T v;
  std::memcpy(&v, bytes.data(), sizeof(T));
  return v;
}

// `optional.emplace(made_by([&] { return out.open(); }))`: an object that cannot move (OutputDir)
// made in place from a function that returns it.
template <class F>
struct made_by {
  F make;
  operator std::invoke_result_t<F&>() { return make(); }
};
template <class F>
made_by(F) -> made_by<F>;

// Options shared by every command that writes a folder.
struct OutputOptions {
  std::string out;
  bool force = false;
  bool no_plots = false;
  // `plots`: the command draws plots, so it takes --no-plots.
  void add_to(CLI::App& app, bool plots = true);
  // Fails early (before any computation) if gnuplot is needed and missing, or the destination
  // exists without --force.
  OutputDir open(bool plots_needed = true) const;
  bool plots() const { return !no_plots; }
};

// A rig argument with its --set overrides. Without a rig file, the overrides apply to the
// default rig (rigs/wang2019-indoor.yaml's values).
struct RigInput {
  std::string path;
  std::vector<std::string> sets;
  void add_to(CLI::App& app, bool required);
  LoadedRig load() const;
};
// "a,b,c": finite numbers, or DataError naming `option` and the text (the studies' sweep lists);
// an empty text is no values when `empty_ok`, else refused.
std::vector<double> parse_number_list(const std::string& text, const char* option, bool empty_ok = false);
// --sun-el-deg: "X", "X,Y,…", or "A:B:N" for N elevations from A to B (both included); DataError
// naming the option and the text for anything else.
std::vector<double> parse_elevations(const std::string& text);
// --set KEY=VALUE (repeatable) into `sets`, refusing a value that is not KEY=VALUE.
void add_set_option(CLI::App& app, std::vector<std::string>& sets);

void add_threads_option(CLI::App& app, int& threads);

// A check for a real-valued option: a finite number in [lo, hi] ("nan" and "inf", which
// CLI::Range lets through, are refused). `unit` is shown after the range.
CLI::Validator finite_range(double lo, double hi, const std::string& unit = "");
// A file option given as '' (an empty shell variable) is refused (DataError, exit 2), not taken as
// absent: `value` is what `option` of `app` holds.
void require_file_name(const CLI::App& app, const std::string& option, const std::string& value);
// "LAT,LON" in degrees, north and east positive, latitude in [−90, 90] and longitude in
// [−180, 180]; DataError (exit 2) naming `option` and the text otherwise.
Site parse_site(const std::string& text, const std::string& option = "--site");
// An ISO 8601 UTC time with a Z (sky/sun.h's parse_utc); DataError naming `option` otherwise.
UtcTime parse_utc_option(const std::string& text, const std::string& option = "--utc");
// --refraction and --ut1-minus-utc, the sun's settings shared by sky, sky table, heading and
// study heading (sky/sun.h's SunSettings; refraction at 1010 hPa and 10 °C).
void add_sun_options(CLI::App& app, SunSettings& sun);
// --quiet on `app` and every command below it: no progress line.
void add_quiet_option(CLI::App& app);
// Where the library reports progress: a line on stderr, rewritten in place, when stderr is a
// terminal, --quiet was not given and this is rank 0; otherwise nowhere. With POLRIG_STAGE_TIMES
// set (rank 0), every stage's wall and CPU time is also kept for write_stage_times.
Progress progress();
// POLRIG_STAGE_TIMES=FILE: writes FILE (stage,wall_s,cpu_s: one row per stage in the order they
// ended, and a last row "(total)" with the command's own wall and CPU time since main began) after
// a command that succeeded; a warning on stderr if it cannot. Nothing without the variable.
void write_stage_times(double total_wall_s, double total_cpu_s);
// Ends an unfinished progress line, so that the next message starts on its own line.
void end_progress_line();
void finish(OutputDir& out);
// Before a command runs: DataError (exit 2) when its -o/--out folder is, contains or lies inside
// any existing file or folder given to it (a positional argument, an option's value, a --set
// KEY=VALUE's value): its inputs (io/output_dir.h, refuse_output_over_inputs).
void refuse_output_over_inputs(const CLI::App& command);

// Command registration; each returns the function to run when the command was chosen.
struct Command {
  CLI::App* app;
  std::function<void()> run;
  // The command shares its work between the ranks of an MPI job; the others refuse to run as
  // more than one rank.
  bool distributes = false;
};
std::vector<Command> add_rig_commands(CLI::App& root, int& threads);
std::vector<Command> add_calibration_commands(CLI::App& root, CLI::App& study, int& threads);
std::vector<Command> add_spectral_commands(CLI::App& root);
std::vector<Command> add_nav_commands(CLI::App& root, CLI::App& study, int& threads);
std::vector<Command> add_sky_commands(CLI::App& root, int& threads);
std::vector<Command> add_position_commands(CLI::App& root, CLI::App& study, int& threads);
std::vector<Command> add_navigation_commands(CLI::App& root, int& threads);
std::vector<Command> add_navigation_study_commands(CLI::App& root, CLI::App& study, int& threads);
std::vector<Command> add_sky_study_commands(CLI::App& root, CLI::App& study, int& threads);
// `simulate` of a unit-array rig: its navigation dataset (navigation_commands.cpp).
void simulate_unit_array(const LoadedRig& r, const OutputOptions& out);
// `calibrate DIR --method unit-array`: the units' installation calibration (navigation_commands.cpp).
void run_calibrate_unit_array(const std::string& input, const std::string& rig_path, const OutputOptions& out);

}  // namespace polrig::cli
