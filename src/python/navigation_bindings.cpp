// Z21's unit-array compass with a strapdown INS (study/navigation.h, study/installation.h):
// Rig.simulate_navigation, polrig.read_navigation_dataset, polrig.navigate and
// polrig.calibrate_unit_array. Thin: each reads or writes the same folders as `polrig simulate`,
// `polrig navigate` and `polrig calibrate --method unit-array` (the same library calls), runs with the
// GIL released and hands its vectors to NumPy.
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include <fmt/format.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.h"
#include "convert.h"
#include "polrig/io/navigation_dataset.h"
#include "polrig/io/rig_yaml.h"
#include "polrig/io/output_dir.h"
#include "polrig/io/plot.h"
#include "polrig/io/installation_yaml.h"
#include "polrig/report/installation_report.h"
#include "polrig/report/navigation_report.h"
#include "polrig/report/navigation_study_report.h"
#include "polrig/study/navigation_study.h"
#include "polrig/units.h"
#include "rig_handle.h"

namespace polrig::python {
namespace {

// A rig loaded for a dataset (Rig.load(dataset=True)) met only a dataset's rules; a simulation
// needs a run's too (rig/keys.h, check_rig): the same message a rig file would have had.
void require_run_rules(const PyRig& r, std::string_view what) {
  if (const std::optional<RigProblem> p = check_rig(r.rig(), RigUse::Run))
    throw RigError(fmt::format("{}: key '{}': {} ({} simulates a run; the rig was read for a dataset, "
                               "Rig.load(dataset=True))", r.loaded.origin, p->path, p->message, what));
}

namespace fs = std::filesystem;

// out= that is, contains or lies inside an input (io/output_dir.h): ValueError, before anything.
void refuse_out_over_inputs(const std::optional<fs::path>& out, const std::vector<fs::path>& inputs) {
  if (!out) return;
  try {
    refuse_output_over_inputs(*out, inputs);
  } catch (const std::invalid_argument& e) {
    throw py::value_error(fmt::format("out: {}", e.what()));
  }
}

// A matrix of rows × columns from a function of (row, column).
template <class F>
py::array_t<double> matrix(std::size_t rows, std::size_t columns, F value) {
  std::vector<double> v(rows * columns);
  for (std::size_t r = 0; r < rows; ++r)
    for (std::size_t c = 0; c < columns; ++c) v[r * columns + c] = value(r, c);
  return take(std::move(v), {static_cast<py::ssize_t>(rows), static_cast<py::ssize_t>(columns)});
}

template <class T, class F>
py::array_t<double> column(const std::vector<T>& rows, F value) {
  std::vector<double> v;
  v.reserve(rows.size());
  for (const T& r : rows) v.push_back(value(r));
  return take(std::move(v));
}

py::dict dataset_dict(const NavigationDataset& d) {
  py::dict out;
  const std::size_t n = d.imu.size(), k = d.compass.size(), u = d.mounts.size();
  out["imu_t_s"] = column(d.imu, [](const ImuSample& s) { return s.t_s; });
  out["dtheta_rad"] = matrix(n, 3, [&](std::size_t r, std::size_t c) { return d.imu[r].dtheta[static_cast<int>(c)]; });
  out["dv_mps"] = matrix(n, 3, [&](std::size_t r, std::size_t c) { return d.imu[r].dv[static_cast<int>(c)]; });
  out["units_t_s"] = column(d.compass, [](const CompassEpoch& e) { return e.t_s; });
  out["aop_deg"] = matrix(k, u, [&](std::size_t r, std::size_t c) { return rad2deg(d.compass[r].units[c].aop_rad); });
  out["dop"] = matrix(k, u, [&](std::size_t r, std::size_t c) { return d.compass[r].units[c].dop; });
  if (d.truth) {
    const NavigationTruth& t = *d.truth;
    const bool samples = k > 0 && d.compass[0].samples.size() == u;
    if (samples) {
      out["true_aop_deg"] = matrix(k, u, [&](std::size_t r, std::size_t c) { return rad2deg(d.compass[r].samples[c].true_aop_rad); });
      out["true_dop"] = matrix(k, u, [&](std::size_t r, std::size_t c) { return d.compass[r].samples[c].true_dop; });
      std::vector<double> V(k * u * 3);
      for (std::size_t r = 0; r < k; ++r)
        for (std::size_t c = 0; c < u; ++c)
          for (std::size_t p = 0; p < 3; ++p) V[(r * u + c) * 3 + p] = d.compass[r].samples[c].V[p];
      out["V"] = take(std::move(V), {static_cast<py::ssize_t>(k), static_cast<py::ssize_t>(u), 3});
    }
    py::dict truth;
    truth["t_s"] = column(t.trajectory, [](const TruthSample& s) { return s.t_s; });
    truth["lat_deg"] = column(t.trajectory, [](const TruthSample& s) { return rad2deg(s.lat_rad); });
    truth["lon_deg"] = column(t.trajectory, [](const TruthSample& s) { return rad2deg(s.lon_rad); });
    truth["h_m"] = column(t.trajectory, [](const TruthSample& s) { return s.h_m; });
    truth["roll_deg"] = column(t.trajectory, [](const TruthSample& s) { return rad2deg(s.euler.roll_rad); });
    truth["pitch_deg"] = column(t.trajectory, [](const TruthSample& s) { return rad2deg(s.euler.pitch_rad); });
    truth["yaw_deg"] = column(t.trajectory, [](const TruthSample& s) { return rad2deg(s.euler.yaw_rad); });
    truth["v_enu"] = matrix(t.trajectory.size(), 3, [&](std::size_t r, std::size_t c) {
      return t.trajectory[r].v_n[static_cast<int>(c)];
    });
    if (!t.sun_elevation_rad.empty())
      truth["sun_elevation_deg"] = column(t.sun_elevation_rad, [](double h) { return rad2deg(h); });
    if (!t.units.mount_error_deg.empty())
      truth["mount_error_deg"] = matrix(u, 3, [&](std::size_t r, std::size_t c) { return t.units.mount_error_deg[r][c]; });
    out["truth"] = truth;
  }
  return out;
}

py::dict fixes_dict(const NavigationDataset& data, const std::vector<NavigationFix>& fixes) {
  py::dict out;
  out["t_s"] = column(fixes, [](const NavigationFix& f) { return f.t_s; });
  out["lat_deg"] = column(fixes, [](const NavigationFix& f) { return rad2deg(f.lat_rad); });
  out["lon_deg"] = column(fixes, [](const NavigationFix& f) { return rad2deg(f.lon_rad); });
  out["h_m"] = column(fixes, [](const NavigationFix& f) { return f.h_m; });
  out["roll_deg"] = column(fixes, [](const NavigationFix& f) { return rad2deg(f.attitude.roll_rad); });
  out["pitch_deg"] = column(fixes, [](const NavigationFix& f) { return rad2deg(f.attitude.pitch_rad); });
  out["yaw_deg"] = column(fixes, [](const NavigationFix& f) { return rad2deg(f.attitude.yaw_rad); });
  out["v_e_mps"] = column(fixes, [](const NavigationFix& f) { return f.v_enu.x(); });
  out["v_n_mps"] = column(fixes, [](const NavigationFix& f) { return f.v_enu.y(); });
  out["v_u_mps"] = column(fixes, [](const NavigationFix& f) { return f.v_enu.z(); });
  py::list status;
  for (const NavigationFix& f : fixes) status.append(f.status);
  out["status"] = status;
  if (data.truth) {
    std::vector<PositionError> e;
    for (const NavigationFix& f : fixes) e.push_back(position_error(f, truth_at(*data.truth, f.t_s)));
    out["err_lat_deg"] = column(e, [](const PositionError& x) { return x.lat_deg; });
    out["err_lon_deg"] = column(e, [](const PositionError& x) { return x.lon_deg; });
    for (int a = 0; a < 3; ++a)
      out[py::str(fmt::format("err_v_{}_mps", "enu"[a]))] = column(fixes, [&](const NavigationFix& f) {
        return f.v_enu[a] - truth_at(*data.truth, f.t_s).v_n[a];
      });
    out["err_north_m"] = column(e, [](const PositionError& x) { return x.north_m; });
    out["err_east_m"] = column(e, [](const PositionError& x) { return x.east_m; });
  }
  return out;
}

py::dict filter_dict(const NavigationRun& run) {
  py::dict out;
  const auto& f = run.filter;
  out["t_s"] = column(f, [](const FilterEpoch& e) { return e.t_s; });
  out["unit_i"] = column(f, [](const FilterEpoch& e) { return e.sun.status == UnitSunStatus::Ok ? e.sun.i + 1.0 : NAN; });
  out["unit_j"] = column(f, [](const FilterEpoch& e) { return e.sun.status == UnitSunStatus::Ok ? e.sun.j + 1.0 : NAN; });
  out["e_angle_deg"] = column(f, [](const FilterEpoch& e) { return e.sun.status == UnitSunStatus::Ok ? rad2deg(e.sun.angle_rad) : NAN; });
  out["elevation_body_deg"] = column(f, [](const FilterEpoch& e) {
    return e.sun.status == UnitSunStatus::Ok ? rad2deg(e.sun.elevation_rad) : NAN;
  });
  out["elevation_deg"] = column(f, [](const FilterEpoch& e) { return rad2deg(e.elevation_rad); });
  out["model_elevation_deg"] = column(f, [](const FilterEpoch& e) { return rad2deg(e.model_elevation_rad); });
  out["innovation"] = column(f, [](const FilterEpoch& e) { return e.update.innovation; });
  out["innovation_var"] = column(f, [](const FilterEpoch& e) { return e.update.variance; });
  out["nis"] = column(f, [](const FilterEpoch& e) { return e.update.nis; });
  out["R"] = column(f, [](const FilterEpoch& e) { return e.update.R; });
  out["azimuth_deg"] = column(f, [](const FilterEpoch& e) { return rad2deg(e.azimuth_rad); });
  out["model_azimuth_deg"] = column(f, [](const FilterEpoch& e) { return rad2deg(e.model_azimuth_rad); });
  out["azimuth_innovation"] = column(f, [](const FilterEpoch& e) { return e.azimuth_update.innovation; });
  out["azimuth_nis"] = column(f, [](const FilterEpoch& e) { return e.azimuth_update.nis; });
  out["azimuth_R"] = column(f, [](const FilterEpoch& e) { return e.azimuth_update.R; });
  out["rest_statistic"] = column(f, [](const FilterEpoch& e) { return e.rest_statistic; });
  out["zero_velocity_nis_e"] = column(f, [](const FilterEpoch& e) { return e.zero_velocity.east.nis; });
  out["zero_velocity_nis_n"] = column(f, [](const FilterEpoch& e) { return e.zero_velocity.north.nis; });
  out["zero_velocity_nis_u"] = column(f, [](const FilterEpoch& e) { return e.zero_velocity.up.nis; });
  out["pns_fix_lat_deg"] = column(f, [](const FilterEpoch& e) { return rad2deg(e.pns_fix_lat_rad); });
  out["pns_fix_lon_deg"] = column(f, [](const FilterEpoch& e) { return rad2deg(e.pns_fix_lon_rad); });
  out["pns_fix_nis"] = column(f, [](const FilterEpoch& e) { return e.position_update.nis(); });
  out["sigma_north_m"] = column(f, [](const FilterEpoch& e) { return e.sigma_north_m; });
  out["sigma_east_m"] = column(f, [](const FilterEpoch& e) { return e.sigma_east_m; });
  out["corr_north_east"] = column(f, [](const FilterEpoch& e) { return e.corr_north_east; });
  out["sigma_heading_deg"] = column(f, [](const FilterEpoch& e) { return rad2deg(e.sigma_heading_rad); });
  py::list sun_status;
  int no_sun = 0;
  for (const FilterEpoch& e : f) {
    sun_status.append(std::string(unit_sun_status_name(e.sun.status)));
    no_sun += e.sun.status == UnitSunStatus::Ok ? 0 : 1;
  }
  out["sun_status"] = sun_status;
  const FilterSummary& s = run.filter_summary;
  py::dict summary;
  summary["status"] = std::string(filter_status_name(s.status));
  summary["predictions"] = s.predictions;
  summary["updates"] = s.updates;
  summary["skipped"] = s.skipped;
  summary["no_sun"] = no_sun;
  summary["innovation_mean"] = s.innovation_mean;
  summary["innovation_rms"] = s.innovation_rms;
  summary["mean_nis"] = s.mean_nis;
  summary["nis_outside_95"] = s.nis_outside_95;
  summary["final_R"] = s.final_R;
  summary["zero_velocity_updates"] = s.zero_velocity_updates;
  summary["zero_velocity_mean_nis"] = s.zero_velocity_mean_nis;
  summary["brief_report"] = s.BriefReport();
  out["summary"] = summary;
  return out;
}

// The dataset's rig (DIR/rig.yaml), or the one given: a unit array.
// A dataset's folder, opened once for its rig and every file (io/dataset_folder.h).
std::unique_ptr<DatasetFolder> dataset_folder(const fs::path& dataset) {
  if (!fs::is_directory(dataset)) throw py::value_error(fmt::format("{}: not a folder (expected a unit-array dataset)", dataset.string()));
  return std::make_unique<DatasetFolder>(dataset);
}

LoadedRig dataset_rig(const DatasetFolder& dataset, const std::optional<PyRig>& rig, const char* what) {
  LoadedRig r;
  if (rig) {
    r = rig->loaded;
  } else {
    if (!dataset.has("rig.yaml"))
      throw py::value_error(fmt::format("{}: no rig.yaml (a unit-array dataset holds its rig; else pass rig=)", dataset.path().string()));
    r = parse_rig(dataset.read("rig.yaml", kMaxRigYamlBytes), dataset.path("rig.yaml").string(), {}, RigUse::ReadDataset);
  }
  require_instrument(r.rig, Instrument::kUnitArray, what, r.origin);
  return r;
}

// plots=True draws into out=: without it there is nowhere to draw, and saying nothing would hide it.
void check_plots(bool plots, bool out) {
  if (plots && !out) throw py::value_error("plots=True: the plots are written into out=; give out= or pass plots=False");
  if (plots && !gnuplot_available())
    throw std::runtime_error("plots=True needs gnuplot, which was not found; install it (scripts/setup-deps.sh) or pass plots=False");
}


py::dict percentiles_dict(const std::vector<Percentiles>& p) {
  py::dict out;
  out["p05"] = column(p, [](const Percentiles& x) { return x.p05; });
  out["p25"] = column(p, [](const Percentiles& x) { return x.p25; });
  out["p50"] = column(p, [](const Percentiles& x) { return x.p50; });
  out["p75"] = column(p, [](const Percentiles& x) { return x.p75; });
  out["p95"] = column(p, [](const Percentiles& x) { return x.p95; });
  return out;
}

template <class T>
py::list names(const std::vector<T>& rows, std::string (*name)(const T&)) {
  py::list out;
  for (const T& r : rows) out.append(name(r));
  return out;
}

py::dict study_dict(const NavigationStudy& st) {
  py::dict out;
  const auto mode_of = +[](const NavigationTrialResult& t) { return std::string(navigation_mode_name(t.mode)); };
  py::dict trials;
  const auto& tr = st.trials;
  trials["cell"] = column(tr, [](const NavigationTrialResult& t) { return static_cast<double>(t.cell); });
  trials["trial"] = column(tr, [](const NavigationTrialResult& t) { return static_cast<double>(t.trial); });
  trials["mode"] = names(tr, mode_of);
  trials["final_north_m"] = column(tr, [](const NavigationTrialResult& t) { return t.final_north_m; });
  trials["final_east_m"] = column(tr, [](const NavigationTrialResult& t) { return t.final_east_m; });
  trials["final_error_m"] = column(tr, [](const NavigationTrialResult& t) { return t.final_error_m; });
  trials["final_heading_error_deg"] = column(tr, [](const NavigationTrialResult& t) { return t.final_heading_error_deg; });
  trials["lat_mae_deg"] = column(tr, [](const NavigationTrialResult& t) { return t.lat_deg.mae; });
  trials["lat_rmse_deg"] = column(tr, [](const NavigationTrialResult& t) { return t.lat_deg.rmse; });
  trials["lat_std_deg"] = column(tr, [](const NavigationTrialResult& t) { return t.lat_deg.std; });
  trials["lon_mae_deg"] = column(tr, [](const NavigationTrialResult& t) { return t.lon_deg.mae; });
  trials["lon_rmse_deg"] = column(tr, [](const NavigationTrialResult& t) { return t.lon_deg.rmse; });
  trials["lon_std_deg"] = column(tr, [](const NavigationTrialResult& t) { return t.lon_deg.std; });
  trials["filter_nis_mean"] = column(tr, [](const NavigationTrialResult& t) { return t.filter_nis_mean; });
  trials["nees_position"] = column(tr, [](const NavigationTrialResult& t) { return t.nees_position; });
  trials["nees_attitude"] = column(tr, [](const NavigationTrialResult& t) { return t.nees_attitude; });
  out["trials"] = trials;
  py::list cells;
  for (const NavigationStudyCell& c : st.cells) {
    py::dict d;
    d["index"] = c.index;
    d["factor"] = c.factor;
    d["key"] = c.key;
    d["value"] = c.value;
    d["duration_s"] = c.duration_s;
    cells.append(d);
  }
  out["cells"] = cells;
  py::dict summary;
  const auto& sm = st.summary;
  summary["cell"] = column(sm, [](const NavigationStudySummary& x) { return static_cast<double>(x.cell); });
  summary["mode"] = names(sm, +[](const NavigationStudySummary& x) { return std::string(navigation_mode_name(x.mode)); });
  std::vector<Percentiles> fe, la, lo;
  for (const NavigationStudySummary& x : sm) fe.push_back(x.final_error_m), la.push_back(x.lat_mae_deg), lo.push_back(x.lon_mae_deg);
  summary["final_error_m"] = percentiles_dict(fe);
  summary["lat_mae_deg"] = percentiles_dict(la);
  summary["lon_mae_deg"] = percentiles_dict(lo);
  out["summary"] = summary;
  py::dict tilt;
  tilt["tilt_deg"] = column(st.tilt, [](const TiltErrorRow& r) { return r.tilt_deg; });
  tilt["mean_abs_deg"] = column(st.tilt, [](const TiltErrorRow& r) { return r.mean_abs_deg; });
  tilt["sd_abs_deg"] = column(st.tilt, [](const TiltErrorRow& r) { return r.sd_abs_deg; });
  tilt["first_order_deg"] = column(st.tilt, [](const TiltErrorRow& r) { return r.first_order_deg; });
  tilt["exact_deg"] = column(st.tilt, [](const TiltErrorRow& r) { return r.exact_deg; });
  tilt["z21_deg"] = column(st.tilt, [](const TiltErrorRow& r) { return r.z21_deg; });
  out["tilt"] = tilt;
  py::dict dop;
  dop["lo"] = column(st.dop, [](const DopBin& b) { return b.lo; });
  dop["hi"] = column(st.dop, [](const DopBin& b) { return b.hi; });
  dop["count"] = column(st.dop, [](const DopBin& b) { return static_cast<double>(b.count); });
  dop["mean_abs_deg"] = column(st.dop, [](const DopBin& b) { return b.mean_abs_deg; });
  dop["sd_abs_deg"] = column(st.dop, [](const DopBin& b) { return b.sd_abs_deg; });
  dop["mean_true_dop"] = column(st.dop, [](const DopBin& b) { return b.mean_true_dop; });
  out["dop"] = dop;
  py::list goal;  // per cell: goal.csv's rows
  for (const NavigationGoal& g : st.goal) {
    py::dict row;
    row["cell"] = g.cell;
    row["trials"] = g.trials;
    row["position_met"] = g.position_met;
    row["heading_met"] = g.heading_met;
    row["both_met"] = g.both_met;
    goal.append(row);
  }
  out["goal"] = goal;
  py::list consistency;  // per cell: consistency.csv's rows
  for (const NavigationConsistency& c : st.consistency) {
    py::dict row;
    row["cell"] = c.cell;
    row["trials"] = c.trials;
    for (auto [b, name] : {std::pair{&c.nees_position, "nees_position"}, {&c.nees_attitude, "nees_attitude"}, {&c.nis, "nis"}}) {
      py::dict band;
      band["mean"] = b->mean;
      band["lo"] = b->lo;
      band["hi"] = b->hi;
      band["dof"] = b->dof;
      band["inside"] = b->inside();
      row[name] = band;
    }
    consistency.append(row);
  }
  out["consistency"] = consistency;
  py::dict bands;
  for (const NavigationErrorBand& b : st.bands) {
    py::dict d = percentiles_dict(b.error_m);
    d["t_s"] = column(b.t_s, [](double t) { return t; });
    bands[py::str(std::string(navigation_mode_name(b.mode)))] = d;
  }
  out["error_vs_time"] = bands;
  return out;
}

// A list argument: empty without one.
std::vector<double> values_of(const std::optional<py::object>& o, const char* name) {
  return o ? finite_values(as_array(*o, name), name) : std::vector<double>{};
}

}  // namespace

void bind_navigation(py::module_& m) {
  auto rig = rig_class(m);
  rig.def("simulate_navigation", [](const PyRig& self, std::optional<fs::path> out, bool force, std::optional<int> threads,
                                    const py::object& progress) {
    require(self, Instrument::kUnitArray, "simulate_navigation");
    require_run_rules(self, "simulate_navigation");
    const ThreadLimit limit(threads);
    const Progress p = progress_from(progress);
    NavigationDataset d;
    {
      py::gil_scoped_release release;
      std::optional<OutputDir> dir;
      if (out) dir.emplace(*out, force);
      d = simulate_navigation(self.rig(), p);
      if (dir) {
        const std::string command = fmt::format("python: polrig.Rig({}).simulate_navigation(out='{}')", self.loaded.origin, out->string());
        write_manifest(dir->staging(), {command, &self.loaded, write_navigation_dataset(dir->staging(), d)});
        dir->commit();
      }
    }
    return dataset_dict(d);
  }, "A unit-array rig's navigation run (Z21): the true trajectory, the IMU with its errors and every unit's reading "
     "at the compass rate, as arrays; with out=, also the dataset folder `polrig simulate` writes (imu.csv, units.csv, "
     "truth.csv, truth.yaml, manifest.yaml, rig.yaml). Keys: imu_t_s, dtheta_rad (N, 3), dv_mps (N, 3), units_t_s, "
     "aop_deg and dop (K, units), true_aop_deg, true_dop, V (K, units, 3), truth (a dict: t_s, lat_deg, lon_deg, h_m, "
     "roll_deg, pitch_deg, yaw_deg, v_enu, sun_elevation_deg, mount_error_deg).",
     py::arg("out") = py::none(), py::kw_only(), py::arg("force") = false, py::arg("threads") = py::none(),
     py::arg("progress") = py::none());


  rig.def("study_navigation", [](const PyRig& self, int trials, std::optional<py::object> durations_s,
                                 std::optional<py::object> p_max, std::optional<py::object> noise_sigma_V,
                                 std::optional<py::object> ring_tilts_deg, std::optional<py::object> tilts_deg,
                                 std::optional<fs::path> out, bool force, bool plots, std::optional<int> threads,
                                 const py::object& progress) {
    require(self, Instrument::kUnitArray, "study_navigation");
    require_run_rules(self, "study_navigation");
    check_plots(plots, out.has_value());
    NavigationStudySettings settings;
    settings.trials = trials;
    settings.durations_s = values_of(durations_s, "durations_s");
    settings.p_max = values_of(p_max, "p_max");
    settings.noise_sigma_V = values_of(noise_sigma_V, "noise_sigma_V");
    settings.ring_tilts_deg = values_of(ring_tilts_deg, "ring_tilts_deg");
    if (tilts_deg) settings.tilts_deg = values_of(tilts_deg, "tilts_deg");
    try {
      check_navigation_study_settings(self.rig(), settings);
    } catch (const std::invalid_argument& e) {
      throw py::value_error(e.what());
    }
    const ThreadLimit limit(threads);
    const Progress p = progress_from(progress);
    NavigationStudy st;
    {
      py::gil_scoped_release release;
      std::optional<OutputDir> d;
      if (out) d.emplace(*out, force);
      st = navigation_study(self.rig(), settings, p);
      if (d) {
        const std::string command = fmt::format("python: polrig.Rig({}).study_navigation(trials={}, out='{}')",
                                                self.loaded.origin, trials, out->string());
        write_manifest(d->staging(), {command, &self.loaded, report_navigation_study(d->staging(), st, plots)});
        d->commit();
      }
    }
    return study_dict(st);
  }, "`polrig study navigation`: Monte-Carlo trials of a unit-array rig (each simulate + SINS, PNS, SINS/PNS), "
     "optional sweeps (durations_s, p_max, noise_sigma_V, ring_tilts_deg: each value × trials), Z21's Fig. 17 "
     "(tilts_deg) and Fig. 16 (DoP bins). Returns a dict: trials (trials.csv's columns), cells, summary (percentiles "
     "per cell and mode), tilt, dop, error_vs_time (per mode, percentiles of the horizontal error per reading). With "
     "out=, the folder the CLI writes.",
     py::kw_only(), py::arg("trials") = 20, py::arg("durations_s") = py::none(), py::arg("p_max") = py::none(),
     py::arg("noise_sigma_V") = py::none(), py::arg("ring_tilts_deg") = py::none(), py::arg("tilts_deg") = py::none(),
     py::arg("out") = py::none(), py::arg("force") = false, py::arg("plots") = false, py::arg("threads") = py::none(),
     py::arg("progress") = py::none());

  m.def("read_navigation_dataset", [](const fs::path& dir, std::optional<PyRig> rig) {
    const std::unique_ptr<DatasetFolder> folder = dataset_folder(dir);
    const LoadedRig r = dataset_rig(*folder, rig, "read_navigation_dataset");
    NavigationDataset d;
    {
      py::gil_scoped_release release;
      d = read_navigation_dataset(*folder, r.rig);
    }
    return dataset_dict(d);
  }, "A unit-array dataset's files (simulated or measured) as arrays, the keys of Rig.simulate_navigation (truth: "
     "truth.csv's columns only).", py::arg("dir"), py::kw_only(), py::arg("rig") = py::none());

  m.def("navigate", [](const fs::path& dir, const std::string& mode, std::optional<fs::path> out, std::optional<PyRig> rig,
                       std::optional<fs::path> calibration, double sins_rate_hz, bool force, bool plots,
                       std::optional<int> threads, const py::object& progress) {
    check_plots(plots, out.has_value());
    if (calibration && calibration->empty()) throw py::value_error("calibration='': expected a file name");
    refuse_out_over_inputs(out, {dir, calibration.value_or(fs::path())});
    const std::unique_ptr<DatasetFolder> folder = dataset_folder(dir);
    const LoadedRig r = dataset_rig(*folder, rig, "navigate");
    NavigationOptions options;
    try {
      options.modes = parse_navigation_modes(mode);
    } catch (const std::invalid_argument& e) {
      throw py::value_error(fmt::format("mode: {}", e.what()));
    }
    if (!(std::isfinite(sins_rate_hz) && sins_rate_hz >= 0))
      throw py::value_error(fmt::format("sins_rate_hz: expected a rate ≥ 0 Hz (0: at the compass readings), got {}", sins_rate_hz));
    options.sins_rate_hz = sins_rate_hz;
    const ThreadLimit limit(threads);
    const Progress p = progress_from(progress);
    NavigationDataset data;
    NavigationRun run;
    {
      py::gil_scoped_release release;
      data = read_navigation_dataset(*folder, r.rig);
      if (calibration) options.mounts = read_installation(*calibration, data.mounts);
      std::optional<OutputDir> d;
      if (out) d.emplace(*out, force);
      run = navigate(data, r.rig, options, p);
      if (d) {
        const std::string command = fmt::format("python: polrig.navigate('{}', mode='{}', out='{}')", dir.string(), mode, out->string());
        std::vector<std::string> inputs{(dir / "imu.csv").string()};
        if (folder->has("units.csv")) inputs.push_back((dir / "units.csv").string());
        if (data.truth) inputs.push_back((dir / "truth.csv").string());
        if (calibration) inputs.push_back(calibration->string());
        write_manifest(d->staging(), {command, &r, report_navigation(d->staging(), data, run, r.rig, plots), inputs});
        d->commit();
      }
    }
    py::dict result;
    for (std::size_t i = 0; i < run.modes.size(); ++i)
      result[py::str(std::string(navigation_mode_name(run.modes[i])))] = fixes_dict(data, run.fixes[i]);
    if (!run.filter.empty()) result["filter"] = filter_dict(run);
    py::dict summary;
    for (const ModeErrorSummary& s : summarize_navigation(data, run)) {
      py::dict row;
      for (const auto& [name, e] : {std::pair{"lat", &s.lat}, {"lon", &s.lon}}) {
        row[py::str(fmt::format("{}_mae_deg", name))] = e->mae;
        row[py::str(fmt::format("{}_rmse_deg", name))] = e->rmse;
        row[py::str(fmt::format("{}_std_deg", name))] = e->std;
      }
      row["count"] = s.lat.count;
      row["final_north_m"] = s.final_north_m;
      row["final_east_m"] = s.final_east_m;
      summary[py::str(std::string(navigation_mode_name(s.mode)))] = row;
    }
    result["summary"] = summary;
    return result;
  }, "SINS, PNS and SINS/PNS on a unit-array dataset (`polrig navigate`): per mode a dict of solution.csv's columns "
     "(t_s, lat_deg, lon_deg, h_m, roll_deg, pitch_deg, yaw_deg, status, and err_* against a truth), 'filter' (filter.csv's "
     "columns and its 'summary'), 'summary' (summary.csv: MAE, RMSE, STD per mode; empty without a truth). With out=, the "
     "folder `polrig navigate` writes.",
     py::arg("dir"), py::kw_only(), py::arg("mode") = "all", py::arg("out") = py::none(), py::arg("rig") = py::none(),
     py::arg("calibration") = py::none(), py::arg("sins_rate_hz") = 0.0, py::arg("force") = false, py::arg("plots") = false,
     py::arg("threads") = py::none(), py::arg("progress") = py::none());

  m.def("calibrate_unit_array", [](const fs::path& dir, std::optional<fs::path> out, std::optional<PyRig> rig, bool force,
                                   bool plots, std::optional<int> threads) {
    check_plots(plots, out.has_value());
    refuse_out_over_inputs(out, {dir});
    const std::unique_ptr<DatasetFolder> folder = dataset_folder(dir);
    const LoadedRig r = dataset_rig(*folder, rig, "calibrate --method unit-array");
    const ThreadLimit limit(threads);
    InstallationRun run;
    {
      py::gil_scoped_release release;
      const NavigationDataset data = read_navigation_dataset(*folder, r.rig);
      std::optional<OutputDir> d;
      if (out) d.emplace(*out, force);
      run = calibrate_unit_array(data, r.rig);
      if (d) {
        const std::string command = fmt::format("python: polrig.calibrate_unit_array('{}', out='{}')", dir.string(), out->string());
        write_manifest(d->staging(), {command, &r, report_installation(d->staging(), run, plots), {dir.string()}});
        d->commit();
      }
    }
    py::dict result;
    const std::size_t n = run.units.size();
    result["error_deg"] = matrix(n, 3, [&](std::size_t i, std::size_t a) { return run.units[i].error_deg[a]; });
    result["standard_error_deg"] = matrix(n, 3, [&](std::size_t i, std::size_t a) { return run.units[i].standard_error_deg[a]; });
    result["rms_before_deg"] = column(run.units, [](const UnitInstallation& u) { return u.rms_before_deg; });
    result["rms_after_deg"] = column(run.units, [](const UnitInstallation& u) { return u.rms_after_deg; });
    result["used"] = column(run.units, [](const UnitInstallation& u) { return static_cast<double>(u.used); });
    result["iterations"] = column(run.units, [](const UnitInstallation& u) { return static_cast<double>(u.iterations); });
    py::list converged;
    for (const UnitInstallation& u : run.units) converged.append(u.converged);
    result["converged"] = converged;
    result["epochs"] = run.epochs;
    result["elevation_readings"] = run.elevation_epochs;
    py::list termination;
    for (const UnitInstallation& u : run.units) termination.append(u.termination);
    result["termination"] = termination;
    result["attitude_from"] = run.attitude_from;
    result["elevation_mean_before_deg"] = run.elevation_mean_before_deg;
    result["elevation_mean_after_deg"] = run.elevation_mean_after_deg;
    result["elevation_mae_before_deg"] = run.elevation_mae_before_deg;
    result["elevation_mae_after_deg"] = run.elevation_mae_after_deg;
    return result;
  }, "Z21's installation calibration of a unit-array dataset (`polrig calibrate --method unit-array`): each unit's "
     "mounting errors δ (units × 3, degrees about its own X, Y, Z), their standard errors, the AoP residual RMS before "
     "and after, and the sun-elevation error before and after. With out=, the folder the CLI writes (calibration.yaml "
     "is what navigate(calibration=) reads).",
     py::arg("dir"), py::kw_only(), py::arg("out") = py::none(), py::arg("rig") = py::none(), py::arg("force") = false,
     py::arg("plots") = false, py::arg("threads") = py::none());
}

}  // namespace polrig::python
