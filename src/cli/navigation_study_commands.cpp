// study navigation: Monte-Carlo of Z21's unit-array compass with its INS (spec sky-and-compasses.md
// §4.5–4.6): trials, sweeps, Fig. 17's tilt study and Fig. 16's DoP bins.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "cli.h"
#include "polrig/io/measured.h"
#include "polrig/report/navigation_study_report.h"
#include "polrig/rig/error.h"
#include "polrig/study/navigation_study.h"

namespace polrig::cli {

namespace {

// The option of `polrig study navigation` that sets a NavigationStudySettings field.
std::string study_navigation_option(std::string_view field) {
  static const std::pair<std::string_view, const char*> options[] = {
      {"trials", "--trials"}, {"durations_s", "--durations"}, {"p_max", "--p-max"},
      {"noise_sigma_V", "--noise"}, {"ring_tilts_deg", "--ring-tilts"}, {"tilts_deg", "--tilts"}};
  for (const auto& [f, option] : options)
    if (f == field) return option;
  return std::string(field);
}

}  // namespace

std::vector<Command> add_navigation_study_commands(CLI::App& /*root*/, CLI::App& study, int& threads) {
  std::vector<Command> commands;
  auto* app = study.add_subcommand(
      "navigation",
      "Monte-Carlo of a unit-array rig's SINS, PNS and SINS/PNS (Z21): trials, sweeps of the run's length, "
      "P_max, noise and ring tilt, Fig. 17's tilt study and Fig. 16's DoP bins");
  auto rig = std::make_shared<RigInput>();
  auto out = std::make_shared<OutputOptions>();
  auto s = std::make_shared<NavigationStudySettings>();
  auto durations = std::make_shared<std::string>();
  auto p_max = std::make_shared<std::string>();
  auto noise = std::make_shared<std::string>();
  auto ring_tilts = std::make_shared<std::string>();
  auto tilts = std::make_shared<std::string>("0.5,1,2");
  rig->add_to(*app, true);
  out->add_to(*app);
  app->add_option("--trials", s->trials, "trials per cell (trial k: seed derive_seed(rig seed, k))")
      ->check(CLI::Range(1, 100000))->capture_default_str();
  app->add_option("--durations", *durations, "sweep trajectory.duration_s: run lengths, s, comma-separated");
  app->add_option("--p-max", *p_max, "sweep sky.p_max: the sky's P_max values, comma-separated");
  app->add_option("--noise", *noise, "sweep electronics.noise_sigma_V: compass noise per sample, V, comma-separated");
  app->add_option("--ring-tilts", *ring_tilts, "sweep device.units.ring_tilt_deg: ring tilts, degrees, comma-separated");
  app->add_option("--tilts", *tilts,
                  "Fig. 17: horizontal-attitude errors, degrees, comma-separated (a random direction per reading)")
      ->capture_default_str();
  add_threads_option(*app, threads);
  commands.push_back({app, [=] {
    NavigationStudySettings settings = *s;
    const LoadedRig r = rig->load();
    settings.durations_s = parse_number_list(*durations, "--durations", true);
    settings.p_max = parse_number_list(*p_max, "--p-max", true);
    settings.noise_sigma_V = parse_number_list(*noise, "--noise", true);
    settings.ring_tilts_deg = parse_number_list(*ring_tilts, "--ring-tilts", true);
    settings.tilts_deg = parse_number_list(*tilts, "--tilts", true);
    const auto named = [](std::string_view field) { return study_navigation_option(field); };
    try {
      check_navigation_study_settings(r.rig, settings, named);
    } catch (const std::invalid_argument& e) {
      throw DataError(fmt::format("{}: {}", r.origin, e.what()));
    } catch (const RigError& e) {
      throw RigError(fmt::format("{}: {}", r.origin, e.what()));
    }
    OutputDir dir = out->open();
    NavigationStudy result;
    try {
      result = navigation_study(r.rig, settings, progress());
    } catch (const std::invalid_argument& e) {  // a cell's run its rig cannot fly (a trajectory past the pole)
      throw RigError(fmt::format("{}: {}", r.origin, e.what()));
    }
    write_manifest(dir.staging(), {command_line(), &r, report_navigation_study(dir.staging(), result, out->plots())});
    finish(dir);
    for (const NavigationStudySummary& st : result.summary) {
      const NavigationStudyCell& c = result.cells[static_cast<std::size_t>(st.cell)];
      const std::string cell = c.index == 0 ? "rig" : fmt::format("{}={}", c.key, c.value);
      std::cout << fmt::format("{} {:>10}: final error median {:.0f} m (25–75 % {:.0f}–{:.0f} m, {}/{} trials), "
                               "latitude MAE median {:.4f}°, longitude {:.4f}°\n",
                               cell, navigation_mode_name(st.mode), st.final_error_m.p50, st.final_error_m.p25,
                               st.final_error_m.p75, st.final_error_m.count, st.trials, st.lat_mae_deg.p50,
                               st.lon_mae_deg.p50);
    }
    for (const NavigationConsistency& c : result.consistency) {
      const NavigationStudyCell& cell = result.cells[static_cast<std::size_t>(c.cell)];
      const auto text = [](const ConsistencyBand& b) {
        return fmt::format("{:.3g} (95 % band {:.3g}–{:.3g}: {})", b.mean, b.lo, b.hi, b.inside() ? "inside" : "outside");
      };
      std::cout << fmt::format("{} consistency over {} trials: NEES position {}, attitude {}; NIS {}\n",
                               cell.index == 0 ? std::string("rig") : fmt::format("{}={}", cell.key, cell.value),
                               c.trials, text(c.nees_position), text(c.nees_attitude), text(c.nis));
    }
    for (const NavigationGoal& g : result.goal) {
      const NavigationStudyCell& cell = result.cells[static_cast<std::size_t>(g.cell)];
      const auto pct = [&](int k) { return g.trials == 0 ? 0.0 : 100.0 * k / g.trials; };
      std::cout << fmt::format("{} goal over {} trials: integrated no worse than the better of SINS and PNS at the end in "
                               "{:.0f} % (position), {:.0f} % (heading), {:.0f} % (both)\n",
                               cell.index == 0 ? std::string("rig") : fmt::format("{}={}", cell.key, cell.value),
                               g.trials, pct(g.position_met), pct(g.heading_met), pct(g.both_met));
    }
    for (const TiltErrorRow& t : result.tilt)
      std::cout << fmt::format("tilt {}°: mean |elevation error| {:.3f}° (standard error {:.3f}°, {} readings; (2/π)·τ = {:.3f}°, "
                               "exact at H = {:.1f}°: {:.3f}°{})\n",
                               t.tilt_deg, t.mean_abs_deg, t.sd_abs_deg / std::sqrt(static_cast<double>(std::max(1LL, t.draws))),
                               t.draws, t.first_order_deg, result.tilt_mean_elevation_deg, t.exact_deg,
                               std::isnan(t.z21_deg) ? std::string() : fmt::format("; Z21 {}°", t.z21_deg));
    for (const DopBin& b : result.dop)
      if (!std::isnan(b.z21_mean_deg))
        std::cout << fmt::format("DoP {:.0f}–{:.0f} %: {} (Z21 {}°, SD {}°)\n", 100 * b.lo, 100 * b.hi,
                                 b.count == 0 ? std::string("no readings")
                                              : fmt::format("|E-vector error| mean {:.4f}°, SD {:.4f}°, over {} readings",
                                                            b.mean_abs_deg, b.sd_abs_deg, b.count),
                                 b.z21_mean_deg, b.z21_sd_deg);
  }});
  return commands;
}

}  // namespace polrig::cli
