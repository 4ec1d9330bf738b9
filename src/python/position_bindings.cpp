// polrig.fix_position (W16 Eq. 17 from zenith angles), polrig.locate (the locate core on a level
// camera's sun vectors: the fix and the heading, Eq. 18), polrig.two_sighting_error (Eq. 15) and
// Rig.study_positioning (docs/python.md). Frames and senses are compass/positioning.h's.
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <pybind11/stl.h>

#include "bindings.h"
#include "convert.h"
#include "polrig/compass/positioning.h"
#include "polrig/io/four_camera_calibration.h"
#include "polrig/report/locate_report.h"
#include "polrig/rig/error.h"
#include "polrig/rig/rig.h"
#include "polrig/study/positioning.h"
#include "records.h"
#include "rig_handle.h"
#include "sky_args.h"

namespace polrig::python {
using namespace pybind11::literals;

namespace {

struct FixTag {};
struct LocationTag {};
struct PositioningStudyTag {};
struct PositioningTrialsTag {};

PositionOptions options_of(bool refraction, double ut1_minus_utc_s, bool second_root) {
  PositionOptions o;
  check_option(ut1_minus_utc_s, "ut1_minus_utc_s", -1, 1, "s");
  o.sun.refraction = refraction;
  o.sun.ut1_minus_utc_s = ut1_minus_utc_s;
  o.second_root = second_root;
  return o;
}

py::object strings(const std::vector<std::string>& v) {
  const py::module_ np = py::module_::import("numpy");
  py::list l;
  for (const std::string& s : v) l.append(py::str(s));
  return np.attr("array")(l, "dtype"_a = "object");
}

// fix.csv's columns, one element per root (the chosen first).
RecordOf<FixTag> fix_record(const PositionFix& fix, const std::optional<Site>& truth) {
  std::vector<const PositionRoot*> roots{&fix.chosen};
  if (fix.alternative) roots.push_back(&*fix.alternative);
  std::vector<std::string> which{"chosen", "alternative"}, termination, message;
  which.resize(roots.size());
  const auto column = [&](auto get) {
    std::vector<double> v;
    for (const PositionRoot* r : roots) v.push_back(get(*r));
    return take(std::move(v));
  };
  const auto count = [&](auto get) {
    std::vector<std::int64_t> v;
    for (const PositionRoot* r : roots) v.push_back(get(*r));
    return take(std::move(v));
  };
  for (const PositionRoot* r : roots) {
    termination.emplace_back(position_termination_name(r->summary.termination));
    message.push_back(r->summary.message);
  }
  Record rec;
  rec.add("root", strings(which));
  rec.add("lat_deg", column([](const PositionRoot& r) { return r.lat_deg; }));
  rec.add("lon_deg", column([](const PositionRoot& r) { return r.lon_deg; }));
  rec.add("error_km", column([&](const PositionRoot& r) {
    return truth ? great_circle_km(r.lat_deg, r.lon_deg, truth->lat_deg, truth->lon_deg) : NAN;
  }));
  rec.add("prior_distance_km", column([](const PositionRoot& r) { return r.prior_distance_km; }));
  rec.add("termination", strings(termination));
  rec.add("iterations", count([](const PositionRoot& r) { return r.summary.iterations; }));
  rec.add("evaluations", count([](const PositionRoot& r) { return r.summary.evaluations; }));
  rec.add("relinearizations", count([](const PositionRoot& r) { return r.summary.relinearizations; }));
  rec.add("sightings", count([](const PositionRoot& r) { return r.summary.sightings; }));
  rec.add("rank", count([](const PositionRoot& r) { return r.summary.rank; }));
  rec.add("singular_ratio", column([](const PositionRoot& r) { return r.summary.singular_ratio; }));
  rec.add("cost_deg2", column([](const PositionRoot& r) { return r.summary.final_cost_deg2; }));
  rec.add("residual_rms_deg", column([](const PositionRoot& r) { return r.summary.residual_rms_deg; }));
  rec.add("sd_north_km", column([](const PositionRoot& r) { return r.sd_north_km; }));
  rec.add("sd_east_km", column([](const PositionRoot& r) { return r.sd_east_km; }));
  rec.add("sd_major_km", column([](const PositionRoot& r) { return r.sd_major_km; }));
  rec.add("corr_north_east", column([](const PositionRoot& r) { return r.corr_north_east; }));
  rec.add("message", strings(message));
  rec.add("alternative_note", py::str(fix.alternative_note));
  return RecordOf<FixTag>(std::move(rec));
}

const std::vector<std::pair<const char*, const char*>> kFixFields{
    {"root", "'chosen' (nearest the prior), then 'alternative' (the mirror root) when found"},
    {"lat_deg", "latitude L̂ (geodetic, north positive)"},
    {"lon_deg", "longitude λ̂ (east positive), (−180°, 180°]"},
    {"error_km", "great-circle distance to the truth (NaN without one)"},
    {"prior_distance_km", "great-circle distance to the prior"},
    {"termination", "how the fit ended: converged, no_convergence, rank_deficient, too_few_sightings"},
    {"iterations", "Jacobian evaluations over all re-linearizations"},
    {"evaluations", "residual evaluations"},
    {"relinearizations", "SunTracks built at successive estimates"},
    {"sightings", "sightings used (positive weight)"},
    {"rank", "rank of the Jacobian (2 when both coordinates are determined)"},
    {"singular_ratio", "σ_min/σ_max of the Jacobian in north/east units (conditioning)"},
    {"cost_deg2", "½·Σ w·r² at the end, deg²"},
    {"residual_rms_deg", "√(Σ w·r²/Σ w), degrees"},
    {"sd_north_km", "1σ of the north coordinate, km (NaN with two sightings or rank < 2)"},
    {"sd_east_km", "1σ of the east coordinate, km"},
    {"sd_major_km", "1σ error ellipse's semi-major axis, km"},
    {"corr_north_east", "the correlation of the north and east errors of the same covariance (NaN likewise)"},
    {"message", "why each fit stopped"},
    {"alternative_note", "why there is no alternative root ('' when there is one)"}};

std::vector<ZenithSighting> zenith_sightings(const py::object& utc, const DoubleArray& zenith,
                                             const py::object& weight) {
  const std::vector<UtcTime> t = utc_times(utc, "utc");
  const std::vector<double> z = finite_values(zenith, "zenith_deg");
  if (z.size() != t.size())
    throw py::value_error(fmt::format("zenith_deg: {} values for {} times", z.size(), t.size()));
  std::vector<double> w(t.size(), 1.0);
  if (!weight.is_none()) {
    w = finite_values(as_array(weight, "weight", 1), "weight");
    if (w.size() != t.size()) throw py::value_error(fmt::format("weight: {} values for {} times", w.size(), t.size()));
  }
  std::vector<ZenithSighting> out(t.size());
  for (std::size_t k = 0; k < t.size(); ++k) out[k] = {t[k], z[k], w[k]};
  return out;
}

// heading.csv's columns and .fix as a polrig.Location (the locate core's and locate_dataset's).
RecordOf<LocationTag> location_record(const Location& loc, const std::optional<Site>& tr,
                                      const std::vector<double>& truth_h) {
  const std::size_t n = loc.samples.size();
  const auto column = [&](auto get) {
    std::vector<double> v(n);
    for (std::size_t k = 0; k < n; ++k) v[k] = get(loc.samples[k], k);
    return take(std::move(v));
  };
  std::vector<std::int64_t> ns(n);
  for (std::size_t k = 0; k < n; ++k) ns[k] = std::llround(loc.samples[k].utc.unix_s * 1e9);
  const py::module_ np = py::module_::import("numpy");
  Record r;
  r.add("fix", py::cast(fix_record(loc.fix, tr)));
  r.add("utc", take(std::move(ns)).attr("astype")("datetime64[ns]"));
  r.add("weight", column([](const LocateSample& s, std::size_t) { return s.weight; }));
  r.add("zenith_deg", column([](const LocateSample& s, std::size_t) { return s.zenith_deg; }));
  r.add("zenith_fix_deg", column([](const LocateSample& s, std::size_t) { return s.zenith_fix_deg; }));
  r.add("residual_deg", column([](const LocateSample& s, std::size_t) { return s.residual_deg; }));
  r.add("alpha_s_deg", column([](const LocateSample& s, std::size_t) { return s.alpha_s_deg; }));
  r.add("beta_deg", column([](const LocateSample& s, std::size_t) { return s.beta_deg; }));
  r.add("heading_deg", column([](const LocateSample& s, std::size_t) { return s.heading_deg; }));
  r.add("heading_true_deg", column([&](const LocateSample&, std::size_t k) { return truth_h[k]; }));
  r.add("heading_error_deg", column([&](const LocateSample& s, std::size_t k) {
    return std::isnan(truth_h[k]) || std::isnan(s.heading_deg) ? NAN : std::remainder(s.heading_deg - truth_h[k], 360.0);
  }));
  r.add("heading_mean_deg", py::float_(loc.heading_mean_deg));
  r.add("heading_sd_deg", py::float_(loc.heading_sd_deg));
  return RecordOf<LocationTag>(std::move(r));
}

}  // namespace

void bind_position(py::module_& m) {
  bind_record<FixTag>(m, "PositionFix",
                      "A position fix from the sun's zenith angles (W16 Eq. 17): fix.csv's columns, "
                      "one element per root.", kFixFields);
  bind_record<LocationTag>(m, "Location",
                           "The locate core's result: .fix (polrig.PositionFix) and heading.csv's "
                           "columns, one element per sighting.",
                           {{"fix", "polrig.PositionFix"},
                            {"utc", "the sightings' times (numpy.datetime64[ns])"},
                            {"weight", "the weights"},
                            {"zenith_deg", "θ_S measured: acos(s_z/|s|) (Eq. 16)"},
                            {"zenith_fix_deg", "the ephemeris' θ_S at the fix (NaN without a fix)"},
                            {"residual_deg", "measured − fix"},
                            {"alpha_s_deg", "W16's α_S, clockwise seen from above: −atan2(s_y, s_x), [0°, 360°)"},
                            {"beta_deg", "the sun's geographic azimuth β at the fix"},
                            {"heading_deg", "ψ = β − α_S (Eq. 18): the geographic azimuth of X_l"},
                            {"heading_true_deg", "the true heading given (NaN without one)"},
                            {"heading_error_deg", "heading − truth, [−180°, 180°)"},
                            {"heading_mean_deg", "circular mean of the headings (weighted)"},
                            {"heading_sd_deg", "RMS deviation of the headings from their mean"}});
  bind_record<PositioningTrialsTag>(m, "PositioningTrials", "study_positioning's trials.csv columns, one element per trial.",
      {{"cell", "the trial's cell (summary.csv's row)"},
       {"factor", "the cell's sweep: window, noise or tilt"},
       {"window_s", "the cell's window length, s"},
       {"noise_sd_deg", "the cell's zenith-angle noise SD, degrees"},
       {"tilt_deg", "the cell's levelling error, degrees"},
       {"trial", "the trial's index in its cell (its random streams)"},
       {"tilt_azimuth_deg", "the azimuth the axis tilts towards (clockwise from north)"},
       {"prior_lat_deg", "the fit's prior latitude"},
       {"prior_lon_deg", "the fit's prior longitude"},
       {"lat_deg", "the fix's latitude (the chosen root)"},
       {"lon_deg", "the fix's longitude"},
       {"error_km", "great-circle distance from the truth, km"},
       {"north_km", "the error's north component, km"},
       {"east_km", "the error's east component, km"},
       {"termination", "how the fit ended (converged, ...)"},
       {"iterations", "Jacobian evaluations of the fit"},
       {"residual_rms_deg", "the fit's residual RMS, degrees"},
       {"sd_major_km", "the fit's own 1σ ellipse semi-major axis, km"}});
  bind_record<PositioningStudyTag>(m, "PositioningStudy",
      "`polrig study positioning`'s summary.csv columns, one element per cell, and .trials (trials.csv).",
      {{"cell", "the cell's index"},
       {"factor", "the sweep: window, noise or tilt"},
       {"window_s", "the window's length, s"},
       {"noise_sd_deg", "the zenith-angle noise SD, degrees"},
       {"tilt_deg", "the levelling error, degrees"},
       {"correlation_s", "the noise's correlation time, s (0: white)"},
       {"sightings", "sightings in the window"},
       {"delta_beta_deg", "the sun's azimuth change over the window, degrees"},
       {"trials_per_cell", "trials run (the CSV's 'trials' column)"},
       {"converged", "trials whose fit converged"},
       {"rms_km", "RMS position error over the converged trials, km"},
       {"mean_km", "mean position error, km"},
       {"p50_km", "median position error, km"},
       {"p95_km", "95th percentile of the position error, km"},
       {"max_km", "largest position error, km"},
       {"mean_north_km", "mean north error (bias), km"},
       {"mean_east_km", "mean east error (bias), km"},
       {"eq15_km", "Eq. 15 for the window's first and last sightings, ε = √(σ² + τ²), km"},
       {"linear_rms_km", "the linearized least-squares RMS error √trace(P·Σ·Pᵀ), km"},
       {"mirror_km", "W16's M′: the window's noise-free mirror root's distance from the truth, km (NaN: none found)"},
       {"wrong_root", "converged trials whose fix is nearer M′ than the truth"},
       {"trials", "polrig.PositioningTrials: trials.csv"}});

  m.def("two_sighting_error", [](double eps_a, double eps_b, double az_a, double az_b) {
        const TwoSightingError e = two_sighting_error(eps_a, eps_b, az_a, az_b);
        return py::make_tuple(e.angle_deg, e.km);
      }, "eps_gamma_a_deg"_a, "eps_gamma_b_deg"_a, "azimuth_a_deg"_a, "azimuth_b_deg"_a,
      "W16 Eq. 15, the two-sighting fix error: ε_M = √(ε_γA² + ε_γB²)/|sin(α_A − α_B)|. Returns "
      "(angle_deg, km) at W16's 111.32 km/° (inf when the azimuths coincide mod 180°). Raises "
      "ValueError for a negative or non-finite error. Check: (0.14, 0.14, 215, 200) → (0.765, 85.2).");

  m.def("fix_position", [](const py::object& utc, const ArrayLike& zenith_deg, const py::object& prior,
                           const py::object& weight, bool refraction, double ut1_minus_utc_s,
                           bool second_root, const py::object& truth) {
        const std::vector<ZenithSighting> z = zenith_sightings(utc, as_array(zenith_deg.obj, "zenith_deg", 1), weight);
        const Site p = site_of(prior, "prior");
        const std::optional<Site> t = truth.is_none() ? std::nullopt : std::optional<Site>(site_of(truth, "truth"));
        const PositionOptions o = options_of(refraction, ut1_minus_utc_s, second_root);
        PositionFix fix;
        {
          py::gil_scoped_release release;
          fix = fix_position(z, p, o);
        }
        return fix_record(fix, t);
      }, "utc"_a, "zenith_deg"_a, "prior"_a, py::kw_only(), "weight"_a = py::none(), "refraction"_a = false,
      "ut1_minus_utc_s"_a = 0.0, "second_root"_a = true, "truth"_a = py::none(),
      "W16 Eq. 17: the site from the sun's zenith angles over a window (compass/positioning.h): "
      "Levenberg–Marquardt from the prior with the analytic Jacobian, the exact topocentric sun of "
      "sky/sun.h re-linearized at each estimate, and the mirror root from a start reflected about "
      "the sun's ground track; the root nearest the prior is chosen.\n\n"
      "utc: times (as polrig.sun_position); zenith_deg: θ_S in [0, 180]°, one per time; prior, "
      "truth: (lat_deg, lon_deg[, height_m]) (the prior's height is the site's); weight: w ≥ 0 per "
      "sighting (None: 1). refraction and ut1_minus_utc_s ([-1, 1] s) as the data's sun. A window "
      "that cannot fix the site is a termination, not an error. Returns polrig.PositionFix.");

  m.def("locate", [](const py::object& utc, const ArrayLike& sun_camera, const py::object& prior,
                     const py::object& weight, bool refraction, double ut1_minus_utc_s, bool second_root,
                     const py::object& truth, const py::object& true_heading_deg) {
        const std::vector<UtcTime> t = utc_times(utc, "utc");
        const DoubleArray s = as_array(sun_camera.obj, "sun_camera", 2, 3);
        const std::vector<double> sv = finite_values(s, "sun_camera");
        if (static_cast<std::size_t>(s.shape(0)) != t.size())
          throw py::value_error(fmt::format("sun_camera: {} vectors for {} times", s.shape(0), t.size()));
        std::vector<double> w(t.size(), 1.0);
        if (!weight.is_none()) {
          w = finite_values(as_array(weight, "weight", 1), "weight");
          if (w.size() != t.size()) throw py::value_error(fmt::format("weight: {} values for {} times", w.size(), t.size()));
        }
        std::vector<double> truth_h(t.size(), NAN);
        if (!true_heading_deg.is_none()) {
          const DoubleArray a = as_array(true_heading_deg, "true_heading_deg", 1);
          if (static_cast<std::size_t>(a.size()) != t.size())
            throw py::value_error(fmt::format("true_heading_deg: {} values for {} times", a.size(), t.size()));
          truth_h.assign(a.data(), a.data() + a.size());
        }
        std::vector<SunSighting> in(t.size());
        for (std::size_t k = 0; k < t.size(); ++k) in[k] = {t[k], {sv[3 * k], sv[3 * k + 1], sv[3 * k + 2]}, w[k]};
        const Site p = site_of(prior, "prior");
        const std::optional<Site> tr = truth.is_none() ? std::nullopt : std::optional<Site>(site_of(truth, "truth"));
        const PositionOptions o = options_of(refraction, ut1_minus_utc_s, second_root);
        Location loc;
        {
          py::gil_scoped_release release;
          loc = locate(in, p, o);
        }
        return location_record(loc, tr, truth_h);
      }, "utc"_a, "sun_camera"_a, "prior"_a, py::kw_only(), "weight"_a = py::none(), "refraction"_a = false,
      "ut1_minus_utc_s"_a = 0.0, "second_root"_a = true, "truth"_a = py::none(),
      "true_heading_deg"_a = py::none(),
      "The locate core (compass/positioning.h): sun vectors of a LEVEL camera (frame l: Z_l up, X_l, Y_l "
      "anticlockwise seen from above; any length > 0), shape (N, 3), at N times → θ_S per sighting, "
      "the Eq. 17 fix (fix_position), and at the fix the sun's azimuth β and the heading ψ = β − α_S "
      "with W16's clockwise α_S = −atan2(s_y, s_x) (Eq. 18). truth, true_heading_deg: optional, for "
      "the error columns. Returns polrig.Location (heading.csv's columns and .fix).");

  m.def("locate_dataset", [](const std::string& dir, const py::object& prior, bool dop_weighting,
                             bool correct_noise_bias, const std::optional<std::string>& calibration) {
        const Site p = site_of(prior, "prior");
        OrientationSettings orientation;
        orientation.dop_weighting = dop_weighting;
        orientation.correct_noise_bias = correct_noise_bias;
        DatasetLocation run;
        {
          py::gil_scoped_release release;
          std::optional<FourCameraModel> model;
          if (calibration) model = read_four_camera_model(*calibration);
          run = locate_four_camera_folder(dir, p, orientation, {}, {}, model);
        }
        return location_record(run.location, run.truth, run.true_heading_deg);
      }, "dir"_a, "prior"_a, py::kw_only(), "dop_weighting"_a = false, "correct_noise_bias"_a = false,
      "calibration"_a = py::none(),
      "`polrig locate DIR --prior LAT,LON`: per stop of a four-camera dataset the sun vector by the "
      "eigenvector method over the fused AoP (dop_weighting: EEᵀ weighted by DoP; correct_noise_bias: "
      "the noise-bias correction, docs/physics.md §15), then locate() over "
      "the stops with a sun; the truth and the true headings from the dataset (a simulated one). calibration: a "
      "calibration.yaml (`--calibration`): each stop's raw frames (--layers all) re-fused with its model instead of "
      "the dataset's fused layers. Returns polrig.Location, whose columns are the CLI's heading.csv and .fix its "
      "fix.csv.");

  rig_class(m).def("study_positioning", [](const PyRig& rig, const py::object& windows_s,
                                           std::vector<double> noise_sd_deg, std::vector<double> tilt_deg,
                                           double baseline_noise_sd_deg, double baseline_tilt_deg,
                                           double correlation_s, double prior_offset_km, int trials,
                                           const py::object& seed, bool second_root,
                                           std::optional<int> threads, const py::object& progress) {
        const std::optional<Sky> sky = rig_sky(rig.rig());
        if (!sky) throw RigError(no_sky_message(rig.rig(), rig.loaded.origin));
        PositioningStudySettings s;
        s.site = sky->site;
        s.first = sky->first_stop;
        s.sun = sky->sun;
        s.times_s = rig.rig().schedule.stop_times_s();
        s.seed = seed.is_none() ? rig.rig().seed : seed.cast<std::uint64_t>();
        if (!windows_s.is_none()) s.windows_s = windows_s.cast<std::vector<double>>();
        s.noise_sd_deg = std::move(noise_sd_deg);
        s.tilt_deg = std::move(tilt_deg);
        s.baseline_noise_sd_deg = baseline_noise_sd_deg;
        s.baseline_tilt_deg = baseline_tilt_deg;
        s.correlation_s = correlation_s;
        s.prior_offset_km = prior_offset_km;
        s.trials = trials;
        s.second_root = second_root;
        check_positioning_study_settings(s);
        const Progress p = progress_from(progress);
        ThreadLimit limit(threads);
        PositioningStudy study;
        {
          py::gil_scoped_release release;
          study = positioning_study(s, p);
        }
        const auto cells = [&](auto get) {
          std::vector<double> v;
          for (std::size_t i = 0; i < study.cells.size(); ++i) v.push_back(get(study.cells[i], study.stats[i]));
          return take(std::move(v));
        };
        const auto per_trial = [&](auto get) {
          std::vector<double> v;
          for (const PositioningTrial& t : study.trials) v.push_back(get(t, study.cells[static_cast<std::size_t>(t.cell)]));
          return take(std::move(v));
        };
        std::vector<std::string> factor, trial_factor, termination;
        for (const PositioningCell& c : study.cells) factor.push_back(c.factor);
        for (const PositioningTrial& t : study.trials) {
          trial_factor.push_back(study.cells[static_cast<std::size_t>(t.cell)].factor);
          termination.emplace_back(position_termination_name(t.termination));
        }
        using C = const PositioningCell&;
        using S = const PositioningStats&;
        using T = const PositioningTrial&;
        Record tr;
        tr.add("cell", per_trial([](T t, C) { return t.cell; }));
        tr.add("factor", strings(trial_factor));
        tr.add("window_s", per_trial([](T, C c) { return c.window_s; }));
        tr.add("noise_sd_deg", per_trial([](T, C c) { return c.noise_sd_deg; }));
        tr.add("tilt_deg", per_trial([](T, C c) { return c.tilt_deg; }));
        tr.add("trial", per_trial([](T t, C) { return t.trial; }));
        tr.add("tilt_azimuth_deg", per_trial([](T t, C) { return t.tilt_azimuth_deg; }));
        tr.add("prior_lat_deg", per_trial([](T t, C) { return t.prior_lat_deg; }));
        tr.add("prior_lon_deg", per_trial([](T t, C) { return t.prior_lon_deg; }));
        tr.add("lat_deg", per_trial([](T t, C) { return t.lat_deg; }));
        tr.add("lon_deg", per_trial([](T t, C) { return t.lon_deg; }));
        tr.add("error_km", per_trial([](T t, C) { return t.error_km; }));
        tr.add("north_km", per_trial([](T t, C) { return t.north_km; }));
        tr.add("east_km", per_trial([](T t, C) { return t.east_km; }));
        tr.add("termination", strings(termination));
        tr.add("iterations", per_trial([](T t, C) { return t.iterations; }));
        tr.add("residual_rms_deg", per_trial([](T t, C) { return t.residual_rms_deg; }));
        tr.add("sd_major_km", per_trial([](T t, C) { return t.sd_major_km; }));
        Record r;
        r.add("cell", cells([](C c, S) { return c.index; }));
        r.add("factor", strings(factor));
        r.add("window_s", cells([](C c, S) { return c.window_s; }));
        r.add("noise_sd_deg", cells([](C c, S) { return c.noise_sd_deg; }));
        r.add("tilt_deg", cells([](C c, S) { return c.tilt_deg; }));
        r.add("correlation_s", cells([&](C, S) { return study.settings.correlation_s; }));
        r.add("sightings", cells([](C c, S) { return c.sightings; }));
        r.add("delta_beta_deg", cells([](C c, S) { return c.delta_beta_deg; }));
        r.add("trials_per_cell", cells([](C, S st) { return st.trials; }));
        r.add("converged", cells([](C, S st) { return st.converged; }));
        r.add("rms_km", cells([](C, S st) { return st.rms_km; }));
        r.add("mean_km", cells([](C, S st) { return st.mean_km; }));
        r.add("p50_km", cells([](C, S st) { return st.p50_km; }));
        r.add("p95_km", cells([](C, S st) { return st.p95_km; }));
        r.add("max_km", cells([](C, S st) { return st.max_km; }));
        r.add("mean_north_km", cells([](C, S st) { return st.mean_north_km; }));
        r.add("mean_east_km", cells([](C, S st) { return st.mean_east_km; }));
        r.add("eq15_km", cells([](C c, S) { return c.eq15_km; }));
        r.add("linear_rms_km", cells([](C c, S) { return c.linear_rms_km; }));
        r.add("mirror_km", cells([](C c, S) { return c.mirror_km; }));
        r.add("wrong_root", cells([](C, S st) { return st.wrong_root; }));
        r.add("trials", py::cast(RecordOf<PositioningTrialsTag>(std::move(tr))));
        return RecordOf<PositioningStudyTag>(std::move(r));
      }, py::kw_only(), "windows_s"_a = py::none(),
      "noise_sd_deg"_a = std::vector<double>{0, 0.02, 0.05, 0.14, 0.3, 0.5},
      "tilt_deg"_a = std::vector<double>{0, 0.02, 0.05, 0.1, 0.2}, "baseline_noise_sd_deg"_a = 0.14,
      "baseline_tilt_deg"_a = 0.0, "correlation_s"_a = 0.0, "prior_offset_km"_a = 100.0, "trials"_a = 100,
      "seed"_a = py::none(), "second_root"_a = false, "threads"_a = py::none(), "progress"_a = py::none(),
      (std::string("`polrig study positioning`: Monte-Carlo of the Eq. 17 fix against the window, the "
                   "zenith-angle noise and the levelling error (study/positioning.h), beside Eq. 15 and "
                   "the linearized least-squares error; bit for bit summary.csv and trials.csv, the "
                   "same for any thread count. The rig's sky gives the truth (site), the first stop and "
                   "the sun's settings, its stop times the window. windows_s: None (the span × 1/60 … 1) "
                   "or lengths in (0, span] s; noise_sd_deg, tilt_deg: lists in [0, 10]°; "
                   "correlation_s in [0, 1e5] s (0: white noise); prior_offset_km in [0, 2000]; trials "
                   "in [1, 1e6]; seed: None (the rig's). Raises ValueError naming a setting out of "
                   "range, RigError for a rig without a sky.\n") +
       kThreadsDoc + "\n" + kProgressDoc + "\nReturns polrig.PositioningStudy.").c_str());
}

}  // namespace polrig::python
