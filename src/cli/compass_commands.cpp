// Commands that navigate: heading (the W19 compass on recorded attitudes and angles) and
// study heading (its Monte-Carlo on a moving platform).
#include <cmath>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <utility>

#include <fmt/format.h>

#include "cli.h"
#include "polrig/io/csv.h"
#include "polrig/quoted.h"
#include "polrig/io/measured.h"
#include "polrig/compass/heading.h"
#include "polrig/compass/heading_rows.h"
#include "polrig/sky/sun.h"
#include "polrig/sky/sun_rows.h"
#include "polrig/report/heading_reports.h"
#include "polrig/report/locate_report.h"
#include "polrig/report/orientation_report.h"
#include "polrig/io/dofp_dataset.h"
#include "polrig/io/four_camera_calibration.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/rig/rig.h"
#include "polrig/study/heading_trials.h"

namespace polrig::cli {

namespace {

constexpr const char* kCorrectNoiseBiasHelp =
    "remove the eigenvector method's noise bias (DoP² weights, EEᵀ·s = c·Σ(I − v·vᵀ)·s; "
    "docs/physics.md §15); replaces --dop-weighting";

// The option of `polrig study heading` that sets a HeadingStudySettings field.
std::string study_heading_option(std::string_view field) {
  static const std::pair<std::string_view, const char*> options[] = {
      {"trials", "--trials"}, {"samples", "--samples"}, {"roll_sd_deg", "--roll-sd"},
      {"pitch_sd_deg", "--pitch-sd"}, {"sync_max_s", "--sync-max"},
      {"turn_rate_max_dps", "--turn-rate-max"}, {"ins_tilt_sd_deg", "--ins-tilt-sd"},
      {"mount_tilt_sd_deg", "--mount-tilt-sd"}, {"mount_azimuth_sd_deg", "--mount-azimuth-sd"},
      {"p_max_min", "--p-max-min"}, {"p_max_max", "--p-max-max"}};
  for (const auto& [f, option] : options)
    if (f == field) return option;
  return std::string(field);
}

// Reads and checks every row before anything is computed or written.
std::vector<HeadingQuery> read_heading_input(const CsvFile& f, const std::optional<Site>& site) {
  constexpr std::string_view section = "6.13 polrig heading";
  const std::size_t c_utc = f.column("utc", section), c_roll = f.column("roll_deg", section),
                    c_pitch = f.column("pitch_deg", section), c_aop = f.column("aop_deg", section);
  const auto c_prior = f.find_column("heading_prior_deg");
  const auto c_lat = f.find_column("lat_deg"), c_lon = f.find_column("lon_deg");
  if (c_lat.has_value() != c_lon.has_value())
    throw DataError(fmt::format("{}:{}: column '{}' without '{}': give both or neither", f.origin,
                                f.header_line, c_lat ? "lat_deg" : "lon_deg",
                                c_lat ? "lon_deg" : "lat_deg"));
  if (c_lat && site)
    throw DataError(fmt::format("{}:{}: the file has lat_deg and lon_deg columns and --site was "
                                "given too: use one", f.origin, f.header_line));
  if (!c_lat && !site)
    throw DataError(fmt::format("{}:{}: no site: give --site LAT,LON or lat_deg and lon_deg "
                                "columns", f.origin, f.header_line));
  if (f.rows.empty()) throw DataError(fmt::format("{}: no data rows after the header", f.origin));
  const auto ranged = [&](std::size_t r, std::size_t c, std::string_view field, const char* what) {
    const double v = f.number(r, c);
    const InputRange range = heading_query_range(field);
    if (v < range.lo || v > range.hi)
      throw DataError(fmt::format("{}:{}: column '{}': {} is outside [{}, {}] ({})", f.origin,
                                  f.line[r], f.header[c], quoted_value(f.rows[r][c]), range.lo, range.hi,
                                  what ? what : range.what));
    return v;
  };
  std::vector<HeadingQuery> rows;
  for (std::size_t r = 0; r < f.rows.size(); ++r) {
    HeadingQuery h;
    try {
      h.at.utc = parse_utc(f.rows[r][c_utc]);
    } catch (const std::invalid_argument& e) {
      throw DataError(fmt::format("{}:{}: column 'utc': '{}': {}", f.origin, f.line[r],
                                  quoted_value(f.rows[r][c_utc]), e.what()));
    }
    h.tilt.roll_deg = ranged(r, c_roll, "roll_deg", nullptr);
    h.tilt.pitch_deg = ranged(r, c_pitch, "pitch_deg", nullptr);
    h.aop_deg = ranged(r, c_aop, "aop_deg", nullptr);
    if (c_prior && !f.rows[r][*c_prior].empty()) h.prior_deg = ranged(r, *c_prior, "prior_deg", nullptr);
    if (c_lat) {
      h.at.site.lat_deg = ranged(r, *c_lat, "lat_deg", nullptr);
      h.at.site.lon_deg = ranged(r, *c_lon, "lon_deg", nullptr);
    } else {
      h.at.site = *site;
    }
    rows.push_back(h);
  }
  return rows;
}

void run_heading(const std::string& input, const std::string& site_text, const SunSettings& sun_settings,
                 const OutputOptions& out) {
  const std::optional<Site> site =
      site_text.empty() ? std::nullopt : std::optional<Site>(parse_site(site_text));
  const CsvFile f = CsvFile::read(input);
  for (const char* added : {"sun_az_deg", "sun_el_deg", "heading_deg", "heading_alt_deg", "status"})
    if (f.find_column(added))
      throw DataError(fmt::format("{}:{}: column '{}' is one heading writes: rename it", f.origin,
                                  f.header_line, added));
  const std::vector<HeadingQuery> rows = read_heading_input(f, site);
  // Opened first, so that an existing destination fails before any work; an error below (a
  // date the ephemeris refuses is that row's error) removes the staging folder.
  OutputDir dir = out.open(false);
  std::vector<HeadingSample> samples;
  try {
    samples = headings_along(rows, sun_settings, {}, progress());
  } catch (const SunRowError& e) {
    throw DataError(fmt::format("{}:{}: column 'utc': '{}': {}", f.origin, f.line[e.row],
                                f.rows[e.row][f.column("utc")], e.what()));
  }
  std::string text;
  for (std::size_t c = 0; c < f.header.size(); ++c) text += f.header[c] + ",";
  text += "sun_az_deg,sun_el_deg,heading_deg,heading_alt_deg,status\n";
  int solved = 0;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const SunPosition& sun = samples[r].sun;
    const HeadingSolution& s = samples[r].solution;
    // Every number finite, except the heading columns of a row without a heading: `nan`
    // (formats.md §5).
    const auto cell = [&](double v, const char* column, bool undefined_ok = false) {
      if (!std::isfinite(v) && !(std::isnan(v) && undefined_ok))
        throw std::runtime_error(fmt::format("{}:{}: a result is not finite: column '{}' is {}; "
                                             "nothing was written", f.origin, f.line[r], column, v));
      return fmt::format("{},", v);
    };
    for (const std::string& v : f.rows[r]) text += v + ",";
    text += cell(sun.azimuth_deg, "sun_az_deg") + cell(sun.elevation_deg, "sun_el_deg");
    const bool ok = has_heading(s.status);
    solved += ok ? 1 : 0;
    text += cell(s.heading_deg, "heading_deg", !ok) + cell(s.heading_alt_deg, "heading_alt_deg", !ok);
    text += fmt::format("{}\n", heading_status_name(s.status));
  }
  write_text_file(dir.staging() / "heading.csv", text);
  write_manifest(dir.staging(),
                 {command_line(), nullptr,
                  {{"heading.csv", 1, "the input's columns, then the sun's azimuth and elevation, "
                                      "the heading (clockwise from north; the root nearest "
                                      "heading_prior_deg, else the one with the sun in front), "
                                      "the other root, and the status"}},
                  {f.origin}});
  finish(dir);
  std::cout << fmt::format("{} rows, {} with a heading, {} without\n", rows.size(), solved,
                           rows.size() - static_cast<std::size_t>(solved));
}

// `orient DIR`: every polarized frame of a camera dataset oriented by the eigenvector method and
// the two comparators (report/orientation_report.h); the sun's geographic azimuth from the
// dataset's sky rig (rig.yaml), the true heading from its stops.csv.
void run_orient(const std::string& input, const std::string& params, const std::string& conversion,
                bool dop_weighting, bool correct_noise_bias, std::optional<double> heading_prior,
                const OutputOptions& out) {
  OrientationSettings settings;
  settings.conversion = *parse_aop_conversion(conversion);
  settings.dop_weighting = dop_weighting;
  settings.correct_noise_bias = correct_noise_bias;
  const std::vector<FrameOrientation> frames = orient_dofp_folder(input, params, settings, heading_prior, progress());
  OutputDir d = out.open();
  std::vector<std::string> inputs = {input};
  if (!params.empty()) inputs.push_back(params);
  write_manifest(d.staging(), {command_line(), nullptr, report_orientation(d.staging(), frames, out.plots()), inputs});
  finish(d);
  int solved = 0;
  for (const FrameOrientation& f : frames) solved += f.estimates[0].solved ? 1 : 0;
  std::cout << fmt::format("{} frames, {} solved by the eigenvector method\n", frames.size(), solved);
}

// `locate DIR`: W16's fix and heading from a four-camera dataset's fused sky images
// (report/locate_report.h): per stop the eigenvector sun vector, then the Eq. 17 fix over the stops
// (both roots, the one nearest --prior chosen) and ψ = β − α_S per stop.
void run_locate(const std::string& input, const std::string& prior_text, bool dop_weighting,
                const std::string& calibration_path, const OutputOptions& out, bool correct_noise_bias) {
  const Site prior = parse_site(prior_text, "--prior");
  OrientationSettings orientation;
  orientation.dop_weighting = dop_weighting;
  orientation.correct_noise_bias = correct_noise_bias;
  std::optional<FourCameraModel> calibration;
  if (!calibration_path.empty()) calibration = read_four_camera_model(calibration_path);
  const DatasetLocation run = locate_four_camera_folder(input, prior, orientation, {}, progress(), calibration);
  OutputDir d = out.open();
  std::vector<std::string> inputs = {input};
  if (calibration) inputs.push_back(calibration_path);
  write_manifest(d.staging(), {command_line(), nullptr, report_dataset_location(d.staging(), run, out.plots()), inputs});
  finish(d);
  std::cout << (calibration ? fmt::format("fused with {} (each stop's raw frames)\n", calibration_path)
                            : std::string("the dataset's fused layers\n"));
  const PositionFix& fix = run.location.fix;
  const PositionRoot& r = fix.chosen;
  std::cout << fmt::format("{} of {} stops with a sun; fix {}: {:.4f}°N {:.4f}°E ({})", run.location.samples.size(),
                           run.suns.size(), position_termination_name(r.summary.termination), r.lat_deg, r.lon_deg,
                           r.summary.brief_report());
  if (run.truth) std::cout << fmt::format(", {:.3f} km from the rig's site", great_circle_km(r.lat_deg, r.lon_deg,
                                                                                        run.truth->lat_deg,
                                                                                        run.truth->lon_deg));
  // Against the dataset's true headings when it has them (a turning table's headings differ by
  // design, so their spread says nothing); else their mean and spread, which mean something only
  // for a sensor that did not turn.
  double sum = 0, sum2 = 0;
  int n = 0;
  for (std::size_t k = 0; k < run.location.samples.size(); ++k) {
    const double e = std::remainder(run.location.samples[k].heading_deg - run.true_heading_deg[k], 360.0);
    if (std::isfinite(e)) sum += e, sum2 += e * e, ++n;
  }
  if (n == 0)
    std::cout << fmt::format("\nheading (no truth in the dataset): mean {:.4f}°, SD {:.4f}° (a spread only if the "
                             "sensor did not turn)", run.location.heading_mean_deg, run.location.heading_sd_deg);
  if (n > 0) std::cout << fmt::format("\nheading error against the truth ({} stops): mean {:.4f}°, RMS {:.4f}°", n, sum / n, std::sqrt(sum2 / n));
  std::cout << "\n";
}

}  // namespace

std::vector<Command> add_nav_commands(CLI::App& root, CLI::App& study, int& threads) {
  std::vector<Command> commands;
  {
    auto* app = root.add_subcommand(
        "heading", "heading from the sky's E-vector, the attitude and the sun (W19 Eqs. 22-25)");
    auto input = std::make_shared<std::string>();
    auto site = std::make_shared<std::string>();
    auto out = std::make_shared<OutputOptions>();
    auto sun = std::make_shared<SunSettings>();
    app->add_option("INPUT", *input, "CSV with utc, roll_deg, pitch_deg, aop_deg and optionally "
                                     "heading_prior_deg, lat_deg, lon_deg")->required();
    app->add_option("--site", *site, "LAT,LON in degrees (north, east positive), unless the "
                                     "input has lat_deg and lon_deg columns");
    out->add_to(*app);
    add_sun_options(*app, *sun);
    add_threads_option(*app, threads);
    commands.push_back({app, [=] { run_heading(*input, *site, *sun, *out); }});
  }
  {
    auto* app = root.add_subcommand(
        "orient", "sun vector and heading from a DoFP camera dataset's sky frames (H17 Eqs. 6-14)");
    auto input = std::make_shared<std::string>();
    auto params = std::make_shared<std::string>();
    auto conversion = std::make_shared<std::string>("meridional");
    auto dop_weighting = std::make_shared<bool>(false);
    auto heading_prior = std::make_shared<std::optional<double>>();
    auto out = std::make_shared<OutputOptions>();
    app->add_option("DIR", *input, "a folder written by polrig simulate for a camera rig")->required();
    app->add_option("--params", *params, "a calibration's params.exr (polrig calibrate --method dofp); "
                                         "default: the nominal K = 1, b = 0, k = 1, eps = 0");
    app->add_option("--conversion", *conversion, "the pixel AoP to E-vector model: meridional | "
                                                 "analyzer-in-front")
        ->check(CLI::IsMember({"meridional", "analyzer-in-front"}))->capture_default_str();
    app->add_flag("--dop-weighting", *dop_weighting, "weight the eigenvector method's EEᵀ by DoP");
    auto correct_noise_bias = std::make_shared<bool>(false);
    app->add_flag("--correct-noise-bias", *correct_noise_bias, kCorrectNoiseBiasHelp);
    app->add_option("--heading-prior", *heading_prior, "an approximate heading of the camera's X_l at table angle 0 "
                                                       "(deg, clockwise from north; each frame adds its table angle): "
                                                       "chooses between the sun and the antisun near the horizon")
        ->check(finite_range(-360.0, 360.0, "deg"));
    out->add_to(*app);
    add_threads_option(*app, threads);
    commands.push_back({app, [=] {
                          require_file_name(*app, "--params", *params);
                          run_orient(*input, *params, *conversion, *dop_weighting, *correct_noise_bias, *heading_prior,
                                     *out);
                        }});
  }
  {
    auto* app = root.add_subcommand(
        "locate", "position and heading from a four-camera dataset's fused sky images (W16 Eqs. 6-18)");
    auto input = std::make_shared<std::string>();
    auto prior = std::make_shared<std::string>();
    auto dop_weighting = std::make_shared<bool>(false);
    auto out = std::make_shared<OutputOptions>();
    app->add_option("DIR", *input, "a four-camera dataset: written by polrig simulate, or measured frames in "
                                   "its layout (formats.md 6.14a)")->required();
    app->add_option("--prior", *prior, "LAT,LON in degrees (north, east positive): an approximate position; of "
                                       "Eq. 17's two roots the one nearer it is chosen")->required();
    app->add_flag("--dop-weighting", *dop_weighting, "weight the eigenvector method's EEᵀ by DoP");
    auto correct_noise_bias = std::make_shared<bool>(false);
    app->add_flag("--correct-noise-bias", *correct_noise_bias, kCorrectNoiseBiasHelp);
    out->add_to(*app);
    add_threads_option(*app, threads);
    auto calibration = std::make_shared<std::string>();
    app->add_option("--calibration", *calibration,
                    "a four-camera calibration.yaml (calibrate --method four-camera): re-fuse each stop's raw frames "
                    "(a dataset written with --layers all) with it instead of the dataset's fused layers");
    commands.push_back(
        {app, [=] {
           require_file_name(*app, "--calibration", *calibration);
           run_locate(*input, *prior, *dop_weighting, *calibration, *out, *correct_noise_bias);
         }});
  }
  {
    auto* app = study.add_subcommand(
        "heading", "Monte-Carlo of the heading error on a moving platform (W19 §5.2)");
    auto rig = std::make_shared<RigInput>();
    auto out = std::make_shared<OutputOptions>();
    auto s = std::make_shared<HeadingStudySettings>();
    auto site = std::make_shared<std::string>();
    auto utc = std::make_shared<std::string>("2019-07-01T11:01:00Z");
    rig->add_to(*app, true);
    out->add_to(*app);
    app->add_option("--trials", s->trials, "number of trials")->check(CLI::Range(1, 10000000))->capture_default_str();
    app->add_option("--site", *site, "LAT,LON in degrees (default: W19's Dalian site, 38.879167,121.543889)");
    app->add_option("--utc", *utc, "time of the run, ISO 8601 with Z (default: W19's dynamic run)")
        ->capture_default_str();
    add_sun_options(*app, s->sun);
    app->add_option("--roll-sd", s->roll_sd_deg, "SD of the roll drawn, degrees")
        ->check(finite_range(0, 30, "°"))->capture_default_str();
    app->add_option("--pitch-sd", s->pitch_sd_deg, "SD of the pitch drawn, degrees")
        ->check(finite_range(0, 30, "°"))->capture_default_str();
    app->add_option("--sync-max", s->sync_max_s, "largest sensor-INS time offset |Δt| drawn (uniform), s")
        ->check(finite_range(0, 10, "s"))->capture_default_str();
    app->add_option("--turn-rate-max", s->turn_rate_max_dps, "largest turn rate |ω| drawn (uniform), °/s")
        ->check(finite_range(0, 360, "°/s"))->capture_default_str();
    app->add_option("--ins-tilt-sd", s->ins_tilt_sd_deg, "SD of the INS's roll and pitch errors, degrees")
        ->check(finite_range(0, 10, "°"))->capture_default_str();
    app->add_option("--mount-tilt-sd", s->mount_tilt_sd_deg, "SD of the sensor axis' tilt about X_b and Y_b, degrees")
        ->check(finite_range(0, 10, "°"))->capture_default_str();
    app->add_option("--mount-azimuth-sd", s->mount_azimuth_sd_deg, "SD of the sensor's azimuthal mount offset, degrees")
        ->check(finite_range(0, 10, "°"))->capture_default_str();
    app->add_option("--p-max-min", s->p_max_min, "smallest P_max drawn (uniform)")
        ->check(finite_range(0.05, 1))->capture_default_str();
    app->add_option("--p-max-max", s->p_max_max, "largest P_max drawn (uniform)")
        ->check(finite_range(0.05, 1))->capture_default_str();
    app->add_option("--samples", s->samples, "voltage samples averaged per heading")
        ->check(CLI::Range(1, 100000))->capture_default_str();
    add_threads_option(*app, threads);
    commands.push_back({app, [=] {
      HeadingStudySettings settings = *s;
      try {
        check_heading_study_settings(settings, [](std::string_view field) {
          return study_heading_option(field);
        });
      } catch (const std::invalid_argument& e) {
        throw DataError(e.what());
      }
      const LoadedRig r = rig->load();
      require_instrument(r.rig, Instrument::kPairVoltages, "study heading", r.origin);
      // Site, time and the sun's settings: a sky rig's `sky:` block (site, first stop, UT1 − UTC,
      // refraction), else W19's dynamic run; an option given on the command line overrides either.
      const SunSettings given = settings.sun;
      const bool sky_rig = use_rig_sky(r.rig, settings);
      if (app->count("--ut1-minus-utc") > 0) settings.sun.ut1_minus_utc_s = given.ut1_minus_utc_s;
      if (app->count("--refraction") > 0) settings.sun.refraction = given.refraction;
      if (!site->empty()) settings.site = parse_site(*site);
      if (app->count("--utc") > 0 || !sky_rig) settings.utc = parse_utc_option(*utc);
      OutputDir dir = out->open();
      const std::vector<HeadingTrial> result = heading_trials(r.rig, settings, progress());
      write_manifest(dir.staging(), {command_line(), &r,
                                     report_heading_trials(dir.staging(), result, settings, out->plots(), progress())});
      finish(dir);
      double sum_sq = 0;
      int solved = 0;
      for (const HeadingTrial& t : result)
        if (!std::isnan(t.error_deg)) {
          sum_sq += t.error_deg * t.error_deg;
          ++solved;
        }
      std::cout << fmt::format("{} trials, {} with a heading; RMS heading error {:.4f}°\n",
                               result.size(), solved, solved ? std::sqrt(sum_sq / solved) : NAN);
    }});
  }
  return commands;
}

}  // namespace polrig::cli
