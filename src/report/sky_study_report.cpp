#include "polrig/report/sky_study_report.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <tuple>

#include <fmt/format.h>

#include "polrig/io/csv.h"
#include "polrig/io/plot.h"
#include "csv_cells.h"

namespace polrig {

namespace {

std::string sky_cells(const SkyCase& c, std::size_t row) {
  return fmt::format("{},{},{}", c.name(), checked_cell(c.tau, "tau", row, true), checked_cell(c.albedo, "albedo", row, true));
}

std::string bias_csv(const SkyStudy& study) {
  std::string out =
      "sky,tau,albedo,sun_el_deg,tilt_deg,heading_deg,method,status,heading_error_deg,sun_el_error_deg,"
      "position_line_km,trials,solved,antisun,heading_mean_deg,heading_sd_deg,sun_el_mean_deg,sun_el_sd_deg,mean_dop\n";
  for (std::size_t i = 0; i < study.bias.size(); ++i) {
    const SkyBiasRow& r = study.bias[i];
    out += fmt::format("{},{},{},{},{},{}", sky_cells(r.sky, i), checked_cell(r.sun_el_deg, "sun_el_deg", i),
                       checked_cell(r.tilt_deg, "tilt_deg", i), checked_cell(r.heading_deg, "heading_deg", i),
                       sky_method_name(r.method), r.status);
    for (auto [v, name] : {std::pair{r.heading_error_deg, "heading_error_deg"}, {r.sun_el_error_deg, "sun_el_error_deg"},
                           {r.position_line_km, "position_line_km"}})
      (out += ',') += checked_cell(v, name, i, true);
    out += fmt::format(",{},{},{}", r.trials, r.solved, r.antisun);
    for (auto [v, name] : {std::pair{r.heading_mean_deg, "heading_mean_deg"}, {r.heading_sd_deg, "heading_sd_deg"},
                           {r.sun_el_mean_deg, "sun_el_mean_deg"}, {r.sun_el_sd_deg, "sun_el_sd_deg"},
                           {r.mean_dop, "mean_dop"}})
      (out += ',') += checked_cell(v, name, i, true);
    out += '\n';
  }
  return out;
}

// Accumulates one group's rows (the headings at one sun, or every sun and heading).
struct Group {
  int rows = 0, solved = 0, antisun = 0;
  double max_heading = NAN, sum_heading2 = 0, max_el = NAN, sum_el = 0, sum_el2 = 0, max_line = NAN;
  int n_el = 0;
  double sum_heading_sd2 = 0, sum_el_sd2 = 0, sum_dop = 0;
  int n_heading_sd = 0, n_el_sd = 0, n_dop = 0;
  void add(const SkyBiasRow& r) {
    ++rows;
    antisun += r.status == "antisun";
    const auto fmax = [](double a, double b) { return std::isnan(a) ? b : std::max(a, b); };
    if (std::isfinite(r.heading_error_deg)) {
      ++solved;
      max_heading = fmax(max_heading, std::abs(r.heading_error_deg));
      sum_heading2 += r.heading_error_deg * r.heading_error_deg;
    }
    if (std::isfinite(r.sun_el_error_deg)) {
      ++n_el;
      max_el = fmax(max_el, std::abs(r.sun_el_error_deg));
      max_line = fmax(max_line, std::abs(r.position_line_km));
      sum_el += r.sun_el_error_deg;
      sum_el2 += r.sun_el_error_deg * r.sun_el_error_deg;
    }
    if (std::isfinite(r.heading_sd_deg)) sum_heading_sd2 += r.heading_sd_deg * r.heading_sd_deg, ++n_heading_sd;
    if (std::isfinite(r.sun_el_sd_deg)) sum_el_sd2 += r.sun_el_sd_deg * r.sun_el_sd_deg, ++n_el_sd;
    if (std::isfinite(r.mean_dop)) sum_dop += r.mean_dop, ++n_dop;
  }
  static double ratio(double a, int n) { return n > 0 ? a / n : NAN; }
  static double root(double a, int n) { return n > 0 ? std::sqrt(a / n) : NAN; }
  // rows,solved,rms_heading,max_heading,mean_el,rms_el,max_el,max_line,heading_sd,sun_el_sd,mean_dop
  std::string cells(std::size_t row) const {
    std::string out = fmt::format("{},{},{}", rows, solved, antisun);
    for (auto [v, name] : {std::pair{root(sum_heading2, solved), "rms_heading_error_deg"},
                           {max_heading, "max_abs_heading_error_deg"}, {ratio(sum_el, n_el), "mean_sun_el_error_deg"},
                           {root(sum_el2, n_el), "rms_sun_el_error_deg"}, {max_el, "max_abs_sun_el_error_deg"},
                           {max_line, "max_abs_position_line_km"}, {root(sum_heading_sd2, n_heading_sd), "heading_sd_deg"},
                           {root(sum_el_sd2, n_el_sd), "sun_el_sd_deg"}, {ratio(sum_dop, n_dop), "mean_dop"}})
      (out += ',') += checked_cell(v, name, row, true);
    return out;
  }
};
constexpr const char* kGroupHeader =
    "rows,solved,antisun,rms_heading_error_deg,max_abs_heading_error_deg,mean_sun_el_error_deg,rms_sun_el_error_deg,"
    "max_abs_sun_el_error_deg,max_abs_position_line_km,heading_sd_deg,sun_el_sd_deg,mean_dop";

// The key of a row's group, in the order the groups are written: sky, method, tilt (, sun).
struct GroupKey {
  std::size_t sky;
  int method;
  double tilt, sun;
  auto tie() const { return std::tie(sky, method, tilt, sun); }
  bool operator<(const GroupKey& o) const { return tie() < o.tie(); }
};

std::string grouped_csv(const SkyStudy& study, bool by_sun) {
  // The sky's index in the study's order (single scattering, then τ-major).
  std::vector<SkyCase> skies;
  std::map<GroupKey, Group> groups;
  std::map<GroupKey, const SkyBiasRow*> first;
  for (const SkyBiasRow& r : study.bias) {
    std::size_t k = 0;
    while (k < skies.size() && !(skies[k].kind == r.sky.kind && (skies[k].tau == r.sky.tau || std::isnan(r.sky.tau)) &&
                                 (skies[k].albedo == r.sky.albedo || std::isnan(r.sky.albedo))))
      ++k;
    if (k == skies.size()) skies.push_back(r.sky);
    const GroupKey key{k, static_cast<int>(r.method), r.tilt_deg, by_sun ? r.sun_el_deg : 0.0};
    groups[key].add(r);
    first.emplace(key, &r);
  }
  std::string out = fmt::format("sky,tau,albedo,method,tilt_deg,{}{}\n", by_sun ? "sun_el_deg," : "", kGroupHeader);
  std::size_t row = 0;
  for (const auto& [key, g] : groups) {
    const SkyBiasRow& r = *first.at(key);
    out += fmt::format("{},{},{},", sky_cells(r.sky, row), sky_method_name(r.method), checked_cell(r.tilt_deg, "tilt_deg", row));
    if (by_sun) out += checked_cell(r.sun_el_deg, "sun_el_deg", row) + ",";
    out += g.cells(row++) + "\n";
  }
  return out;
}

std::string dop_csv(const SkyStudy& study) {
  std::string out = "sky,tau,albedo,sun_el_deg,zenith_dop,max_dop_sky,max_dop_compass,mean_dop_compass\n";
  for (std::size_t i = 0; i < study.dop.size(); ++i) {
    const SkyDopRow& r = study.dop[i];
    out += fmt::format("{},{}", sky_cells(r.sky, i), checked_cell(r.sun_el_deg, "sun_el_deg", i));
    for (auto [v, name] : {std::pair{r.zenith_dop, "zenith_dop"}, {r.max_dop_sky, "max_dop_sky"},
                           {r.max_dop_compass, "max_dop_compass"}, {r.mean_dop_compass, "mean_dop_compass"}})
      (out += ',') += checked_cell(v, name, i, true);
    out += '\n';
  }
  return out;
}

std::string evector_csv(const SkyStudy& study) {
  std::string out = "sky,tau,albedo,sun_el_deg,dop_lo,dop_hi,cells,mean_abs_deg,sd_abs_deg,rms_deg,max_abs_deg\n";
  for (std::size_t i = 0; i < study.evector_by_dop.size(); ++i) {
    const EvectorByDopRow& r = study.evector_by_dop[i];
    out += fmt::format("{},{},{},{},{}", sky_cells(r.sky, i), checked_cell(r.sun_el_deg, "sun_el_deg", i),
                       checked_cell(r.dop_lo, "dop_lo", i), checked_cell(r.dop_hi, "dop_hi", i), r.cells);
    for (auto [v, name] : {std::pair{r.mean_abs_deg, "mean_abs_deg"}, {r.sd_abs_deg, "sd_abs_deg"},
                           {r.rms_deg, "rms_deg"}, {r.max_abs_deg, "max_abs_deg"}})
      (out += ',') += checked_cell(v, name, i, true);
    out += '\n';
  }
  return out;
}

const char* kColors[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf"};

// One series per τ (at the first albedo), then the single-scattering sky, on `file`'s `column`
// where `filter` holds.
std::vector<PlotSeries> per_tau(const SkyStudySettings& s, const std::string& file, const std::string& x,
                                const std::string& column, const std::string& filter, const std::string& dash = "") {
  std::vector<PlotSeries> out;
  for (std::size_t i = 0; i < s.tau.size(); ++i)
    out.push_back({file,
                   fmt::format("{}:((@sky eq 'vector-rt' && $tau == {} && $albedo == {}{}) ? ${} : NaN)", x, s.tau[i],
                               s.albedo[0], filter, column),
                   fmt::format("vector-RT τ = {}, A = {}", s.tau[i], s.albedo[0]),
                   fmt::format("linespoints lw 2 pt 7 ps 0.6 lc rgb '{}'{}", kColors[i % 8], dash)});
  return out;
}

std::vector<Plot> plots_of(const SkyStudy& study) {
  const SkyStudySettings& s = study.settings;
  const double tilt_max = *std::max_element(s.tilt_deg.begin(), s.tilt_deg.end());
  const double tilt_min = *std::min_element(s.tilt_deg.begin(), s.tilt_deg.end());
  const std::string published = " && @method eq 'published'";
  const std::string device = study.compass.device;
  std::vector<Plot> plots;

  Plot heading{"heading_bias.png",
               fmt::format("{}: largest heading bias over {} headings (published method)", device,
                           s.heading_deg.size()),
               "sun elevation (°)", "largest |heading error| (°)"};
  heading.series = per_tau(s, "by_sun.csv", "$sun_el_deg", "max_abs_heading_error_deg",
                           fmt::format("{} && $tilt_deg == {}", published, tilt_min));
  if (tilt_max != tilt_min) {
    std::vector<PlotSeries> tilted = per_tau(s, "by_sun.csv", "$sun_el_deg", "max_abs_heading_error_deg",
                                             fmt::format("{} && $tilt_deg == {}", published, tilt_max), " dt 2");
    for (std::size_t i = 0; i < tilted.size(); ++i) tilted[i].title += fmt::format(", tilt {}°", tilt_max);
    heading.series.insert(heading.series.end(), tilted.begin(), tilted.end());
  }
  for (PlotSeries& p : heading.series)
    if (p.title.find("tilt") == std::string::npos) p.title += fmt::format(", tilt {}°", tilt_min);
  // Logarithmic: a tilted view near the sun errs by tens of degrees, a level symmetric compass by 0
  // (its curve then lies below the axis).
  heading.extra = "set key below horizontal spacing 1.2\nset grid\nset logscale y\nset format y '%g'\nset yrange [1e-3:*]";
  plots.push_back(heading);

  if (study.compass.kind != SkyCompassKind::ZenithEVector) {
    Plot el{"sun_el_bias.png",
            fmt::format("{}: sun elevation bias, level, mean over the headings (published method)", device),
            "sun elevation (°)", "elevation error (°)", "position line shift (km, 111.2 km/°)"};
    el.series = per_tau(s, "by_sun.csv", "$sun_el_deg", "mean_sun_el_error_deg",
                        fmt::format("{} && $tilt_deg == {}", published, tilt_min));
    el.extra = "set key below horizontal spacing 1.2\nset grid\nset link y2 via y*111.195 inverse y/111.195\nset y2tics";
    plots.push_back(el);

    Plot methods{"methods.png",
                 fmt::format("{}: elevation bias by method (τ = {}, A = {}, level)", device,
                             s.tau.back(), s.albedo[0]),
                 "sun elevation (°)", "mean elevation error (°)"};
    std::size_t i = 0;
    for (SkyMethod m : sky_methods(study.compass.kind))
      methods.series.push_back(
          {"by_sun.csv",
           fmt::format("$sun_el_deg:((@sky eq 'vector-rt' && $tau == {} && $albedo == {} && @method eq '{}' && "
                       "$tilt_deg == {}) ? $mean_sun_el_error_deg : NaN)",
                       s.tau.back(), s.albedo[0], sky_method_name(m), tilt_min),
           std::string(sky_method_name(m)), fmt::format("linespoints lw 2 pt 7 ps 0.6 lc rgb '{}'", kColors[i++ % 8])});
    methods.extra = "set key below horizontal\nset grid";
    plots.push_back(methods);
  }

  const double mid_sun = s.sun_el_deg[s.sun_el_deg.size() / 2];
  Plot ev{"evector_by_dop.png",
          fmt::format("Single-scattering E-vector error by vector-RT DoP, upper sky (sun at {}°)", mid_sun),
          "vector-RT DoP", "mean |E-vector error| (°)"};
  ev.series = per_tau(s, "evector_by_dop.csv", "(($dop_lo + $dop_hi)/2)", "mean_abs_deg",
                      fmt::format(" && $sun_el_deg == {}", mid_sun));
  ev.extra = "set key below horizontal spacing 1.2\nset grid\nset logscale y\nset format y '%g'";
  plots.push_back(ev);

  Plot dop{"dop.png", fmt::format("Zenith DoP against the sun's elevation (single scattering: P_max = {})",
                                  s.P_max.at(mid_sun)),
           "sun elevation (°)", "zenith DoP"};
  for (std::size_t t = 0; t < s.tau.size(); ++t)
    for (std::size_t a = 0; a < s.albedo.size(); ++a)
      dop.series.push_back({"sky_dop.csv",
                            fmt::format("$sun_el_deg:((@sky eq 'vector-rt' && $tau == {} && $albedo == {}) ? "
                                        "$zenith_dop : NaN)",
                                        s.tau[t], s.albedo[a]),
                            fmt::format("τ = {}, A = {}", s.tau[t], s.albedo[a]),
                            fmt::format("lines lw 2 lc rgb '{}' dt {}", kColors[t % 8], a + 1)});
  dop.series.push_back({"sky_dop.csv", "$sun_el_deg:((@sky eq 'single-scattering') ? $zenith_dop : NaN)",
                        "single scattering", "lines lw 2 lc rgb 'black'"});
  dop.extra = "set key below horizontal spacing 1.2\nset grid";
  plots.push_back(dop);
  return plots;
}

}  // namespace

std::vector<DatasetFile> report_sky_study(const std::filesystem::path& dir, const SkyStudy& study, bool plots) {
  // Every file formatted (and checked finite) before any is written.
  const std::string bias = bias_csv(study), by_sun = grouped_csv(study, true), summary = grouped_csv(study, false);
  const std::string dop = dop_csv(study), evector = evector_csv(study);
  write_text_file(dir / "bias.csv", bias);
  write_text_file(dir / "by_sun.csv", by_sun);
  write_text_file(dir / "summary.csv", summary);
  write_text_file(dir / "sky_dop.csv", dop);
  write_text_file(dir / "evector_by_dop.csv", evector);
  std::vector<DatasetFile> files{
      {"bias.csv", 1, "per sky, sun elevation, tilt, heading and method: the noise-free reading's status, heading "
                      "error, sun-elevation error and position-line shift, and the noisy trials' mean and SD"},
      {"by_sun.csv", 1, "per sky, method, tilt and sun elevation, over the headings: RMS and largest heading error, "
                        "mean, RMS and largest elevation error, largest position-line shift, the noise's SD"},
      {"summary.csv", 1, "per sky, method and tilt, over every sun elevation and heading: as by_sun.csv"},
      {"sky_dop.csv", 1, "per sky and sun elevation: the DoP at the zenith, its largest over the sky and over the "
                         "level compass's views, and its mean there"},
      {"evector_by_dop.csv", 1, "per vector-RT sky, sun elevation and DoP bin: the single-scattering E-vector's "
                                "error against the vector-RT sky over the upper hemisphere's cells in the bin"}};
  if (!plots) return files;
  const std::vector<Plot> p = plots_of(study);
  render_plots(dir, "plots.gp", p);
  for (const Plot& plot : p) files.push_back({plot.png, 1, plot.title});
  return files;
}

}  // namespace polrig
