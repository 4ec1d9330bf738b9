// `polrig sky` (an all-sky map of the Rayleigh sky) and `polrig sky table` (the sun and the sky's
// polarization along given directions at given times and places).
#include <cmath>
#include <future>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "cli.h"
#include "polrig/io/csv.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/io/sky_files.h"
#include "polrig/report/sky_reports.h"
#include "polrig/sky/sun_rows.h"
#include "polrig/sky/sky.h"
#include "polrig/sky/sky_map.h"

namespace polrig::cli {
namespace {

struct SkyOptions {
  std::string site, utc, radiance = "uniform";
  double p_max = 0.7;
  SunSettings sun;
  void add_to(CLI::App& app, bool map) {
    app.add_option("--p-max", p_max, "maximum degree of polarization P_max, (0, 1]")
        ->check(finite_range(1e-6, 1.0))->capture_default_str();
    add_sun_options(app, sun);
    if (!map) return;
    app.add_option("--site", site, "LAT,LON in degrees, north and east positive (default: W19's roof in Dalian, 38.879167,121.543889)");
    app.add_option("--utc", utc, "ISO 8601 UTC time with a Z (default: 2018-11-16T08:09:40Z, W19 Outdoor1)");
    app.add_option("--radiance", radiance, "radiance model")
        ->check(CLI::IsMember({"uniform", "rayleigh", "cie-clear"}))->capture_default_str();
  }
  // The sky of the options, starting from `base` (a rig's sky block, or the defaults); with a
  // rig, only the options given on the command line (`app` counts them) change it.
  Sky sky(const Sky& base = {}, const CLI::App* app = nullptr) const {
    Sky s = base;
    const auto given = [&](const char* option) {
      return app == nullptr || (app->get_option_no_throw(option) != nullptr && app->count(option) > 0);
    };
    if (!site.empty()) s.site = parse_site(site);
    if (!utc.empty()) s.first_stop = parse_utc_option(utc);
    if (given("--p-max")) s.model.P_max.constant = p_max;
    if (given("--radiance")) s.model.radiance = *parse_sky_radiance(radiance);  // CLI::IsMember has refused anything else
    if (given("--refraction")) s.sun.refraction = sun.refraction;
    if (given("--ut1-minus-utc")) s.sun.ut1_minus_utc_s = sun.ut1_minus_utc_s;
    return s;
  }
};

}  // namespace

std::vector<Command> add_sky_commands(CLI::App& root, int& threads) {
  std::vector<Command> commands;
  auto* sky_app = root.add_subcommand(
      "sky", "an all-sky map of the Rayleigh sky (EXR, PNG previews, sun.yaml); `sky table` for points");
  sky_app->require_subcommand(0, 1);

  // ---- sky table (before `sky`: both are "parsed" when it is chosen)
  {
    auto* app = sky_app->add_subcommand(
        "table", "sun position, DoP and AoP at the times, places and view directions of a CSV");
    auto input = std::make_shared<std::string>();
    auto out = std::make_shared<OutputOptions>();
    auto opts = std::make_shared<SkyOptions>();
    app->add_option("INPUT", *input, "CSV with columns utc, lat_deg, lon_deg, view_az_deg, view_el_deg, or "
                                     "sun_az_deg, sun_el_deg, view_az_deg, view_el_deg (a fixed sun)")
        ->required();
    auto rig = std::make_shared<RigInput>();
    app->add_option("--rig", rig->path, "a rig file with source.model sky: its sky block (sky.model, sky.rt.*, "
                                        "P_max, radiance, refraction) is the default of every option");
    add_set_option(*app, rig->sets);
    out->add_to(*app, false);
    opts->add_to(*app, false);
    add_threads_option(*app, threads);
    commands.push_back({app, [=] {
      std::optional<LoadedRig> loaded;
      if (!rig->path.empty() || !rig->sets.empty()) {
        loaded = rig->load();
        if (!rig_sky(loaded->rig)) throw RigError(no_sky_message(loaded->rig, rig->path));
      }
      const Sky sky = loaded ? opts->sky(*rig_sky(loaded->rig), app) : opts->sky();
      const CsvFile in = CsvFile::read(*input);
      const std::vector<SkyQuery> queries = read_sky_table_input(in);  // every cell checked
      // Opened before the work, so that an existing destination fails at once.
      OutputDir dir = out->open(false);
      std::vector<SkySample> samples;
      try {
        samples = sky_along(queries, sky.model, sky.sun, progress());
      } catch (const SunRowError& e) {
        throw DataError(fmt::format("{}:{}: column '{}': {}", in.origin, in.line[e.row],
                                    sky_table_fixed_sun(in) ? "sun_el_deg" : "utc", e.what()));
      }
      write_text_file(dir.staging() / "sky.csv", sky_table_csv(in, samples));
      const bool absolute = !samples.empty() && samples.front().absolute;
      Manifest m{command_line(), loaded ? &*loaded : nullptr,
                 {{"sky.csv", 1,
                   std::string("the input's columns as written, then ") +
                       (sky_table_fixed_sun(in) ? "" : "sun_az_deg, sun_el_deg, ") + "dop, aop_deg" +
                       (absolute ? ", I_sr, Q_sr, U_sr (L/E0 in 1/sr; Q, U in the view's meridian frame)" : "")}}};
      m.inputs.push_back(*input);
      write_manifest(dir.staging(), m);
      finish(dir);
    }});
  }

  // ---- sky
  {
    auto out = std::make_shared<OutputOptions>();
    auto opts = std::make_shared<SkyOptions>();
    auto size = std::make_shared<int>(1024);
    auto rig = std::make_shared<std::string>();
    sky_app->add_option("RIG", *rig, "a rig file with source.model sky: its sky block (site, first "
                                     "stop, P_max, radiance, refraction) is the default of every option");
    auto compression = std::make_shared<std::string>("rle");
    // -o is checked when the map is made: `sky table` has its own.
    sky_app->add_option("-o,--out", out->out, "output folder (written whole or not at all); "
                                              "required unless a subcommand is given");
    sky_app->add_flag("--force", out->force, "replace the output folder if it exists");
    sky_app->add_flag("--no-plots", out->no_plots, "write sky.exr and sun.yaml only, no PNG previews");
    opts->add_to(*sky_app, true);
    sky_app->add_option("--size", *size, "image width = height in pixels")
        ->check(CLI::Range(2, 8192))->capture_default_str();
    sky_app->add_option("--exr-compression", *compression,
                        "sky.exr's lossless compression: rle (fast), zip (a quarter smaller, "
                        "5x slower to write) or none")
        ->check(CLI::IsMember({"rle", "zip", "none"}))->capture_default_str();
    add_threads_option(*sky_app, threads);
    // -o is required for the map only; CLI11 cannot say "required unless a subcommand", so
    // the check runs once the line is parsed, with CLI11's error and exit code (106).
    sky_app->parse_complete_callback([sky_app, out] {
      if (sky_app->get_subcommands().empty() && out->out.empty())
        throw CLI::RequiredError("--out");
    });
    commands.push_back({sky_app, [=] {
      std::optional<LoadedRig> loaded;
      if (!rig->empty()) {
        loaded = load_rig(*rig);
        if (!rig_sky(loaded->rig)) throw RigError(no_sky_message(loaded->rig, *rig));
      }
      const Sky sky = loaded ? opts->sky(*rig_sky(loaded->rig), sky_app)
                             : opts->sky();
      OutputDir dir = out->open();
      const SkyMap map = sky_map(sky, *size);
      const ExrCompression c = *compression == "none" ? ExrCompression::None
                               : *compression == "zip" ? ExrCompression::Zip
                                                       : ExrCompression::Rle;
      // The previews (gnuplot, a process of its own) are drawn while the EXR is written.
      std::future<std::vector<DatasetFile>> previews;
      if (out->plots())
        previews = std::async(std::launch::async, [&] { return report_sky_previews(dir.staging(), map, sky); });
      std::vector<DatasetFile> files = write_sky_map(dir.staging(), map, sky, c);
      if (previews.valid())
        for (DatasetFile& f : previews.get()) files.push_back(std::move(f));
      write_manifest(dir.staging(), {command_line(), loaded ? &*loaded : nullptr, files});
      finish(dir);
    }});
  }
  return commands;
}

}  // namespace polrig::cli
