// `polrig sky` (an all-sky map of the Rayleigh sky) and `polrig sky table` (the sun and the sky's
// polarization along given directions at given times and places).
#include <charconv>
#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "cli.h"
#include "polrig/io/csv.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/io/sky_files.h"
#include "polrig/sky/sky.h"
#include "polrig/sky/sky_map.h"

namespace polrig::cli {
namespace {

double parse_number(const std::string& text, const std::string& option, const std::string& whole) {
  double v = 0;
  const char* b = text.data();
  const char* e = b + text.size();
  auto [end, err] = std::from_chars(b, e, v);
  if (text.empty() || err != std::errc() || end != e || !std::isfinite(v))
    throw std::runtime_error(fmt::format("{} '{}': '{}' is not a finite number (expected LAT,LON in degrees)",
                                         option, whole, text));
  return v;
}

// "LAT,LON" in degrees, north and east positive.
Site parse_site(const std::string& text) {
  const auto comma = text.find(',');
  if (comma == std::string::npos || text.find(',', comma + 1) != std::string::npos)
    throw std::runtime_error(fmt::format("--site '{}': expected LAT,LON in degrees, e.g. 38.8792,121.5439", text));
  Site site;
  site.lat_deg = parse_number(text.substr(0, comma), "--site", text);
  site.lon_deg = parse_number(text.substr(comma + 1), "--site", text);
  if (std::abs(site.lat_deg) > 90)
    throw std::runtime_error(fmt::format("--site '{}': latitude {} is outside [-90, 90]", text, site.lat_deg));
  if (site.lon_deg < -180 || site.lon_deg > 360)
    throw std::runtime_error(fmt::format("--site '{}': longitude {} is outside [-180, 360]", text, site.lon_deg));
  return site;
}

SkyRadiance parse_radiance(const std::string& name) {
  if (name == "uniform") return SkyRadiance::Uniform;
  if (name == "rayleigh") return SkyRadiance::Rayleigh;
  return SkyRadiance::CieClear;  // CLI::IsMember has refused anything else
}

struct SkyOptions {
  std::string site, utc, radiance = "uniform";
  double p_max = 0.7, ut1_minus_utc = 0;
  bool refraction = false;
  void add_to(CLI::App& app, bool map) {
    app.add_option("--p-max", p_max, "maximum degree of polarization P_max, (0, 1]")
        ->check(finite_range(1e-6, 1.0))->capture_default_str();
    app.add_flag("--refraction", refraction, "refract the sun (Saemundsson, 1010 hPa, 10 °C); off: geometric");
    app.add_option("--ut1-minus-utc", ut1_minus_utc, "UT1 - UTC in seconds (IERS Bulletin A)")
        ->check(finite_range(-1, 1, "s"))->capture_default_str();
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
    const auto given = [&](const char* option) { return app == nullptr || app->count(option) > 0; };
    if (!site.empty()) s.site = parse_site(site);
    if (!utc.empty()) {
      try {
        s.first_stop = parse_utc(utc);
      } catch (const std::invalid_argument& e) {
        throw std::runtime_error(fmt::format("--utc: {}", e.what()));
      }
    }
    if (given("--p-max")) s.model.P_max.constant = p_max;
    if (given("--radiance")) s.model.radiance = parse_radiance(radiance);
    if (given("--refraction")) s.sun.refraction = refraction;
    if (given("--ut1-minus-utc")) s.sun.ut1_minus_utc_s = ut1_minus_utc;
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
    app->add_option("INPUT", *input, "CSV with columns utc, lat_deg, lon_deg, view_az_deg, view_el_deg")
        ->required();
    out->add_to(*app);
    opts->add_to(*app, false);
    commands.push_back({app, [=] {
      const Sky sky = opts->sky();
      const CsvFile in = CsvFile::read(*input);
      const std::string csv = sky_table_csv(in, sky.model, sky.sun);  // all rows checked first
      OutputDir dir = out->open(false);
      write_text_file(dir.staging() / "sky.csv", csv);
      Manifest m{command_line(), nullptr,
                 {{"sky.csv", 1, "the input rows with sun_az_deg, sun_el_deg, dop, aop_deg"}}};
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
    // -o is checked when the map is made: `sky table` has its own.
    sky_app->add_option("-o,--out", out->out, "output folder (written whole or not at all)");
    sky_app->add_flag("--force", out->force, "replace the output folder if it exists");
    sky_app->add_flag("--no-plots", out->no_plots, "write sky.exr and sun.yaml only, no PNG previews");
    opts->add_to(*sky_app, true);
    sky_app->add_option("--size", *size, "image width = height in pixels")
        ->check(CLI::Range(2, 8192))->capture_default_str();
    add_threads_option(*sky_app, threads);
    commands.push_back({sky_app, [=] {
      if (out->out.empty()) throw std::runtime_error("sky: -o/--out is required");
      std::optional<LoadedRig> loaded;
      if (!rig->empty()) {
        loaded = load_rig(*rig);
        if (!loaded->rig.light->has(Source::kTimeDependent))
          throw RigError(fmt::format("{}: source.model {} has no sky (expected source.model sky)",
                                     *rig, loaded->rig.source.model));
      }
      const Sky sky = loaded ? opts->sky(loaded->rig.source.sky.resolved_sky(), sky_app)
                             : opts->sky();
      OutputDir dir = out->open();
      const SkyMap map = sky_map(sky, *size);
      write_manifest(dir.staging(), {command_line(), loaded ? &*loaded : nullptr,
                                     write_sky_map(dir.staging(), map, sky, out->plots())});
      finish(dir);
    }});
  }
  return commands;
}

}  // namespace polrig::cli
