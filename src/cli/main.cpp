// polrig: the command-line front end.
#include <chrono>
#include <ctime>
#include <iostream>
#include <memory>
#include <string>

#include <fmt/format.h>
#include <tbb/global_control.h>

#include "cli.h"
#include "polrig/calib/fit.h"
#include "polrig/freed_memory.h"
#include "polrig/io/measured.h"
#include "polrig/io/output_dir.h"
#include "polrig/io/sphere_cache.h"
#include "polrig/ranks.h"
#include "polrig/rig/error.h"
#include "polrig/version.h"

using namespace polrig;

namespace {
// "study cs", "sweep": the command as typed after polrig.
std::string command_name(const CLI::App* app) {
  std::string name = app->get_name();
  for (const CLI::App* p = app->get_parent(); p && p->get_parent(); p = p->get_parent())
    name = p->get_name() + " " + name;
  return name;
}
}  // namespace

int main(int argc, char** argv) {
  const auto started = std::chrono::steady_clock::now();
  keep_freed_memory();  // before any allocation worth keeping (freed_memory.h)
  clean_up_outputs_on_signals();  // first: before any other thread exists (MPI starts some)
  // MPI starts only under a launcher (mpirun, srun), and ends when `job` goes, after everything.
  std::unique_ptr<Ranks> job;
  try {
    job = join_mpi_job(argc, argv);
  } catch (const std::exception& e) {
    if (launch_from_environment().rank == 0) std::cerr << "polrig: error: " << e.what() << "\n";
    return 2;
  }
  cli::set_ranks(job ? *job : this_process_only());
  const bool root = cli::ranks().is_root();
  cli::set_command_line(argc, argv);
  CLI::App app{"polrig: simulator and calibration toolkit for polarization-sensor calibration rigs"};
  app.set_version_flag("--version", fmt::format("polrig {} ({})", POLRIG_VERSION, POLRIG_GIT_REVISION));
  app.require_subcommand(1);
  int threads = 0;
  cli::add_threads_option(app, threads);

  std::vector<cli::Command> commands = cli::add_rig_commands(app, threads);
  CLI::App* study = app.get_subcommand("study");
  for (cli::Command& c : cli::add_calibration_commands(app, *study, threads)) commands.push_back(c);
  for (cli::Command& c : cli::add_spectral_commands(app)) commands.push_back(c);
  for (cli::Command& c : cli::add_nav_commands(app, *study, threads)) commands.push_back(c);
  for (cli::Command& c : cli::add_sky_commands(app, threads)) commands.push_back(c);
  for (cli::Command& c : cli::add_position_commands(app, *study, threads)) commands.push_back(c);
  for (cli::Command& c : cli::add_navigation_commands(app, threads)) commands.push_back(c);
  for (cli::Command& c : cli::add_navigation_study_commands(app, *study, threads)) commands.push_back(c);
  for (cli::Command& c : cli::add_sky_study_commands(app, *study, threads)) commands.push_back(c);
  cli::add_quiet_option(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return root ? app.exit(e) : 0;
  } catch (const CLI::CallForAllHelp& e) {
    return root ? app.exit(e) : 0;
  } catch (const CLI::CallForVersion& e) {
    return root ? app.exit(e) : 0;
  } catch (const CLI::ParseError& e) {
    // A usage error, exit 2 as every other bad input; every rank parsed the same line.
    if (root) std::cerr << "polrig: error: " << cli::usage_error(app, argc, argv, e) << "\n";
    return 2;
  }

  // The sphere cache (docs/cli.md, "The sphere cache"): rank 0 alone writes it and warns.
  install_sphere_cache(sphere_cache_from_environment(root, [root](const std::string& warning) {
    if (!root) return;
    cli::end_progress_line();
    std::cerr << "polrig: warning: " << warning << "\n";
  }));
  std::unique_ptr<tbb::global_control> limit;
  if (threads > 0)
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                  static_cast<std::size_t>(threads));
  try {
    for (cli::Command& c : commands)
      if (c.app->parsed()) {
        if (cli::ranks().size() > 1 && !c.distributes)
          throw RigError(fmt::format(
              "polrig {} runs as one process, but was started as {} MPI ranks: it does not share "
              "its work between ranks (only polrig sweep and polrig study calibration do; "
              "docs/scale.md). Run it without mpirun/srun, or with -np 1",
              command_name(c.app), cli::ranks().size()));
        cli::refuse_output_over_inputs(*c.app);
        c.run();
        cli::write_stage_times(std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(),
                               static_cast<double>(std::clock()) / CLOCKS_PER_SEC);
        break;
      }
  } catch (...) {
    const cli::Failure f = cli::failure_of(std::current_exception());
    if (root) {
      cli::end_progress_line();
      std::cerr << "polrig: error: " << f.message << "\n";
    }
    return f.exit_code;
  }
  return 0;
}
