// polrig.heading (the W19 compass over arrays), solve_heading, the forward model sky_view_body and
// study_heading (docs/python.md §6). Frames and senses are compass/heading.h's (spec
// sky-and-compasses.md §0): ENU; body X right, Y forward, Z up; θ_b from X_b towards Y_b
// (anticlockwise seen from above); heading clockwise from north seen from above; pitch nose up,
// roll right side down positive.
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <pybind11/stl.h>

#include "bindings.h"
#include "convert.h"
#include "polrig/compass/heading.h"
#include "polrig/compass/heading_rows.h"
#include "polrig/study/heading_trials.h"
#include "records.h"
#include "rig_handle.h"
#include "sky_args.h"

namespace polrig::python {
using namespace pybind11::literals;

namespace {

struct HeadingTag {};
struct BodySkyViewTag {};
struct HeadingTrialsTag {};
struct HeadingSummaryTag {};
struct HeadingCdfTag {};

constexpr HeadingStatus kStatuses[] = {HeadingStatus::Ok, HeadingStatus::Clamped,
                                       HeadingStatus::SunNearZenithOrVerticalE,
                                       HeadingStatus::Inconsistent};

std::int8_t status_code(HeadingStatus s) {
  for (std::size_t i = 0; i < std::size(kStatuses); ++i)
    if (kStatuses[i] == s) return static_cast<std::int8_t>(i);
  return -1;
}

py::tuple status_names() {
  py::tuple t(std::size(kStatuses));
  for (std::size_t i = 0; i < std::size(kStatuses); ++i)
    t[i] = py::str(std::string(heading_status_name(kStatuses[i])));
  return t;
}

HeadingSettings heading_settings(double min_horizontal, double tangent_tolerance) {
  check_option(min_horizontal, "min_horizontal", 0, 1, "");
  check_option(tangent_tolerance, "tangent_tolerance", 0, 1, "");
  return {min_horizontal, tangent_tolerance};
}

RecordOf<HeadingSummaryTag> summary_record(const std::vector<HeadingErrorStats>& rows) {
  const py::module_ np = py::module_::import("numpy");
  py::list factor, error;
  std::vector<double> lo, hi, mean, rms, p50, p95, max;
  std::vector<std::int64_t> trials, solved;
  for (const HeadingErrorStats& s : rows) {
    factor.append(s.factor), error.append(s.error);
    lo.push_back(s.bin_lo), hi.push_back(s.bin_hi), trials.push_back(s.trials), solved.push_back(s.solved);
    mean.push_back(s.mean_deg), rms.push_back(s.rms_deg), p50.push_back(s.p50_abs_deg);
    p95.push_back(s.p95_abs_deg), max.push_back(s.max_abs_deg);
  }
  Record r;
  r.add("factor", np.attr("array")(factor, "dtype"_a = "object"));
  r.add("error", np.attr("array")(error, "dtype"_a = "object"));
  r.add("bin_lo", take(std::move(lo)));
  r.add("bin_hi", take(std::move(hi)));
  r.add("trials", take(std::move(trials)));
  r.add("solved", take(std::move(solved)));
  r.add("mean_deg", take(std::move(mean)));
  r.add("rms_deg", take(std::move(rms)));
  r.add("p50_abs_deg", take(std::move(p50)));
  r.add("p95_abs_deg", take(std::move(p95)));
  r.add("max_abs_deg", take(std::move(max)));
  return RecordOf<HeadingSummaryTag>(std::move(r));
}

RecordOf<HeadingCdfTag> cdf_record(HeadingErrorCdf c) {
  Record r;
  r.add("fraction", take(std::move(c.fraction)));
  const char* names[] = {"all_deg", "sync_deg", "ins_tilt_deg", "mount_deg", "noise_deg"};
  for (std::size_t m = 0; m < c.abs_error_deg.size(); ++m) r.add(names[m], take(std::move(c.abs_error_deg[m])));
  return RecordOf<HeadingCdfTag>(std::move(r));
}

constexpr const char* kFrames =
    "Frames and senses (compass/heading.h, spec sky-and-compasses.md §0): ENU (x east, y north, z "
    "up); body X right, Y forward, Z up, the sensor looking along +Z_b; heading clockwise from "
    "north seen from above; roll γ right side down positive; pitch λ nose up positive; θ_b (aop) "
    "from X_b towards Y_b, anticlockwise seen from above, axial (mod 180°).";

}  // namespace

void bind_compass(py::module_& m) {
  m.attr("HEADING_STATUS") = status_names();

  py::class_<HeadingSolution>(m, "HeadingSolution",
                              "One solve of W19 Eq. 25 (compass/heading.h): both roots and the choice.")
      .def_property_readonly("status", [](const HeadingSolution& s) {
             return std::string(heading_status_name(s.status));
           }, "'ok', 'clamped', 'sun-near-zenith-or-vertical-e' or 'inconsistent'.")
      .def_property_readonly("status_code", [](const HeadingSolution& s) { return status_code(s.status); },
                             "The status as its index into polrig.HEADING_STATUS (0 ok … 3 inconsistent).")
      .def_readonly("heading_deg", &HeadingSolution::heading_deg,
                    "The chosen root, degrees clockwise from north, [0, 360); NaN without a heading.")
      .def_readonly("heading_alt_deg", &HeadingSolution::heading_alt_deg, "The other root, degrees; NaN without a heading.")
      .def_readonly("a", &HeadingSolution::a, "Eq. 25's coefficient a (a·cos H + b·sin H = c).")
      .def_readonly("b", &HeadingSolution::b, "Eq. 25's coefficient b.")
      .def_readonly("c", &HeadingSolution::c, "Eq. 25's coefficient c.")
      .def_readonly("sun_forward", &HeadingSolution::sun_forward,
                    "s_b,y at the chosen root: the sun's component along the body's forward axis.")
      .def_readonly("from_prior", &HeadingSolution::from_prior,
                    "True when the root was chosen as the nearest the prior (else: sun in front).")
      .def("__repr__", [](const HeadingSolution& s) {
        return fmt::format("<polrig.HeadingSolution: status '{}', heading_deg {}, heading_alt_deg {}, "
                           "a {}, b {}, c {}, sun_forward {}, from_prior {}>",
                           heading_status_name(s.status), s.heading_deg, s.heading_alt_deg, s.a,
                           s.b, s.c, s.sun_forward, s.from_prior ? "True" : "False");
      });

  bind_record<HeadingTag>(m, "Headings",
      "`polrig heading`'s added columns, arrays of the broadcast shape S, and the solver's "
      "details.", {
      {"sun_az_deg", "the sun's azimuth, degrees from north towards east, [0, 360)."},
      {"sun_el_deg", "the sun's elevation, degrees."},
      {"heading_deg", "the heading, degrees clockwise from north, [0, 360): the root nearest "
                      "prior_deg, else the one with the sun in front; NaN without a heading (the "
                      "CLI writes nan)."},
      {"heading_alt_deg", "the other root, degrees; NaN without a heading."},
      {"status", "the status as the CLI writes it (heading.csv's status column): 'ok', 'clamped', "
                 "'sun-near-zenith-or-vertical-e' or 'inconsistent', an object array of str."},
      {"status_code", "the status as int8 codes indexing polrig.HEADING_STATUS: 0 ok, 1 clamped, "
                      "2 sun-near-zenith-or-vertical-e, 3 inconsistent."},
      {"a", "Eq. 25's a."},
      {"b", "Eq. 25's b."},
      {"c", "Eq. 25's c."},
      {"sun_forward", "s_b,y at the chosen root (NaN without a heading)."},
      {"from_prior", "bool: chosen as the root nearest the prior."}});
  bind_record<BodySkyViewTag>(m, "BodySkyView",
      "What a sensor looking along +Z_b sees of the single-scattering sky (compass/heading.h).", {
      {"aop_body_deg", "θ_b, degrees, [0, 180), from X_b towards Y_b (anticlockwise seen from "
                       "above); NaN where the view is along the sun's line."},
      {"dop", "degree of linear polarization P(γ)."}});
  bind_record<HeadingTrialsTag>(m, "HeadingTrials",
      "The trials of `polrig study heading` (trials.csv's columns), arrays of shape (trials,); "
      "status as str (the CSV's) and status_code as int8 codes into polrig.HEADING_STATUS.", {
      {"trial", "trial index (int64)."}, {"seed", "the trial's seed (uint64)."},
      {"heading_deg", "true heading at the INS's time, degrees clockwise from north."},
      {"roll_deg", "true roll, degrees, right side down positive."},
      {"pitch_deg", "true pitch, degrees, nose up positive."},
      {"sync_s", "sensor-INS time offset Δt, s."}, {"turn_rate_dps", "turn rate ω, °/s."},
      {"sync_heading_deg", "ω·Δt, degrees."},
      {"ins_roll_error_deg", "INS roll error, degrees."}, {"ins_pitch_error_deg", "INS pitch error, degrees."},
      {"mount_x_deg", "mount tilt about X_b, degrees."}, {"mount_y_deg", "mount tilt about Y_b, degrees."},
      {"mount_tilt_deg", "√(m_x² + m_y²), degrees."}, {"mount_z_deg", "azimuthal mount offset, degrees."},
      {"p_max", "the sky's P_max."}, {"dop", "d at the sensor's axis."},
      {"aop_true_deg", "θ_b from a perfect sensor on a perfect mount, degrees (anticlockwise from above)."},
      {"aop_meas_deg", "θ_b from the noisy voltages, degrees."},
      {"status", "the status as trials.csv writes it, an object array of str."},
      {"status_code", "int8 codes into polrig.HEADING_STATUS."},
      {"heading_est_deg", "estimated heading, degrees; NaN without a solution."},
      {"error_deg", "estimate − truth, [−180, 180) degrees, all factors; NaN without a solution."},
      {"error_sync_deg", "the error from the sync alone."}, {"error_ins_tilt_deg", "from the INS tilt alone."},
      {"error_mount_deg", "from the mount alone."}, {"error_noise_deg", "from the sensor noise alone."},
      {"summary", "polrig.HeadingSummary: summary.csv's columns."},
      {"cdf", "polrig.HeadingCdf: cdf.csv's columns."}});
  bind_record<HeadingSummaryTag>(m, "HeadingSummary",
      "summary.csv of `polrig study heading`: the heading error's statistics overall and for each "
      "factor alone (factor 'all', bins NaN), then the full error in 8 bins of each factor's range "
      "(study/heading_trials.h); NaN where no trial of a row has a heading.", {
      {"factor", "'all' or the binned factor (sync_heading_deg, tilt_deg, mount_tilt_deg, "
                 "mount_z_deg, p_max, dop), object array of str."},
      {"error", "which error: error_deg (all factors) or one factor alone, object array of str."},
      {"bin_lo", "the bin's lower edge in the factor's unit (NaN for 'all')."},
      {"bin_hi", "the bin's upper edge (NaN for 'all')."},
      {"trials", "trials in the row (int64)."}, {"solved", "of which with a heading (int64)."},
      {"mean_deg", "mean error, degrees."}, {"rms_deg", "RMS error, degrees."},
      {"p50_abs_deg", "median |error|, degrees."}, {"p95_abs_deg", "95th percentile of |error|, degrees."},
      {"max_abs_deg", "largest |error|, degrees."}});
  bind_record<HeadingCdfTag>(m, "HeadingCdf",
      "cdf.csv of `polrig study heading`: at fraction (k + ½)/n the k-th smallest |error| of each "
      "column, each sorted on its own; NaN past a column's solved trials.", {
      {"fraction", "(k + ½)/n."}, {"all_deg", "|error| with all factors, degrees."},
      {"sync_deg", "|error| from the sync alone."}, {"ins_tilt_deg", "from the INS tilt alone."},
      {"mount_deg", "from the mount alone."}, {"noise_deg", "from the sensor noise alone."}});

  m.def("heading", [](const py::object& utc, const py::object& lat, const py::object& lon,
                      const py::object& roll, const py::object& pitch, const py::object& aop,
                      const py::object& prior, bool refraction, double ut1_minus_utc_s,
                      double min_horizontal, double tangent_tolerance, std::optional<int> threads,
                      const py::object& progress) {
        SunSettings sun;
        sun.refraction = refraction;
        check_option(ut1_minus_utc_s, "ut1_minus_utc_s", -1, 1, "s");
        sun.ut1_minus_utc_s = ut1_minus_utc_s;
        const HeadingSettings settings = heading_settings(min_horizontal, tangent_tolerance);
        const std::vector<UtcTime> times = utc_times(utc, "utc");
        const py::object no_prior = py::float_(std::numeric_limits<double>::quiet_NaN());
        const Broadcast b = broadcast({{utc_index(utc), "utc"}, {lat, "lat_deg"}, {lon, "lon_deg"},
                                       {roll, "roll_deg"}, {pitch, "pitch_deg"}, {aop, "aop_deg"},
                                       {prior.is_none() ? no_prior : prior, "prior_deg", true}});
        const char* inputs[] = {"utc", "lat_deg", "lon_deg", "roll_deg", "pitch_deg", "aop_deg", "prior_deg"};
        for (std::size_t k = 1; k <= 5; ++k) check_input(b.values[k], inputs[k], heading_query_range(inputs[k]));
        check_input(b.values[6], "prior_deg", heading_query_range("prior_deg"),
                    "degrees clockwise from north; NaN for none");
        std::vector<HeadingQuery> queries(b.size);
        for (std::size_t i = 0; i < b.size; ++i) {
          HeadingQuery& q = queries[i];
          q.at = {times[static_cast<std::size_t>(b.values[0][i])], {b.values[1][i], b.values[2][i], 0}};
          q.tilt = {b.values[3][i], b.values[4][i]};
          q.aop_deg = b.values[5][i];
          if (!std::isnan(b.values[6][i])) q.prior_deg = b.values[6][i];
        }
        const Progress p = progress_from(progress);
        ThreadLimit limit(threads);
        std::vector<HeadingSample> samples;
        {
          py::gil_scoped_release release;
          try {
            samples = headings_along(queries, sun, settings, p);
          } catch (const SunRowError& e) {
            throw py::value_error(fmt::format("utc (element {}): {}", e.row, e.what()));
          }
        }
        const std::size_t n = samples.size();
        std::vector<double> az(n), el(n), h(n), h2(n), a(n), bb(n), c(n), fwd(n);
        std::vector<std::int8_t> status(n);
        std::vector<bool> from_prior(n);
        py::list names_list;
        const py::tuple names = status_names();
        for (std::size_t i = 0; i < n; ++i) {
          const HeadingSample& s = samples[i];
          az[i] = s.sun.azimuth_deg, el[i] = s.sun.elevation_deg;
          h[i] = s.solution.heading_deg, h2[i] = s.solution.heading_alt_deg;
          a[i] = s.solution.a, bb[i] = s.solution.b, c[i] = s.solution.c;
          fwd[i] = s.solution.sun_forward;
          status[i] = status_code(s.solution.status);
          from_prior[i] = s.solution.from_prior;
        }
        const py::module_ np = py::module_::import("numpy");
        const py::array_t<std::int8_t> codes = take(std::move(status), b.shape);
        py::array_t<bool> prior_flags(b.shape);
        for (std::size_t i = 0; i < n; ++i) prior_flags.mutable_data()[i] = from_prior[i];
        Record r;
        r.add("sun_az_deg", take(std::move(az), b.shape));
        r.add("sun_el_deg", take(std::move(el), b.shape));
        r.add("heading_deg", take(std::move(h), b.shape));
        r.add("heading_alt_deg", take(std::move(h2), b.shape));
        r.add("status", np.attr("array")(names, "dtype"_a = "object")[codes]);
        r.add("status_code", codes);
        r.add("a", take(std::move(a), b.shape));
        r.add("b", take(std::move(bb), b.shape));
        r.add("c", take(std::move(c), b.shape));
        r.add("sun_forward", take(std::move(fwd), b.shape));
        r.add("from_prior", prior_flags);
        return RecordOf<HeadingTag>(std::move(r));
      }, "utc"_a, "lat_deg"_a, "lon_deg"_a, "roll_deg"_a, "pitch_deg"_a, "aop_deg"_a, py::kw_only(),
      "prior_deg"_a = py::none(), "refraction"_a = false, "ut1_minus_utc_s"_a = 0.0,
      "min_horizontal"_a = HeadingSettings{}.min_horizontal,
      "tangent_tolerance"_a = HeadingSettings{}.tangent_tolerance, "threads"_a = py::none(),
      "progress"_a = py::none(),
      (std::string("`polrig heading`: the heading from the sky's E-vector, the attitude and the sun "
                   "(W19 Eqs. 22-25) for every row, bit for bit the values of its heading.csv.\n\n") +
       kFrames +
       "\n\nutc: times (ISO strings with Z, aware datetimes, numpy.datetime64); lat_deg in [-90, "
       "90], lon_deg in [-180, 180]; roll_deg in [-180, 180]; pitch_deg in [-90, 90]; aop_deg θ_b "
       "in [-360, 360]; prior_deg: None, or headings in [-360, 360] (degrees clockwise from north; "
       "NaN for none: the root nearest it is chosen, else the one with the sun in front). All "
       "broadcast to the result's shape S.\n"
       "refraction, ut1_minus_utc_s ([-1, 1] s): the sun's settings. min_horizontal, "
       "tangent_tolerance: HeadingSettings (compass/heading.h; the CLI uses the defaults).\n" +
       kThreadsDoc + "\n" + kProgressDoc +
       "\nReturns polrig.Headings: sun_az_deg, sun_el_deg, heading_deg, heading_alt_deg (NaN "
       "without a heading), status (str, the CSV's), status_code (int8 codes into "
       "polrig.HEADING_STATUS), a, b, c, "
       "sun_forward, from_prior, each of shape S. The sun of a row is exact when few rows share "
       "its site and interpolated along a SunTrack (sky/sun_rows.h) when many do, so a row's sun "
       "may differ by ~1e-8° depending on how many rows share the call.").c_str());

  m.def("solve_heading", [](const py::object& sun_enu, double aop_body_deg, double roll_deg,
                            double pitch_deg, std::optional<double> prior_deg, double min_horizontal,
                            double tangent_tolerance) {
        const std::vector<double> s = finite_values(as_array(sun_enu, "sun_enu", 1, 3), "sun_enu");
        for (auto [v, name] : {std::pair{aop_body_deg, "aop_body_deg"}, {roll_deg, "roll_deg"},
                               {pitch_deg, "pitch_deg"}})
          if (!std::isfinite(v)) throw py::value_error(fmt::format("{}: {} is not finite", name, v));
        if (prior_deg && !std::isfinite(*prior_deg))
          throw py::value_error(fmt::format("prior_deg: {} is not finite", *prior_deg));
        return solve_heading({s[0], s[1], s[2]}, aop_body_deg, {roll_deg, pitch_deg}, prior_deg,
                             heading_settings(min_horizontal, tangent_tolerance));
      }, "sun_enu"_a, "aop_body_deg"_a, "roll_deg"_a = 0.0, "pitch_deg"_a = 0.0,
      "prior_deg"_a = py::none(), py::kw_only(),
      "min_horizontal"_a = HeadingSettings{}.min_horizontal,
      "tangent_tolerance"_a = HeadingSettings{}.tangent_tolerance,
      (std::string("Solves W19 Eq. 25 once (compass/heading.h's solve_heading): a·cos H + b·sin H = c.\n\n") +
       kFrames +
       "\n\nsun_enu: the unit vector to the sun in ENU, shape (3,) (e.g. Sky.sun().enu), its length within 1e-9 of 1; "
       "aop_body_deg: θ_b, degrees; roll_deg, pitch_deg: the tilt, degrees; prior_deg: None or a "
       "heading (degrees clockwise from north) whose nearest root is chosen.\n"
       "Returns polrig.HeadingSolution (a status, never an exception, when there is no heading).\n"
       "Raises ValueError for a sun_enu whose length is not 1 within 1e-9 or a non-finite argument.").c_str());

  m.def("sky_view_body", [](const py::object& sun_enu, const py::object& heading_deg,
                            const py::object& roll_deg, const py::object& pitch_deg, double p_max) {
        const DoubleArray s = as_array(sun_enu, "sun_enu", 0, 3);
        const auto comp = [&](int k) { return s.attr("__getitem__")(py::make_tuple(py::ellipsis(), k)); };
        const Broadcast b = broadcast({{comp(0), "sun_enu[..., 0]"}, {comp(1), "sun_enu[..., 1]"},
                                       {comp(2), "sun_enu[..., 2]"}, {heading_deg, "heading_deg"},
                                       {roll_deg, "roll_deg"}, {pitch_deg, "pitch_deg"}});
        SkyModel model;
        check_option(p_max, "p_max", 1e-6, 1.0, "");
        model.P_max.constant = p_max;
        std::vector<double> aop(b.size), dop(b.size);
        {
          py::gil_scoped_release release;
          for (std::size_t i = 0; i < b.size; ++i) {
            const BodySkyView v = sky_view_body({b.values[0][i], b.values[1][i], b.values[2][i]},
                                                b.values[3][i], {b.values[4][i], b.values[5][i]}, model);
            aop[i] = v.aop_body_deg, dop[i] = v.dop;
          }
        }
        Record r;
        r.add("aop_body_deg", take(std::move(aop), b.shape));
        r.add("dop", take(std::move(dop), b.shape));
        return RecordOf<BodySkyViewTag>(std::move(r));
      }, "sun_enu"_a, "heading_deg"_a, "roll_deg"_a = 0.0, "pitch_deg"_a = 0.0, py::kw_only(),
      "p_max"_a = 0.7,
      (std::string("The forward model (compass/heading.h's sky_view_body): the E-vector angle θ_b and "
                   "the degree of polarization a sensor looking along +Z_b sees of the "
                   "single-scattering sky, vectorised.\n\n") +
       kFrames +
       "\n\nsun_enu: unit vectors to the sun in ENU, shape (..., 3), each of length 1 within 1e-9 (else ValueError); heading_deg (clockwise from "
       "north), roll_deg, pitch_deg: degrees; the leading shape of sun_enu and the others "
       "broadcast to S. p_max in (0, 1] (the radiance model does not enter: AoP and DoP do not depend on it).\n"
       "Returns polrig.BodySkyView: aop_body_deg in [0, 180) (NaN where the view lies along the "
       "sun's line) and dop, shape S. solve_heading inverts it.").c_str());

  rig_class(m).def("study_heading", [](const PyRig& rig, int trials, const py::object& site, const py::object& utc,
                            std::optional<bool> refraction, std::optional<double> ut1_minus_utc_s,
                            double roll_sd, double pitch_sd, double sync_max, double turn_rate_max,
                            double ins_tilt_sd, double mount_tilt_sd, double mount_azimuth_sd,
                            double p_max_min, double p_max_max, int samples,
                            std::optional<int> threads, const py::object& progress) {
        require(rig, Instrument::kPairVoltages, "study heading");
        HeadingStudySettings s;
        s.trials = trials;
        s.samples = samples;
        s.roll_sd_deg = roll_sd, s.pitch_sd_deg = pitch_sd, s.sync_max_s = sync_max;
        s.turn_rate_max_dps = turn_rate_max, s.ins_tilt_sd_deg = ins_tilt_sd;
        s.mount_tilt_sd_deg = mount_tilt_sd, s.mount_azimuth_sd_deg = mount_azimuth_sd;
        s.p_max_min = p_max_min, s.p_max_max = p_max_max;
        check_heading_study_settings(s);
        // The run's site, time and sun: a sky rig's sky block, else W19's dynamic run; an
        // argument given overrides either (as the CLI's options).
        use_rig_sky(rig.rig(), s);
        if (refraction) s.sun.refraction = *refraction;
        if (ut1_minus_utc_s) {
          check_option(*ut1_minus_utc_s, "ut1_minus_utc_s", -1, 1, "s");
          s.sun.ut1_minus_utc_s = *ut1_minus_utc_s;
        }
        if (!site.is_none()) s.site = site_of(site, "site");
        if (!utc.is_none()) s.utc = utc_time(utc, "utc");
        const Progress p = progress_from(progress);
        ThreadLimit limit(threads);
        std::vector<HeadingTrial> result;
        std::vector<HeadingErrorStats> summary;
        HeadingErrorCdf cdf;
        {
          py::gil_scoped_release release;
          result = heading_trials(rig.rig(), s, p);
          summary = summarize_heading_trials(result);
          cdf = heading_error_cdf(result);
        }
        const std::size_t n = result.size();
        std::vector<std::int64_t> index(n);
        std::vector<std::uint64_t> seed(n);
        std::vector<std::int8_t> status(n);
        using Get = double (*)(const HeadingTrial&);
        const std::vector<std::pair<const char*, Get>> before{
            {"heading_deg", [](const HeadingTrial& t) { return t.heading_deg; }},
            {"roll_deg", [](const HeadingTrial& t) { return t.roll_deg; }},
            {"pitch_deg", [](const HeadingTrial& t) { return t.pitch_deg; }},
            {"sync_s", [](const HeadingTrial& t) { return t.sync_s; }},
            {"turn_rate_dps", [](const HeadingTrial& t) { return t.turn_rate_dps; }},
            {"sync_heading_deg", [](const HeadingTrial& t) { return t.sync_heading_deg(); }},
            {"ins_roll_error_deg", [](const HeadingTrial& t) { return t.ins_roll_error_deg; }},
            {"ins_pitch_error_deg", [](const HeadingTrial& t) { return t.ins_pitch_error_deg; }},
            {"mount_x_deg", [](const HeadingTrial& t) { return t.mount_x_deg; }},
            {"mount_y_deg", [](const HeadingTrial& t) { return t.mount_y_deg; }},
            {"mount_tilt_deg", [](const HeadingTrial& t) { return t.mount_tilt_deg(); }},
            {"mount_z_deg", [](const HeadingTrial& t) { return t.mount_z_deg; }},
            {"p_max", [](const HeadingTrial& t) { return t.p_max; }},
            {"dop", [](const HeadingTrial& t) { return t.dop; }},
            {"aop_true_deg", [](const HeadingTrial& t) { return t.aop_true_deg; }},
            {"aop_meas_deg", [](const HeadingTrial& t) { return t.aop_meas_deg; }}};
        const std::vector<std::pair<const char*, Get>> after{
            {"heading_est_deg", [](const HeadingTrial& t) { return t.heading_est_deg; }},
            {"error_deg", [](const HeadingTrial& t) { return t.error_deg; }},
            {"error_sync_deg", [](const HeadingTrial& t) { return t.error_sync_deg; }},
            {"error_ins_tilt_deg", [](const HeadingTrial& t) { return t.error_ins_tilt_deg; }},
            {"error_mount_deg", [](const HeadingTrial& t) { return t.error_mount_deg; }},
            {"error_noise_deg", [](const HeadingTrial& t) { return t.error_noise_deg; }}};
        const auto column = [&](Get get) {
          std::vector<double> v(n);
          for (std::size_t i = 0; i < n; ++i) v[i] = get(result[i]);
          return take(std::move(v));
        };
        for (std::size_t i = 0; i < n; ++i) {
          index[i] = result[i].index;
          seed[i] = result[i].seed;
          status[i] = status_code(result[i].status);
        }
        const py::module_ np = py::module_::import("numpy");
        const py::array_t<std::int8_t> codes = take(std::move(status));
        Record r;
        r.add("trial", take(std::move(index)));
        r.add("seed", take(std::move(seed)));
        for (const auto& [name, get] : before) r.add(name, column(get));
        r.add("status", np.attr("array")(status_names(), "dtype"_a = "object")[codes]);
        r.add("status_code", codes);
        for (const auto& [name, get] : after) r.add(name, column(get));
        r.add("summary", py::cast(summary_record(summary)));
        r.add("cdf", py::cast(cdf_record(std::move(cdf))));
        return RecordOf<HeadingTrialsTag>(std::move(r));
      }, py::kw_only(), "trials"_a = 1000, "site"_a = py::none(), "utc"_a = py::none(),
      "refraction"_a = py::none(), "ut1_minus_utc_s"_a = py::none(), "roll_sd_deg"_a = 5.0,
      "pitch_sd_deg"_a = 5.0, "sync_max_s"_a = 0.1, "turn_rate_max_dps"_a = 30.0,
      "ins_tilt_sd_deg"_a = 0.015, "mount_tilt_sd_deg"_a = 0.2, "mount_azimuth_sd_deg"_a = 0.05,
      "p_max_min"_a = 0.5, "p_max_max"_a = 0.7, "samples"_a = 1, "threads"_a = py::none(),
      "progress"_a = py::none(),
      (std::string("`polrig study heading`: Monte-Carlo of the heading error of the W19 compass on "
                   "a moving platform (study/heading_trials.h); bit for bit the rows of its "
                   "trials.csv, the same for any thread count.\n\n") +
       kFrames +
       "\n\nThe rig gives the device, electronics and seed; a sky rig's sky block gives the "
       "site, time, refraction and UT1 − UTC. trials in [1, 1e7]. site: (lat_deg, lon_deg[, "
       "height_m]) or None (the rig's sky, else W19's Dalian site); utc: a time or None (the rig's "
       "first stop, else 2019-07-01T11:01:00Z); refraction, ut1_minus_utc_s ([-1, 1] s): None keeps "
       "the rig's. roll_sd_deg, pitch_sd_deg in [0, 30]°; sync_max_s in [0, 10] s; "
       "turn_rate_max_dps in [0, 360] °/s; ins_tilt_sd_deg, mount_tilt_sd_deg, "
       "mount_azimuth_sd_deg in [0, 10]°; p_max_min ≤ p_max_max in [0.05, 1]; samples in [1, "
       "1e5] averaged per heading. Raises ValueError naming a setting out of range.\n" +
       kThreadsDoc + "\n" + kProgressDoc +
       "\nReturns polrig.HeadingTrials: trials.csv's columns as arrays of shape (trials,) (errors "
       "NaN for a trial without a heading), .summary (summary.csv) and .cdf (cdf.csv).").c_str());
}

}  // namespace polrig::python
