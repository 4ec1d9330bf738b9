// Positioning from the sun's zenith angle: study positioning (W16 Eqs. 15 and 17, spec
// sky-and-compasses.md §3.4–3.6).
#include <cmath>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

#include <fmt/format.h>

#include "cli.h"
#include "polrig/io/measured.h"
#include "polrig/report/positioning_reports.h"
#include "polrig/rig/error.h"
#include "polrig/rig/rig.h"
#include "polrig/study/positioning.h"

namespace polrig::cli {

namespace {

// The option of `polrig study positioning` that sets a PositioningStudySettings field.
std::string study_positioning_option(std::string_view field) {
  static const std::pair<std::string_view, const char*> options[] = {
      {"trials", "--trials"}, {"windows_s", "--windows"}, {"noise_sd_deg", "--noise"},
      {"tilt_deg", "--tilts"}, {"baseline_noise_sd_deg", "--baseline-noise"},
      {"baseline_tilt_deg", "--baseline-tilt"}, {"correlation_s", "--correlation"},
      {"prior_offset_km", "--prior-offset"}, {"times_s", "the rig's stop times (schedule)"},
      {"site", "the rig's sky site"}};
  for (const auto& [f, option] : options)
    if (f == field) return option;
  return std::string(field);
}

}  // namespace

std::vector<Command> add_position_commands(CLI::App& /*root*/, CLI::App& study, int& threads) {
  std::vector<Command> commands;
  auto* app = study.add_subcommand(
      "positioning",
      "Monte-Carlo of the position fix from the sun's zenith angle (W16 Eq. 17) against the window, "
      "the zenith-angle noise and the levelling error, beside Eq. 15");
  auto rig = std::make_shared<RigInput>();
  auto out = std::make_shared<OutputOptions>();
  auto s = std::make_shared<PositioningStudySettings>();
  auto windows = std::make_shared<std::string>();
  auto noise = std::make_shared<std::string>("0,0.02,0.05,0.14,0.3,0.5");
  auto tilts = std::make_shared<std::string>("0,0.02,0.05,0.1,0.2");
  auto seed = std::make_shared<std::uint64_t>(0);
  rig->add_to(*app, true);
  out->add_to(*app);
  app->add_option("--windows", *windows,
                  "window lengths from the first stop, s, comma-separated (default: the stops' span × "
                  "1/60, 1/30, 1/12, 1/6, 1/3, 1/2, 1)");
  app->add_option("--noise", *noise, "zenith-angle noise SDs, degrees, comma-separated")->capture_default_str();
  app->add_option("--tilts", *tilts, "levelling errors, degrees, comma-separated (towards a random azimuth per trial)")
      ->capture_default_str();
  app->add_option("--baseline-noise", s->baseline_noise_sd_deg, "the noise SD of the window and tilt sweeps, degrees")
      ->check(finite_range(0, 10, "°"))->capture_default_str();
  app->add_option("--baseline-tilt", s->baseline_tilt_deg, "the levelling error of the window and noise sweeps, degrees")
      ->check(finite_range(0, 10, "°"))->capture_default_str();
  app->add_option("--correlation", s->correlation_s,
                  "correlation time of the zenith-angle noise (first-order Gauss-Markov), s; 0: white")
      ->check(finite_range(0, 1e5, "s"))->capture_default_str();
  app->add_option("--prior-offset", s->prior_offset_km, "distance of the fit's prior from the truth (random direction), km")
      ->check(finite_range(0, 2000, "km"))->capture_default_str();
  app->add_option("--trials", s->trials, "trials per cell")->check(CLI::Range(1, 1000000))->capture_default_str();
  app->add_option("--seed", *seed, "random seed (default: the rig's seed)");
  app->add_flag("--second-root", s->second_root,
                "also search the mirror root in every fit (twice the work); every cell reports M′ either way");
  add_threads_option(*app, threads);
  commands.push_back({app, [=] {
    PositioningStudySettings settings = *s;
    const LoadedRig r = rig->load();
    const std::optional<Sky> sky = rig_sky(r.rig);
    if (!sky) throw RigError(no_sky_message(r.rig, r.origin));
    settings.site = sky->site;
    settings.first = sky->first_stop;
    settings.sun = sky->sun;
    settings.times_s = r.rig.schedule.stop_times_s();
    settings.seed = app->count("--seed") > 0 ? *seed : r.rig.seed;
    if (!windows->empty()) settings.windows_s = parse_number_list(*windows, "--windows");
    settings.noise_sd_deg = parse_number_list(*noise, "--noise");
    settings.tilt_deg = parse_number_list(*tilts, "--tilts");
    try {
      check_positioning_study_settings(settings, [](std::string_view field) { return study_positioning_option(field); });
    } catch (const std::invalid_argument& e) {
      throw DataError(fmt::format("{}: {}", r.origin, e.what()));
    }
    OutputDir dir = out->open();
    const PositioningStudy result = positioning_study(settings, progress());
    write_manifest(dir.staging(), {command_line(), &r, report_positioning_study(dir.staging(), result, out->plots())});
    finish(dir);
    for (std::size_t i = 0; i < result.cells.size(); ++i) {
      const PositioningCell& c = result.cells[i];
      if (c.factor != "noise") continue;
      const PositioningStats& st = result.stats[i];
      std::cout << fmt::format("window {} s, noise {}°, tilt {}°: RMS position error {:.3f} km "
                               "({}/{} converged; Eq. 15 over Δβ = {:.2f}°: {:.1f} km, linearized: {:.3f} km; "
                               "mirror root {:.0f} km away, {} fixes nearer it)\n",
                               c.window_s, c.noise_sd_deg, c.tilt_deg, st.rms_km, st.converged, st.trials,
                               c.delta_beta_deg, c.eq15_km, c.linear_rms_km, c.mirror_km, st.wrong_root);
    }
  }});
  return commands;
}

}  // namespace polrig::cli
