// polrig: the command-line front end. Each command loads and checks all of its input first,
// computes into a staging folder, and renames it into place only when everything is written.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <tbb/global_control.h>
#include <tbb/info.h>

#include "polrig/io/manifest.h"
#include "polrig/io/output_dir.h"
#include "polrig/io/plot.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/rig/keys.h"
#include "polrig/study/adc_limit.h"
#include "polrig/study/cs.h"
#include "polrig/study/reports.h"
#include "polrig/study/sweep.h"
#include "polrig/version.h"

namespace fs = std::filesystem;
using namespace polrig;

namespace {

// Options shared by every command that takes a rig and writes a folder.
struct RigCommand {
  std::string rig_path;
  std::vector<std::string> sets;
  std::string out;
  bool force = false;
  bool no_plots = false;

  void add_to(CLI::App& app, bool rig_required = true) {
    auto* r = app.add_option("RIG", rig_path, "rig file (YAML), e.g. rigs/wang2019-indoor.yaml");
    if (rig_required) r->required();
    app.add_option("--set", sets, "override a rig value: key.path=value (repeatable)")
        ->type_name("KEY=VALUE");
    app.add_option("-o,--out", out, "output folder (written whole or not at all)")->required();
    app.add_flag("--force", force, "replace the output folder if it exists");
    app.add_flag("--no-plots", no_plots, "write the CSV files only, no PNG plots");
  }

  LoadedRig load() const {
    std::vector<RigOverride> overrides;
    for (const std::string& s : sets) overrides.push_back(RigOverride::parse(s));
    return load_rig(rig_path, overrides);
  }
};

std::string g_command_line;

void require_plotting(bool no_plots) {
  if (!no_plots && !gnuplot_available())
    throw std::runtime_error(
        "gnuplot is needed for the PNG plots and was not found; install it (scripts/setup-deps.sh) "
        "or pass --no-plots");
}

void finish(OutputDir& out) {
  out.commit();
  std::cout << "wrote " << out.destination().string() << "\n";
}

void run_simulate(const RigCommand& c, bool samples) {
  const LoadedRig rig = c.load();
  require_plotting(c.no_plots);
  const Simulation sim = simulate(rig.rig, samples);
  OutputDir out(c.out, c.force);
  auto files = report_simulation(out.staging(), sim, !c.no_plots);
  write_manifest(out.staging(), {g_command_line, &rig, files});
  finish(out);
}

void run_study_cs(const RigCommand& c, int steps) {
  const LoadedRig rig = c.load();
  require_plotting(c.no_plots);
  const CsStudy study = cs_study(rig.rig, CsTurn(steps));
  OutputDir out(c.out, c.force);
  auto files = report_cs_study(out.staging(), study, !c.no_plots);
  write_manifest(out.staging(), {g_command_line, &rig, files});
  finish(out);
}

std::vector<double> parse_d_list(const std::string& text) {
  std::vector<double> ds;
  if (text.find(':') != std::string::npos) {
    const GridAxis axis = GridAxis::parse("device.d=" + text);
    for (int i = 0; i < axis.count; ++i) ds.push_back(axis.value(i));
    return ds;
  }
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t comma = std::min(text.find(',', pos), text.size());
    const double d = parse_finite_number(std::string_view(text).substr(pos, comma - pos), "--d");
    if (!(d > 0.0 && d < 1.0))
      throw RigError(fmt::format("--d {}: expected degrees of polarization in (0, 1), got {}", text, d));
    ds.push_back(d);
    pos = comma + 1;
  }
  return ds;
}

void run_study_adc(const RigCommand& c, const std::string& d_list, double step_deg) {
  // The ADC study uses the rig's electronics and film axes; without a rig, the default rig's.
  std::optional<LoadedRig> rig;
  if (!c.rig_path.empty()) rig = c.load();
  const Rig r = rig ? rig->rig : Rig{};
  const std::vector<double> ds = parse_d_list(d_list);
  if (!(step_deg > 0.0 && step_deg <= 10.0))
    throw RigError(fmt::format("--step {}: expected a step in (0, 10] degrees", step_deg));
  require_plotting(c.no_plots);
  std::vector<AdcLimit> limits(ds.size());
  for (std::size_t k = 0; k < ds.size(); ++k)
    limits[k] = adc_accuracy_limit(ds[k], r.electronics, r.device.film_axis_deg, step_deg);
  OutputDir out(c.out, c.force);
  auto files = report_adc_limits(out.staging(), limits, !c.no_plots);
  write_manifest(out.staging(), {g_command_line, rig ? &*rig : nullptr, files});
  finish(out);
}

void run_sweep(const RigCommand& c, const std::vector<std::string>& grids, int steps) {
  const LoadedRig rig = c.load();
  std::vector<GridAxis> axes;
  for (const std::string& g : grids) axes.push_back(GridAxis::parse(g));
  require_plotting(c.no_plots);
  const bool tty = ::isatty(2);
  const auto t0 = std::chrono::steady_clock::now();
  auto last = t0;
  const SweepResult result = sweep(rig.rig, axes, CsTurn(steps), [&](std::size_t done, std::size_t total) {
    const auto now = std::chrono::steady_clock::now();
    if (done < total && now - last < std::chrono::milliseconds(500)) return;
    last = now;
    const double s = std::chrono::duration<double>(now - t0).count();
    std::fprintf(stderr, "%ssweep: %zu/%zu grid points (%.0f%%), %.1f s%s", tty ? "\r" : "", done,
                 total, 100.0 * static_cast<double>(done) / static_cast<double>(total), s,
                 (tty && done < total) ? "" : "\n");
  });
  OutputDir out(c.out, c.force);
  auto files = report_sweep(out.staging(), result, !c.no_plots);
  write_manifest(out.staging(), {g_command_line, &rig, files});
  finish(out);
}

// The main job: the indoor calibration run (simulate), the CS study and the ADC limits.
void run_all(const RigCommand& c) {
  const LoadedRig rig = c.load();
  require_plotting(c.no_plots);
  const Simulation sim = simulate(rig.rig, false);
  const CsStudy study = cs_study(rig.rig, CsTurn(360));
  std::vector<AdcLimit> limits;
  for (int k = 1; k <= 19; ++k)
    limits.push_back(adc_accuracy_limit(k / 20.0, rig.rig.electronics, rig.rig.device.film_axis_deg));
  OutputDir out(c.out, c.force);
  const fs::path sim_dir = out.staging() / "simulate", cs_dir = out.staging() / "cs",
                 adc_dir = out.staging() / "adc";
  for (const fs::path& d : {sim_dir, cs_dir, adc_dir}) fs::create_directory(d);
  write_manifest(sim_dir, {g_command_line, &rig, report_simulation(sim_dir, sim, !c.no_plots)});
  write_manifest(cs_dir, {g_command_line, &rig, report_cs_study(cs_dir, study, !c.no_plots)});
  write_manifest(adc_dir, {g_command_line, &rig, report_adc_limits(adc_dir, limits, !c.no_plots)});
  finish(out);
  const CsSummary& s = study.summary;
  std::cout << "CS study at the rig's eccentricity (mV):\n"
            << "pair     BSD       ASD   mean_br   mean_mr     Eq. 6\n";
  for (int i = 0; i < 3; ++i)
    std::cout << fmt::format("{:4d} {:9.5f} {:9.5f} {:9.5f} {:9.5f} {:9.5f}\n", i + 1, s[i].bsd_mV,
                             s[i].asd_mV, s[i].mean_br_mV, s[i].mean_mr_mV, s[i].eq6_mV);
}

void print_keys_markdown() {
  Rig defaults;
  std::cout << "| key | unit | default | accepts | meaning |\n|---|---|---|---|---|\n";
  for (const RigKey& k : rig_keys()) {
    std::string def;
    using K = RigKey::Kind;
    switch (k.kind) {
      case K::Real: def = fmt::format("{}", k.real(defaults)); break;
      case K::Integer: def = fmt::format("{}", k.integer(defaults)); break;
      case K::Seed: def = fmt::format("{}", k.seed(defaults)); break;
      case K::Text: def = k.text(defaults); break;
      case K::RealArray: def = fmt::format("[{}]", fmt::join(k.array(defaults), ", ")); break;
      case K::RealList: def = "(none)"; break;
    }
    std::cout << fmt::format("| `{}` | {} | {} | {} | {} |\n", k.path, k.unit, def, k.expects, k.doc);
  }
}

}  // namespace

int main(int argc, char** argv) {
  for (int i = 0; i < argc; ++i) g_command_line += (i ? " " : "") + std::string(argv[i]);
  g_command_line.replace(0, std::string(argv[0]).size(), "polrig");

  CLI::App app{"polrig: simulator and calibration toolkit for polarization-sensor calibration rigs"};
  app.set_version_flag("--version", fmt::format("polrig {} ({})", POLRIG_VERSION, POLRIG_GIT_REVISION));
  app.require_subcommand(1);
  int threads = 0;
  app.add_option("--threads", threads, "worker threads (default: all cores); results do not depend on it")
      ->check(CLI::Range(1, 1024));

  RigCommand sim_cmd, cs_cmd, adc_cmd, sweep_cmd, run_cmd, show_cmd;
  bool samples = false;
  int cs_steps = 360, sweep_steps = 360;
  std::string d_list = "0.05:0.95:19";
  double adc_step = 0.1;
  std::vector<std::string> grids;

  auto* sim = app.add_subcommand("simulate", "synthetic measurements over the rig's table schedule");
  sim_cmd.add_to(*sim);
  sim->add_flag("--samples", samples, "also write every quantized sample (samples.csv)");

  auto* study = app.add_subcommand("study", "studies of the rig");
  study->require_subcommand(1);
  auto* cs = study->add_subcommand("cs", "central-symmetry study over a full turn (Figs. 8-9)");
  cs_cmd.add_to(*cs);
  cs->add_option("--steps", cs_steps, "table angles per turn (even)")->check(CLI::Range(2, 3600000));
  auto* adc = study->add_subcommand("adc", "ADC accuracy limit against d (Fig. 6)");
  adc_cmd.add_to(*adc, false);
  adc->add_option("--d", d_list, "degrees of polarization: a,b,c or start:stop:count")->capture_default_str();
  adc->add_option("--step", adc_step, "θ step in degrees")->capture_default_str();

  auto* sw = app.add_subcommand("sweep", "the CS study over a grid of rig keys (Figs. 10-12)");
  sweep_cmd.add_to(*sw);
  sw->add_option("--grid", grids, "key=start:stop:count (repeatable: the product grid)")->required();
  sw->add_option("--steps", sweep_steps, "table angles per turn (even)")->check(CLI::Range(2, 3600000));

  auto* run = app.add_subcommand("run", "the main job: simulate, CS study and ADC limits into one folder");
  run_cmd.add_to(*run);

  auto* rig = app.add_subcommand("rig", "inspect rig files");
  rig->require_subcommand(1);
  auto* show = rig->add_subcommand("show", "print the effective rig (file + overrides + defaults)");
  show->add_option("RIG", show_cmd.rig_path, "rig file")->required();
  show->add_option("--set", show_cmd.sets, "override a rig value: key.path=value (repeatable)");
  auto* keys = rig->add_subcommand("keys", "print every rig key as a Markdown table");

  // --threads is accepted before the command and after it.
  for (CLI::App* sub : {sim, cs, adc, sw, run})
    sub->add_option("--threads", threads, "worker threads (default: all cores)")
        ->check(CLI::Range(1, 1024));
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
    if (*sim) run_simulate(sim_cmd, samples);
    else if (*cs) run_study_cs(cs_cmd, cs_steps);
    else if (*adc) run_study_adc(adc_cmd, d_list, adc_step);
    else if (*sw) run_sweep(sweep_cmd, grids, sweep_steps);
    else if (*run) run_all(run_cmd);
    else if (*show) std::cout << rig_to_yaml(show_cmd.load().rig);
    else if (*keys) print_keys_markdown();
  } catch (const RigError& e) {
    std::cerr << "polrig: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "polrig: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
