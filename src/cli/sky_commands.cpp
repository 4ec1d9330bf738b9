// `polrig sky` (an all-sky map of the Rayleigh sky) and `polrig sky table` (the sun and the sky's
// polarization along given directions at given times and places).
#include <cmath>
#include <future>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "cli.h"
#include "polrig/io/csv.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/io/sky_files.h"
#include "polrig/report/sky_reports.h"
#include "polrig/sky/sun_rows.h"
#include "polrig/sky/sky.h"
#include "polrig/io/plot.h"
#include "polrig/sky/berry_fit.h"
#include "polrig/sky/neutral_points.h"
#include "polrig/sky/sky_map.h"
#include "polrig/sky/vector_rt_sky.h"

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

// --sun-el-deg's elevations, each within [the model's lowest sun, 90°].
std::vector<double> checked_elevations(const std::string& text, const SkyModel& model) {
  const std::vector<double> h = parse_elevations(text);
  const double lo = min_sun_elevation_deg(model);
  for (double e : h)
    if (!(e >= lo && e <= 90))
      throw DataError(fmt::format("--sun-el-deg {}: the sun's elevation {}° is outside [{}°, 90°]{}", text, e, lo,
                                  lo > -90 ? " (the vector-rt sky's low-sun limit)" : ""));
  return h;
}

// The sky in a plot's title: its model and, where it has one, its atmosphere.
std::string sky_title(const Rig& rig, const SkyModel& model) {
  if (model.kind == SkyKind::SingleScattering) return "single scattering";
  const VectorRtSettings rt = rig.source.sky.resolved_rt();
  const std::string atmosphere = atmosphere_text(rt);
  if (model.kind == SkyKind::VectorRt) return "vector-RT sky, " + atmosphere;
  const auto distance = [](const std::optional<double>& d) { return d ? fmt::format("{:g} deg", *d) : std::string("fit"); };
  return fmt::format("Berry's sky, Babinet {}, Brewster {}{}", distance(model.berry.babinet_deg),
                     distance(model.berry.brewster_deg), model.berry.fit ? " to the vector-RT sky of " + atmosphere : "");
}

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

  // ---- sky neutral-points
  {
    auto* app = sky_app->add_subcommand(
        "neutral-points", "the Babinet, Brewster and Arago points of the rig's sky along its solar meridian");
    auto out = std::make_shared<OutputOptions>();
    auto rig = std::make_shared<RigInput>();
    auto elevations = std::make_shared<std::string>();
    app->add_option("--rig", rig->path, "a rig file with source.model sky (its sky block: sky.model, sky.rt.*)");
    add_set_option(*app, rig->sets);
    app->add_option("--sun-el-deg", *elevations, "the sun's elevation X, or A:B:N (N elevations from A to B), degrees")
        ->required();
    out->add_to(*app, true);
    add_threads_option(*app, threads);
    commands.push_back({app, [=] {
      const LoadedRig loaded = rig->load();
      const std::optional<Sky> sky = rig_sky(loaded.rig);
      if (!sky) throw RigError(no_sky_message(loaded.rig, rig->path));
      const std::vector<double> h = checked_elevations(*elevations, sky->model);
      OutputDir dir = out->open();
      std::vector<NeutralPoints> points(h.size());
      const Progress p = progress();
      p.begin("neutral points", static_cast<long long>(h.size()));
      tbb::parallel_for(std::size_t{0}, h.size(), [&](std::size_t k) {
        points[k] = sky_neutral_points(sky->model, h[k]);
        p.advance();
      });
      p.finish();
      std::string csv = "sun_el_deg,babinet_deg,brewster_deg,arago_deg\n";
      const auto cell = [](const std::optional<double>& v) { return v ? fmt::format("{}", *v) : std::string("nan"); };
      for (const NeutralPoints& n : points)
        csv += fmt::format("{},{},{},{}\n", n.sun_el_deg, cell(n.babinet_deg), cell(n.brewster_deg), cell(n.arago_deg));
      write_text_file(dir.staging() / "neutral_points.csv", csv);
      std::vector<DatasetFile> files{{"neutral_points.csv", 1,
          "sun_el_deg, then the angular distances along the solar meridian of Babinet (above the sun), Brewster "
          "(below it) and Arago (above the antisun), degrees; nan where absent or below the horizon"}};
      if (out->plots() && sky->model.kind != SkyKind::SingleScattering) {  // single scattering has no point to draw
        const std::string what = sky_title(loaded.rig, sky->model);
        Plot plot{"neutral_points.png", "Neutral points on the solar meridian (" + what + "; single scattering: none)",
                  "sun elevation (deg)", "distance along the meridian (deg)", "",
                  {{"neutral_points.csv", "$sun_el_deg:$babinet_deg", "Babinet (above the sun)", "linespoints lw 2 pt 7 ps 0.6"},
                   {"neutral_points.csv", "$sun_el_deg:$brewster_deg", "Brewster (below the sun)", "linespoints lw 2 pt 5 ps 0.6"},
                   {"neutral_points.csv", "$sun_el_deg:$arago_deg", "Arago (above the antisun)", "linespoints lw 2 pt 9 ps 0.6"}},
                  "set key top right\nset grid\nset yrange [0:*]"};
        render_plots(dir.staging(), "plots.gp", {plot}, progress());
        files.push_back({"neutral_points.png", 1, "the three distances against the sun's elevation"});
      }
      write_manifest(dir.staging(), {command_line(), &loaded, files});
      finish(dir);
    }});
  }

  // ---- sky berry-fit
  {
    auto* app = sky_app->add_subcommand(
        "berry-fit", "Berry's two distances fitted to the vector-RT sky of the rig's atmosphere, with the fit's AoP error");
    auto out = std::make_shared<OutputOptions>();
    auto rig = std::make_shared<RigInput>();
    auto elevations = std::make_shared<std::string>();
    app->add_option("--rig", rig->path, "a rig file with source.model sky (its atmosphere: sky.rt.*)");
    add_set_option(*app, rig->sets);
    app->add_option("--sun-el-deg", *elevations, "the sun's elevation X, or A:B:N (N elevations from A to B), degrees")
        ->required();
    out->add_to(*app, true);
    add_threads_option(*app, threads);
    commands.push_back({app, [=] {
      const LoadedRig loaded = rig->load();
      if (!rig_sky(loaded.rig)) throw RigError(no_sky_message(loaded.rig, rig->path));
      const VectorRtSettings rt = loaded.rig.source.sky.resolved_rt();
      SkyModel exact;
      exact.kind = SkyKind::VectorRt;
      const std::vector<double> h = checked_elevations(*elevations, exact);
      OutputDir dir = out->open();
      const std::shared_ptr<const VectorRtSky> sky = vector_rt_sky(rt);
      std::vector<BerryFitResult> fits(h.size());
      const Progress p = progress();
      p.begin("Berry fits", static_cast<long long>(h.size()));
      tbb::parallel_for(std::size_t{0}, h.size(), [&](std::size_t k) {
        fits[k] = fit_berry(sky->for_sun(h[k]), h[k]);
        p.advance();
      });
      p.finish();
      std::string csv = "sun_el_deg,babinet_deg,brewster_deg,aop_rms_deg,aop_p95_deg,single_aop_rms_deg,views,iterations,status\n";
      for (const BerryFitResult& f : fits)
        csv += fmt::format("{},{},{},{},{},{},{},{},{}\n", f.sun_el_deg, f.distances.babinet_deg, f.distances.brewster_deg,
                           f.summary.aop_rms_deg, f.summary.aop_p95_deg, f.summary.single_aop_rms_deg, f.summary.views,
                           f.summary.iterations, f.summary.status);
      write_text_file(dir.staging() / "berry_fit.csv", csv);
      std::vector<DatasetFile> files{{"berry_fit.csv", 1,
          "sun_el_deg; Berry's fitted babinet_deg and brewster_deg; over the views with exact DoP >= 0.02 (uniform in "
          "solid angle above the horizon) Berry's AoP error against the vector-RT sky, rms and 95th percentile, and "
          "single scattering's rms; views; iterations and Eigen's Levenberg-Marquardt status"}};
      if (out->plots()) {
        const std::string what = atmosphere_text(rt);
        Plot distances{"berry_fit.png", "Berry's distances fitted to the vector-RT sky (" + what + ")",
                       "sun elevation (deg)", "distance along the solar meridian (deg)", "",
                       {{"berry_fit.csv", "$sun_el_deg:$babinet_deg", "Babinet (above the sun)", "linespoints lw 2 pt 7 ps 0.6"},
                        {"berry_fit.csv", "$sun_el_deg:$brewster_deg", "Brewster (below the sun)", "linespoints lw 2 pt 5 ps 0.6"}},
                       "set key top right\nset grid\nset yrange [0:*]"};
        Plot error{"berry_fit_error.png", "AoP against the vector-RT sky (" + what + "; views with DoP >= 0.02)",
                   "sun elevation (deg)", "AoP error (deg)", "",
                   {{"berry_fit.csv", "$sun_el_deg:$aop_rms_deg", "Berry fitted, rms", "linespoints lw 2 pt 7 ps 0.6"},
                    {"berry_fit.csv", "$sun_el_deg:$aop_p95_deg", "Berry fitted, 95th percentile", "linespoints lw 1 pt 6 ps 0.6"},
                    {"berry_fit.csv", "$sun_el_deg:$single_aop_rms_deg", "single scattering, rms", "linespoints lw 2 pt 5 ps 0.6"}},
                   "set key top right\nset grid\nset yrange [0:*]"};
        render_plots(dir.staging(), "plots.gp", {distances, error}, progress());
        files.push_back({"berry_fit.png", 1, "the two distances against the sun's elevation"});
        files.push_back({"berry_fit_error.png", 1, "Berry's and single scattering's AoP error against the sun's elevation"});
      }
      write_manifest(dir.staging(), {command_line(), &loaded, files});
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
                                     "stop, sky.model, sky.rt.*, P_max, radiance, refraction) is the default of every option");
    auto sets = std::make_shared<std::vector<std::string>>();
    add_set_option(*sky_app, *sets);
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
      if (!rig->empty() || !sets->empty()) {
        loaded = RigInput{*rig, *sets}.load();
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
        previews = std::async(std::launch::async, [&] {
          return report_sky_previews(dir.staging(), map, sky, loaded ? loaded->rig.source.sky.resolved_rt() : VectorRtSettings{});
        });
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
