// polrig: the command-line front end.
#include <iostream>
#include <memory>

#include <fmt/format.h>
#include <tbb/global_control.h>

#include "cli.h"
#include "polrig/calib/fit.h"
#include "polrig/io/measured.h"
#include "polrig/io/output_dir.h"
#include "polrig/version.h"

using namespace polrig;

int main(int argc, char** argv) {
  clean_up_outputs_on_signals();  // first: before any other thread exists
  cli::set_command_line(argc, argv);
  CLI::App app{"polrig: simulator and calibration toolkit for polarization-sensor calibration rigs"};
  app.set_version_flag("--version", fmt::format("polrig {} ({})", POLRIG_VERSION, POLRIG_GIT_REVISION));
  app.require_subcommand(1);
  int threads = 0;
  cli::add_threads_option(app, threads);

  std::vector<cli::Command> commands = cli::add_rig_commands(app, threads);
  CLI::App* study = app.get_subcommand("study");
  for (cli::Command& c : cli::add_calibration_commands(app, *study, threads)) commands.push_back(c);
  for (cli::Command& c : cli::add_sky_commands(app, threads)) commands.push_back(c);
  cli::add_quiet_option(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }

  std::unique_ptr<tbb::global_control> limit;
  if (threads > 0)
    limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                  static_cast<std::size_t>(threads));
  try {
    for (cli::Command& c : commands)
      if (c.app->parsed()) {
        c.run();
        break;
      }
  } catch (const RigError& e) {
    cli::end_progress_line();
    std::cerr << "polrig: error: " << e.what() << "\n";
    return 2;
  } catch (const DataError& e) {
    cli::end_progress_line();
    std::cerr << "polrig: error: " << e.what() << "\n";
    return 2;
  } catch (const CalibrationError& e) {
    cli::end_progress_line();
    std::cerr << "polrig: error: cannot calibrate: " << e.what() << "\n";
    return 3;
  } catch (const std::exception& e) {
    cli::end_progress_line();
    std::cerr << "polrig: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
