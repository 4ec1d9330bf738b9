#include "polrig/report/navigation_report.h"

#include <cmath>
#include <tuple>

#include <fmt/format.h>

#include "polrig/io/csv.h"
#include "polrig/io/plot.h"
#include "polrig/sky/sun.h"
#include "polrig/units.h"

namespace polrig {

namespace {

// An undefined value (a PNS epoch without a fix, a skipped update) as nan (docs/formats.md §5).
std::string cell(double v) { return std::isfinite(v) ? fmt::format("{}", v) : std::string("nan"); }

std::string solution_csv(const NavigationDataset& data, const NavigationRun& run) {
  const bool truth = data.truth.has_value();
  std::string out = "t_s,mode,lat_deg,lon_deg,h_m,roll_deg,pitch_deg,yaw_deg,v_e_mps,v_n_mps,v_u_mps,status";
  if (truth) out += ",err_lat_deg,err_lon_deg,err_north_m,err_east_m,err_v_e_mps,err_v_n_mps,err_v_u_mps";
  out += '\n';
  for (std::size_t m = 0; m < run.modes.size(); ++m)
    for (const NavigationFix& f : run.fixes[m]) {
      out += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{}", f.t_s, navigation_mode_name(run.modes[m]),
                         cell(rad2deg(f.lat_rad)), cell(rad2deg(f.lon_rad)), cell(f.h_m), rad2deg(f.attitude.roll_rad),
                         rad2deg(f.attitude.pitch_rad), rad2deg(f.attitude.yaw_rad), cell(f.v_enu.x()), cell(f.v_enu.y()),
                         cell(f.v_enu.z()), f.status);
      if (truth) {
        const TruthSample& t = truth_at(*data.truth, f.t_s);
        const PositionError e = position_error(f, t);
        const Eigen::Vector3d dv = f.v_enu - t.v_n;
        out += fmt::format(",{},{},{},{},{},{},{}", cell(e.lat_deg), cell(e.lon_deg), cell(e.north_m), cell(e.east_m),
                           cell(dv.x()), cell(dv.y()), cell(dv.z()));
      }
      out += '\n';
    }
  return out;
}

std::string filter_csv(const NavigationDataset& data, const NavigationRun& run, const Sky& sky) {
  const bool truth = data.truth.has_value();
  std::string out = "t_s,unit_i,unit_j,e_angle_deg,elevation_body_deg,elevation_deg,model_elevation_deg";
  if (truth) out += ",true_elevation_deg";
  out += ",innovation,innovation_var,nis,R,sigma_north_m,sigma_east_m,corr_north_east,sigma_heading_deg,sun_status";
  out += ",azimuth_deg,model_azimuth_deg,azimuth_innovation,azimuth_innovation_var,azimuth_nis,azimuth_R";
  out += ",rest_statistic,zero_velocity,zero_velocity_nis_e,zero_velocity_nis_n,zero_velocity_nis_u";
  out += ",pns_fix_lat_deg,pns_fix_lon_deg,pns_fix_nis\n";
  for (const FilterEpoch& f : run.filter) {
    const bool ok = f.sun.status == UnitSunStatus::Ok;
    out += fmt::format("{},{},{},{},{},{},{}", f.t_s, ok ? std::to_string(f.sun.i + 1) : "nan", ok ? std::to_string(f.sun.j + 1) : "nan",
                       ok ? cell(rad2deg(f.sun.angle_rad)) : "nan", ok ? cell(rad2deg(f.sun.elevation_rad)) : "nan",
                       cell(rad2deg(f.elevation_rad)), cell(rad2deg(f.model_elevation_rad)));
    if (truth) {
      const TruthSample& t = truth_at(*data.truth, f.t_s);
      const Site site{rad2deg(t.lat_rad), rad2deg(t.lon_rad), t.h_m};
      out += fmt::format(",{}", sun_position(data.start.plus_seconds(f.t_s), site, sky.sun).elevation_deg);
    }
    out += fmt::format(",{},{},{},{},{},{},{},{},{}", cell(f.update.innovation), cell(f.update.variance), cell(f.update.nis),
                       cell(f.update.R), f.sigma_north_m, f.sigma_east_m, cell(f.corr_north_east), rad2deg(f.sigma_heading_rad),
                       unit_sun_status_name(f.sun.status));
    out += fmt::format(",{},{},{},{},{},{}", cell(rad2deg(f.azimuth_rad)), cell(rad2deg(f.model_azimuth_rad)),
                       cell(f.azimuth_update.innovation), cell(f.azimuth_update.variance), cell(f.azimuth_update.nis),
                       cell(f.azimuth_update.R));
    const ZeroVelocityUpdate& z = f.zero_velocity;
    const bool zupt = std::isfinite(z.east.nis) || std::isfinite(z.north.nis) || std::isfinite(z.up.nis);
    out += fmt::format(",{},{},{},{},{}", cell(f.rest_statistic), zupt ? 1 : 0, cell(z.east.nis), cell(z.north.nis),
                       cell(z.up.nis));
    out += fmt::format(",{},{},{}\n", cell(rad2deg(f.pns_fix_lat_rad)), cell(rad2deg(f.pns_fix_lon_rad)),
                       cell(f.position_update.nis()));
  }
  return out;
}

std::string summary_csv(const std::vector<ModeErrorSummary>& rows) {
  std::string out = "mode,coordinate,mae_deg,rmse_deg,std_deg,count,final_error_m\n";
  for (const ModeErrorSummary& r : rows) {
    out += fmt::format("{},latitude,{},{},{},{},{}\n", navigation_mode_name(r.mode), cell(r.lat.mae), cell(r.lat.rmse),
                       cell(r.lat.std), r.lat.count, cell(r.final_north_m));
    out += fmt::format("{},longitude,{},{},{},{},{}\n", navigation_mode_name(r.mode), cell(r.lon.mae), cell(r.lon.rmse),
                       cell(r.lon.std), r.lon.count, cell(r.final_east_m));
  }
  return out;
}

std::string filter_summary_yaml(const NavigationRun& run, const Rig& rig) {
  const FilterSummary& s = run.filter_summary;
  int no_sun = 0;
  for (const FilterEpoch& f : run.filter) no_sun += f.sun.status == UnitSunStatus::Ok ? 0 : 1;
  return fmt::format(
      "# How the integrated filter ended (ins/filter.h FilterSummary): {}\n"
      "status: {}\npredictions: {}\nupdates: {}\nskipped: {}\nno_sun: {}  # readings without two usable units\n"
      "innovation_mean: {}\ninnovation_rms: {}\nmean_nis: {}\nnis_outside_95: {}\nfinal_R: {}\n"
      "zero_velocity_updates: {}  # navigation.zupt: scalar updates, one per velocity component\n"
      "zero_velocity_mean_nis: {}\n"
      "vertical_channel: {}\nmeasurement: {}  # navigation.measurement\nstart: {}\n",
      s.BriefReport(), filter_status_name(s.status), s.predictions, s.updates, s.skipped, no_sun, cell(s.innovation_mean),
      cell(s.innovation_rms), cell(s.mean_nis), cell(s.nis_outside_95), cell(s.final_R),
      s.zero_velocity_updates, cell(s.zero_velocity_mean_nis), run.vertical_channel,
      rig.navigation.measurement, run.start);
}

std::string mode_series(NavigationMode m, const std::string& column) {
  return fmt::format("($t_s/60):(@mode eq '{}' ? {} : NaN)", navigation_mode_name(m), column);
}

// Per NavigationMode, in its order.
constexpr std::string_view kModeStyle[4] = {"lines lw 2 lc rgb '#d62728'", "points pt 7 ps 0.4 lc rgb '#2ca02c'",
                                            "lines lw 2 lc rgb '#1f77b4'", "lines lw 2 lc rgb '#9467bd'"};
constexpr std::string_view kModeTitle[4] = {"SINS", "PNS", "SINS/PNS", "SINS/PNS smoothed (RTS)"};

std::vector<Plot> navigation_plots(const NavigationDataset& data, const NavigationRun& run) {
  const bool truth = data.truth.has_value();
  std::vector<Plot> plots;
  for (const auto& [png, column, label] : {std::tuple{"latitude.png", "$lat_deg", "latitude (°N)"},
                                           {"longitude.png", "$lon_deg", "longitude (°E)"}}) {
    Plot p{png, fmt::format("{} per mode (Z21 Figs. 8–11)", label), "time (min)", label};
    for (NavigationMode m : run.modes)
      p.series.push_back({"solution.csv", mode_series(m, column), std::string(kModeTitle[static_cast<int>(m)]),
                          std::string(kModeStyle[static_cast<int>(m)])});
    if (truth) {  // the truth from one INS mode's rows (every row of a mode is at a compass reading)
      NavigationMode ref = run.modes.front();
      for (NavigationMode m : run.modes)
        if (m != NavigationMode::Pns) ref = m;
      p.series.push_back({"solution.csv", mode_series(ref, fmt::format("{} - $err_{}", column, std::string(column).substr(1))),
                          "truth", "lines lw 1 dt 2 lc rgb 'black'"});
    }
    p.extra = "set key below horizontal maxrows 1 spacing 1.4\nset format y '%.3f'";
    plots.push_back(p);
  }
  if (truth) {
    Plot e{"position_error.png", "Position error per mode: north (solid, filled) and east (dashed, open)", "time (min)", "error (km)"};
    for (NavigationMode m : run.modes) {
      const int i = static_cast<int>(m);
      e.series.push_back({"solution.csv", mode_series(m, "$err_north_m/1000"), fmt::format("{} north", kModeTitle[i]),
                          std::string(kModeStyle[i])});
      // East dashed, or for PNS's points open circles.
      std::string east = std::string(kModeStyle[i]);
      if (east.starts_with("points")) east.replace(east.find("pt 7"), 4, "pt 6");
      else east += " dt 2";
      e.series.push_back({"solution.csv", mode_series(m, "$err_east_m/1000"), fmt::format("{} east", kModeTitle[i]), east});
    }
    e.extra = "set key below horizontal maxrows 2 spacing 1.4";
    plots.push_back(e);
  }
  if (!run.filter.empty()) {
    Plot f{"filter.png", "The SINS/PNS filter: innovation z = sin H_c − sin H^n and its ±2σ (√S), NIS on the right",
           "time (min)", "innovation", "NIS"};
    f.series = {{"filter.csv", "($t_s/60):$innovation", "innovation", "points pt 7 ps 0.4 lc rgb '#1f77b4'"},
                {"filter.csv", "($t_s/60):(2*sqrt($innovation_var))", "+2σ", "lines lw 1 lc rgb 'black'"},
                {"filter.csv", "($t_s/60):(-2*sqrt($innovation_var))", "−2σ", "lines lw 1 lc rgb 'black'"},
                {"filter.csv", "($t_s/60):$nis", "NIS (right axis)", "points pt 6 ps 0.4 lc rgb '#ff7f0e'", true}};
    f.extra = "set key below horizontal maxrows 1 spacing 1.4";
    plots.push_back(f);
    Plot h{"elevation.png", "The sun's elevation H^n: measured (two units, the filter's attitude) and the model at the "
                            "filter's position",
           "time (min)", "elevation (°)"};
    h.series = {{"filter.csv", "($t_s/60):$elevation_deg", "measured", "points pt 7 ps 0.4 lc rgb '#1f77b4'"},
                {"filter.csv", "($t_s/60):$model_elevation_deg", "model", "lines lw 2 lc rgb '#2ca02c'"}};
    if (truth) h.series.push_back({"filter.csv", "($t_s/60):$true_elevation_deg", "truth", "lines lw 1 dt 2 lc rgb 'black'"});
    h.extra = "set key below horizontal maxrows 1 spacing 1.4";
    plots.push_back(h);
  }
  return plots;
}

}  // namespace

std::vector<ModeErrorSummary> summarize_navigation(const NavigationDataset& data, const NavigationRun& run) {
  std::vector<ModeErrorSummary> out;
  if (!data.truth) return out;
  for (std::size_t m = 0; m < run.modes.size(); ++m) {
    std::vector<double> lat, lon;
    PositionError last{};
    for (const NavigationFix& f : run.fixes[m]) {
      const PositionError e = position_error(f, truth_at(*data.truth, f.t_s));
      lat.push_back(e.lat_deg);
      lon.push_back(e.lon_deg);
      last = e;
    }
    out.push_back({run.modes[m], error_statistics(lat), error_statistics(lon), last.north_m, last.east_m});
  }
  return out;
}

std::vector<DatasetFile> report_navigation(const std::filesystem::path& dir, const NavigationDataset& data,
                                           const NavigationRun& run, const Rig& rig, bool plots) {
  write_text_file(dir / "solution.csv", solution_csv(data, run));
  std::vector<DatasetFile> files{{"solution.csv", 1, "every mode's position and attitude per compass reading (and "
                                                     "its errors against the truth)"}};
  if (!run.filter.empty()) {
    write_text_file(dir / "filter.csv", filter_csv(data, run, rig.source.sky.resolved_sky()));
    write_text_file(dir / "filter_summary.yaml", filter_summary_yaml(run, rig));
    files.push_back({"filter.csv", 3, "the integrated filter per compass reading: the two units, the elevations, the "
                                      "innovation, its variance, NIS, R and the position and heading σ; the azimuth's; "
                                      "the rest detector and the zero-velocity update"});
    files.push_back({"filter_summary.yaml", 1, "how the integrated filter ended"});
  }
  if (data.truth) {
    write_text_file(dir / "summary.csv", summary_csv(summarize_navigation(data, run)));
    files.push_back({"summary.csv", 1, "MAE, RMSE and STD of the latitude and longitude errors per mode (Z21 §5)"});
  }
  if (plots) {
    const std::vector<Plot> p = navigation_plots(data, run);
    render_plots(dir, "plots.gp", p);
    for (const Plot& q : p) files.push_back({q.png, 1, q.title});
  }
  return files;
}

}  // namespace polrig
