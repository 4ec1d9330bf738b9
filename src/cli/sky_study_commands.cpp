// What the real sky does to each compass: study sky (spec skies.md §5; docs/physics.md §23).
#include <algorithm>
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
#include "polrig/report/sky_study_report.h"
#include "polrig/rig/error.h"
#include "polrig/rig/rig.h"
#include "polrig/study/sky_compasses.h"

namespace polrig::cli {

namespace {

// The option of `polrig study sky` that sets a SkyStudySettings field.
std::string study_sky_option(std::string_view field) {
  static const std::pair<std::string_view, const char*> options[] = {
      {"tau", "--tau"},         {"albedo", "--albedo"},   {"sun_el_deg", "--sun-el-deg"}, {"tilt_deg", "--tilts"},
      {"heading_deg", "--headings"}, {"noise_sd", "--noise"}, {"trials", "--trials"},       {"min_dop", "--min-dop"},
      {"grid_cols", "--grid"},  {"mu_cells", "--sky-cells"}};
  for (const auto& [f, option] : options)
    if (f == field) return option;
  return std::string(field);
}

// The published method's largest errors per sky and tilt, one line each.
void print_summary(const SkyStudy& study) {
  struct Line {
    std::string sky;
    double tilt, heading = 0, el = 0;
  };
  std::vector<Line> lines;
  for (const SkyBiasRow& r : study.bias) {
    if (r.method != SkyMethod::Published) continue;
    const std::string sky = r.sky.kind == SkyKind::SingleScattering
                                ? std::string("single scattering")
                                : fmt::format("vector-RT τ = {}, A = {}", r.sky.tau, r.sky.albedo);
    auto l = std::find_if(lines.begin(), lines.end(),
                          [&](const Line& x) { return x.sky == sky && x.tilt == r.tilt_deg; });
    if (l == lines.end()) l = lines.insert(lines.end(), {sky, r.tilt_deg});
    if (std::isfinite(r.heading_error_deg)) l->heading = std::max(l->heading, std::abs(r.heading_error_deg));
    if (std::isfinite(r.sun_el_error_deg)) l->el = std::max(l->el, std::abs(r.sun_el_error_deg));
  }
  const bool has_el = study.compass.kind != SkyCompassKind::ZenithEVector;
  for (const Line& l : lines)
    std::cout << fmt::format("{}, {}, tilt {}°: largest |heading error| {:.4f}°{}\n", study.compass.device, l.sky, l.tilt,
                             l.heading,
                             has_el ? fmt::format(", largest |sun elevation error| {:.4f}° ({:.1f} km of position line)",
                                                  l.el, 111.195 * l.el)
                                    : std::string());
}

}  // namespace

std::vector<Command> add_sky_study_commands(CLI::App& /*root*/, CLI::App& study, int& threads) {
  std::vector<Command> commands;
  auto* app = study.add_subcommand(
      "sky",
      "the rig's compass under the exact vector-RT sky, read by its own single-scattering method: the bias and "
      "spread of its heading, sun elevation and position line against τ, the ground's albedo, the sun's elevation "
      "and the tilt, beside the single-scattering sky");
  auto rig = std::make_shared<RigInput>();
  auto out = std::make_shared<OutputOptions>();
  auto s = std::make_shared<SkyStudySettings>();
  auto tau = std::make_shared<std::string>("0.05,0.1,0.25,0.5");
  auto albedo = std::make_shared<std::string>("0,0.25,0.8");
  auto elevations = std::make_shared<std::string>("5:85:17");
  auto tilts = std::make_shared<std::string>("0,5,10");
  auto headings = std::make_shared<std::string>("0,45,90,135,180,225,270,315");
  auto seed = std::make_shared<std::uint64_t>(0);
  rig->add_to(*app, true);
  out->add_to(*app);
  app->add_option("--tau", *tau, "the vector-RT skies' Rayleigh optical depths, comma-separated")->capture_default_str();
  app->add_option("--albedo", *albedo, "the ground's albedos, comma-separated (each with every τ)")->capture_default_str();
  app->add_option("--sun-el-deg", *elevations, "the sun's elevations: X, X,Y,… or A:B:N, degrees")->capture_default_str();
  app->add_option("--tilts", *tilts, "the compass's tilts (roll), degrees, comma-separated")->capture_default_str();
  app->add_option("--headings", *headings, "the compass's headings relative to the sun's azimuth, degrees, comma-separated")
      ->capture_default_str();
  app->add_option("--noise", s->noise_sd, "the SD of the noise on each view's normalised Stokes q = Q/I and u = U/I")
      ->check(finite_range(0, 1))->capture_default_str();
  app->add_option("--trials", s->trials, "noisy readings per row (0: the noise-free reading only)")
      ->check(CLI::Range(0, 100000))->capture_default_str();
  app->add_option("--min-dop", s->min_dop, "the min-dop method's threshold")->check(finite_range(0, 1))->capture_default_str();
  app->add_option("--grid", s->grid_cols, "the cameras' points across the image")->check(CLI::Range(4, 2048))
      ->capture_default_str();
  app->add_option("--sky-cells", s->mu_cells, "the whole-sky statistics' cells in cos θ (× 4 in azimuth)")
      ->check(CLI::Range(4, 1000))->capture_default_str();
  app->add_option("--seed", *seed, "random seed (default: the rig's seed)");
  add_threads_option(*app, threads);
  commands.push_back({app, [=] {
    SkyStudySettings settings = *s;
    const LoadedRig r = rig->load();
    const std::optional<Sky> sky = rig_sky(r.rig);
    if (!sky) throw RigError(no_sky_message(r.rig, r.origin));
    // The depolarization, the streams and the aerosol; τ and A are the sweep's.
    settings.rt = r.rig.source.sky.resolved_rt();
    settings.P_max = sky->model.P_max;
    settings.seed = app->count("--seed") > 0 ? *seed : r.rig.seed;
    settings.tau = parse_number_list(*tau, "--tau");
    settings.albedo = parse_number_list(*albedo, "--albedo");
    settings.sun_el_deg = parse_elevations(*elevations);
    settings.tilt_deg = parse_number_list(*tilts, "--tilts");
    settings.heading_deg = parse_number_list(*headings, "--headings");
    SkyCompass compass;
    try {
      check_sky_study_settings(settings, [](std::string_view field) { return study_sky_option(field); });
      compass = sky_compass(r.rig, settings.grid_cols);
    } catch (const std::invalid_argument& e) {
      throw DataError(fmt::format("{}: {}", r.origin, e.what()));
    }
    OutputDir dir = out->open();
    const SkyStudy result = sky_study(compass, settings, progress());
    write_manifest(dir.staging(), {command_line(), &r, report_sky_study(dir.staging(), result, out->plots())});
    finish(dir);
    print_summary(result);
  }});
  return commands;
}

}  // namespace polrig::cli
