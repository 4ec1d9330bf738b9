// Rig.study_sky (docs/python.md): `polrig study sky`'s bias.csv, sky_dop.csv and evector_by_dop.csv
// as NumPy columns. Frames, senses and signs are study/sky_compasses.h's.
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <pybind11/stl.h>

#include "bindings.h"
#include "convert.h"
#include "polrig/rig/error.h"
#include "polrig/rig/rig.h"
#include "polrig/study/sky_compasses.h"
#include "records.h"
#include "rig_handle.h"

namespace polrig::python {
using namespace pybind11::literals;

namespace {

struct SkyStudyTag {};
struct SkyBiasTag {};
struct SkyDopTag {};
struct EvectorByDopTag {};

py::object object_strings(const std::vector<std::string>& v) {
  py::list l;
  for (const std::string& s : v) l.append(py::str(s));
  return py::module_::import("numpy").attr("array")(l, "dtype"_a = "object");
}

// The columns of rows: one array per getter, NaN kept.
template <class Row, class Get>
py::object column(const std::vector<Row>& rows, Get get) {
  std::vector<double> v;
  v.reserve(rows.size());
  for (const Row& r : rows) v.push_back(static_cast<double>(get(r)));
  return take(std::move(v));
}

template <class Row>
void add_sky(Record& r, const std::vector<Row>& rows) {
  std::vector<std::string> names;
  for (const Row& x : rows) names.push_back(x.sky.name());
  r.add("sky", object_strings(names));
  r.add("tau", column(rows, [](const Row& x) { return x.sky.tau; }));
  r.add("albedo", column(rows, [](const Row& x) { return x.sky.albedo; }));
  r.add("sun_el_deg", column(rows, [](const Row& x) { return x.sun_el_deg; }));
}

Record bias_record(const std::vector<SkyBiasRow>& rows) {
  using R = const SkyBiasRow&;
  Record r;
  add_sky(r, rows);
  r.add("tilt_deg", column(rows, [](R x) { return x.tilt_deg; }));
  r.add("heading_deg", column(rows, [](R x) { return x.heading_deg; }));
  std::vector<std::string> method, status;
  for (R x : rows) method.emplace_back(sky_method_name(x.method)), status.push_back(x.status);
  r.add("method", object_strings(method));
  r.add("status", object_strings(status));
  r.add("heading_error_deg", column(rows, [](R x) { return x.heading_error_deg; }));
  r.add("sun_el_error_deg", column(rows, [](R x) { return x.sun_el_error_deg; }));
  r.add("position_line_km", column(rows, [](R x) { return x.position_line_km; }));
  r.add("trials", column(rows, [](R x) { return x.trials; }));
  r.add("solved", column(rows, [](R x) { return x.solved; }));
  r.add("antisun", column(rows, [](R x) { return x.antisun; }));
  r.add("heading_mean_deg", column(rows, [](R x) { return x.heading_mean_deg; }));
  r.add("heading_sd_deg", column(rows, [](R x) { return x.heading_sd_deg; }));
  r.add("sun_el_mean_deg", column(rows, [](R x) { return x.sun_el_mean_deg; }));
  r.add("sun_el_sd_deg", column(rows, [](R x) { return x.sun_el_sd_deg; }));
  r.add("mean_dop", column(rows, [](R x) { return x.mean_dop; }));
  return r;
}

Record dop_record(const std::vector<SkyDopRow>& rows) {
  using R = const SkyDopRow&;
  Record r;
  add_sky(r, rows);
  r.add("zenith_dop", column(rows, [](R x) { return x.zenith_dop; }));
  r.add("max_dop_sky", column(rows, [](R x) { return x.max_dop_sky; }));
  r.add("max_dop_compass", column(rows, [](R x) { return x.max_dop_compass; }));
  r.add("mean_dop_compass", column(rows, [](R x) { return x.mean_dop_compass; }));
  return r;
}

Record evector_record(const std::vector<EvectorByDopRow>& rows) {
  using R = const EvectorByDopRow&;
  Record r;
  add_sky(r, rows);
  r.add("dop_lo", column(rows, [](R x) { return x.dop_lo; }));
  r.add("dop_hi", column(rows, [](R x) { return x.dop_hi; }));
  r.add("cells", column(rows, [](R x) { return x.cells; }));
  r.add("mean_abs_deg", column(rows, [](R x) { return x.mean_abs_deg; }));
  r.add("sd_abs_deg", column(rows, [](R x) { return x.sd_abs_deg; }));
  r.add("rms_deg", column(rows, [](R x) { return x.rms_deg; }));
  r.add("max_abs_deg", column(rows, [](R x) { return x.max_abs_deg; }));
  return r;
}

const std::vector<std::pair<const char*, const char*>> kSkyFields = {
    {"sky", "single-scattering or vector-rt"},
    {"tau", "the vector-RT sky's Rayleigh optical depth (NaN for single scattering)"},
    {"albedo", "the ground's Lambertian albedo (NaN for single scattering)"},
    {"sun_el_deg", "the sun's elevation, degrees"}};

std::vector<std::pair<const char*, const char*>> with_sky(std::vector<std::pair<const char*, const char*>> more) {
  std::vector<std::pair<const char*, const char*>> f = kSkyFields;
  f.insert(f.end(), more.begin(), more.end());
  return f;
}

}  // namespace

void bind_sky_study(py::module_& m) {
  bind_record<SkyBiasTag>(m, "SkyBias", "study_sky's bias.csv columns: one element per sky, sun, attitude and method.",
      with_sky({{"tilt_deg", "the compass's tilt (roll), degrees"},
                {"heading_deg", "its heading relative to the sun's azimuth, degrees"},
                {"method", "published, dop-weighted, min-dop or all-units"},
                {"status", "the noise-free reading's status (the method's, or antisun)"},
                {"heading_error_deg", "the noise-free heading error, estimate − truth, degrees"},
                {"sun_el_error_deg", "the noise-free sun-elevation error, degrees (NaN for one E-vector)"},
                {"position_line_km", "the position line's shift towards the sun, 111.195 km per degree"},
                {"trials", "noisy readings"},
                {"solved", "noisy readings that gave the sun (not the antisun)"},
                {"antisun", "noisy readings whose sign rule took the antisun"},
                {"heading_mean_deg", "the noisy heading errors' mean"},
                {"heading_sd_deg", "their SD"},
                {"sun_el_mean_deg", "the noisy elevation errors' mean"},
                {"sun_el_sd_deg", "their SD"},
                {"mean_dop", "the DoP over the compass's views"}}));
  bind_record<SkyDopTag>(m, "SkyDop", "study_sky's sky_dop.csv columns: one element per sky and sun.",
      with_sky({{"zenith_dop", "the DoP at the zenith"},
                {"max_dop_sky", "the largest DoP over the upper hemisphere's cells"},
                {"max_dop_compass", "the largest DoP over the level compass's views"},
                {"mean_dop_compass", "the mean DoP over them"}}));
  bind_record<EvectorByDopTag>(m, "EvectorByDop",
      "study_sky's evector_by_dop.csv columns: per vector-RT sky, sun and DoP bin, the single-scattering "
      "E-vector's error against the vector-RT sky over the upper hemisphere's cells in the bin.",
      with_sky({{"dop_lo", "the bin's lower DoP"}, {"dop_hi", "its upper DoP"}, {"cells", "cells in the bin"},
                {"mean_abs_deg", "mean |error|, degrees"}, {"sd_abs_deg", "SD of |error|"},
                {"rms_deg", "RMS error"}, {"max_abs_deg", "largest |error|"}}));
  bind_record<SkyStudyTag>(m, "SkyStudy", "`polrig study sky`'s tables.",
      {{"device", "the rig's device.kind"}, {"bias", "polrig.SkyBias: bias.csv"},
       {"sky_dop", "polrig.SkyDop: sky_dop.csv"}, {"evector_by_dop", "polrig.EvectorByDop: evector_by_dop.csv"}});

  rig_class(m).def("study_sky", [](const PyRig& rig, std::vector<double> tau, std::vector<double> albedo,
                                   std::vector<double> sun_el_deg, std::vector<double> tilt_deg,
                                   std::vector<double> heading_deg, double noise_sd, int trials, double min_dop,
                                   int grid, int sky_cells, const py::object& seed, std::optional<int> threads,
                                   const py::object& progress) {
        const std::optional<Sky> sky = rig_sky(rig.rig());
        if (!sky) throw RigError(no_sky_message(rig.rig(), rig.loaded.origin));
        SkyStudySettings s;
        s.rt = rig.rig().source.sky.resolved_rt();
        s.P_max = sky->model.P_max;
        s.seed = seed.is_none() ? rig.rig().seed : seed.cast<std::uint64_t>();
        s.tau = std::move(tau);
        s.albedo = std::move(albedo);
        s.sun_el_deg = std::move(sun_el_deg);
        s.tilt_deg = std::move(tilt_deg);
        s.heading_deg = std::move(heading_deg);
        s.noise_sd = noise_sd;
        s.trials = trials;
        s.min_dop = min_dop;
        s.grid_cols = grid;
        s.mu_cells = sky_cells;
        check_sky_study_settings(s);
        const SkyCompass compass = sky_compass(rig.rig(), s.grid_cols);
        const Progress p = progress_from(progress);
        ThreadLimit limit(threads);
        SkyStudy study;
        {
          py::gil_scoped_release release;
          study = sky_study(compass, s, p);
        }
        Record r;
        r.add("device", py::str(study.compass.device));
        r.add("bias", py::cast(RecordOf<SkyBiasTag>(bias_record(study.bias))));
        r.add("sky_dop", py::cast(RecordOf<SkyDopTag>(dop_record(study.dop))));
        r.add("evector_by_dop", py::cast(RecordOf<EvectorByDopTag>(evector_record(study.evector_by_dop))));
        return RecordOf<SkyStudyTag>(std::move(r));
      }, py::kw_only(), "tau"_a = std::vector<double>{0.05, 0.1, 0.25, 0.5},
      "albedo"_a = std::vector<double>{0, 0.25, 0.8}, "sun_el_deg"_a = SkyStudySettings{}.sun_el_deg,
      "tilt_deg"_a = std::vector<double>{0, 5, 10}, "heading_deg"_a = SkyStudySettings{}.heading_deg,
      "noise_sd"_a = 0.01, "trials"_a = 16, "min_dop"_a = 0.15, "grid"_a = 48, "sky_cells"_a = 45,
      "seed"_a = py::none(), "threads"_a = py::none(), "progress"_a = py::none(),
      "`polrig study sky` (docs/physics.md §23): the rig's compass (its device.kind) under the vector-RT sky of "
      "every τ with every albedo, and under the single-scattering sky, read by its own method at every sun "
      "elevation, tilt and heading (relative to the sun). Returns polrig.SkyStudy, whose .bias, .sky_dop and "
      ".evector_by_dop are the CLI's bias.csv, sky_dop.csv and evector_by_dop.csv.");
}

}  // namespace polrig::python
