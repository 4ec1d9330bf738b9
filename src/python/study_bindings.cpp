// The rig's studies from Python (docs/python.md §4): Rig.simulate, Rig.study_cs, Rig.sweep,
// Rig.study_adc, Rig.study_calibration and Rig.light_at_pose. Each converts its arguments, runs
// the library with the GIL released and hands back NumPy arrays named as the CLI's CSV columns.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.h"
#include "convert.h"
#include "polrig/calib/pipeline.h"
#include "polrig/io/manifest.h"
#include "polrig/io/output_dir.h"
#include "polrig/io/plot.h"
#include "polrig/report/reports.h"
#include "polrig/report/trace_report.h"
#include "polrig/io/scene_yaml.h"
#include "polrig/calib/rig_options.h"
#include "polrig/rig/keys.h"
#include "polrig/sim/simulate.h"
#include "polrig/source/source.h"
#include "polrig/study/adc_limit.h"
#include "polrig/study/calibration_trials.h"
#include "polrig/study/cs.h"
#include "polrig/study/sweep.h"
#include "polrig/report/sweep_report.h"
#include "rig_handle.h"

namespace polrig::python {
namespace {

using Shape = std::vector<py::ssize_t>;

// ---- arguments

// The turn of `steps` table angles, after the CLI's --steps check (geometry/turn.h).
// The last one is kept (its cos/sin tables cost about as much as a 360-angle study); called with
// the GIL held, which guards the cache.
std::shared_ptr<const CsTurn> turn_of(int steps) {
  if (const auto problem = cs_steps_problem(steps))
    throw py::value_error(fmt::format("steps={}: {}", steps, *problem));
  static std::shared_ptr<const CsTurn> last;
  if (!last || last->steps() != steps) last = std::make_shared<const CsTurn>(steps);
  return last;
}

double finite_in(double v, double lo, double hi, const char* name, const char* unit) {
  if (!(v >= lo && v <= hi))
    throw py::value_error(fmt::format("{}={}: expected a number in [{}, {}]{}{}", name, v, lo, hi,
                                      *unit ? " " : "", unit));
  return v;
}

// ---- results: fixed-size per-row C++ arrays as (N, K) NumPy arrays, filled in one pass.

// A result array as a result object keeps it: checked finite (NaN only where `allow_nan`, as
// the CLI's CSV), then read-only.
py::array_t<double> kept(py::array_t<double> a, const char* name, bool allow_nan = false) {
  check_finite(a, name, allow_nan);
  return read_only(std::move(a));
}

template <class Row, class Get>
py::array_t<double> rows_of(const std::vector<Row>& rows, py::ssize_t k, const Get& get) {
  std::vector<double> out;
  out.reserve(rows.size() * static_cast<std::size_t>(k));
  for (const Row& r : rows) {
    const auto& a = get(r);
    out.insert(out.end(), a.begin(), a.end());
  }
  return take(std::move(out), {static_cast<py::ssize_t>(rows.size()), k});
}

template <class Row, class Get>
py::array_t<double> column_of(const std::vector<Row>& rows, const Get& get) {
  std::vector<double> out;
  out.reserve(rows.size());
  for (const Row& r : rows) out.push_back(get(r));
  return take(std::move(out));
}

// ---- simulate

struct PySimulation {
  py::array_t<double> theta_R_deg, t_s, theta_deg, d, E_Wm2, V_ideal, V_ecc, V_mean, V_std;
  py::object samples = py::none();
  int samples_per_stop = 0;
  bool time_dependent = false;
};

PySimulation to_python(const Simulation& sim) {
  PySimulation r;
  const auto& st = sim.stops;
  r.theta_R_deg = kept(column_of(st, [](const Stop& s) { return s.theta_R_deg; }), "theta_R_deg");
  r.t_s = kept(column_of(st, [](const Stop& s) { return s.t_s; }), "t_s");
  r.theta_deg = kept(column_of(st, [](const Stop& s) { return s.light.theta_deg; }), "theta_deg");
  r.d = kept(column_of(st, [](const Stop& s) { return s.light.d; }), "d");
  r.E_Wm2 = kept(rows_of(st, 6, [](const Stop& s) -> const auto& { return s.light.E_Wm2; }), "E_Wm2");
  r.V_ideal = kept(rows_of(st, 3, [](const Stop& s) -> const auto& { return s.V_ideal; }), "V_ideal");
  r.V_ecc = kept(rows_of(st, 3, [](const Stop& s) -> const auto& { return s.V_ecc; }), "V_ecc");
  r.V_mean = kept(rows_of(st, 3, [](const Stop& s) -> const auto& { return s.V_mean; }), "V_mean");
  r.V_std = kept(rows_of(st, 3, [](const Stop& s) -> const auto& { return s.V_std; }), "V_std");
  r.samples_per_stop = sim.samples_per_stop;
  r.time_dependent = sim.time_dependent;
  if (!sim.samples.empty()) {
    auto a = empty_array({static_cast<py::ssize_t>(st.size()), sim.samples_per_stop, 3});
    std::memcpy(a.mutable_data(), sim.samples.data(), sim.samples.size() * sizeof(sim.samples[0]));
    r.samples = kept(std::move(a), "samples");
  }
  return r;
}

// ---- study cs: the study kept in C++, its arrays made on first access (a call costs the
// study, not its conversion).

struct PyCsStudy {
  CsStudy s;
  std::size_t steps = 0;
  py::object theta_R_deg = py::none(), deviations = py::none(), deviations_se = py::none(),
             summary = py::none(), coaxial = py::none();  // caches

  py::array_t<double> pairs_mV(const std::array<std::vector<double>, 3>& br,
                               const std::array<std::vector<double>, 3>& mr, const char* name) const {
    const std::size_t n = steps;
    auto a = empty_array({static_cast<py::ssize_t>(n), 3, 2});
    double* out = a.mutable_data();
    for (std::size_t k = 0; k < n; ++k)
      for (std::size_t i = 0; i < 3; ++i) {
        out[(k * 3 + i) * 2] = br[i][k] * 1e3;  // as deviations.csv: volts × 1e3
        out[(k * 3 + i) * 2 + 1] = mr[i][k] * 1e3;
      }
    return kept(std::move(a), name);
  }
};

// The fields of a CS summary as summary.csv names them; eq6_mV may be NaN (no closed form).
struct SummaryField {
  const char* name;
  double CsPairSummary::*field;
  bool standard_error;
};
constexpr SummaryField kSummaryFields[] = {
    {"bsd_mV", &CsPairSummary::bsd_mV, false},
    {"asd_mV", &CsPairSummary::asd_mV, false},
    {"mean_br_mV", &CsPairSummary::mean_br_mV, false},
    {"mean_mr_mV", &CsPairSummary::mean_mr_mV, false},
    {"eq6_mV", &CsPairSummary::eq6_mV, false},
    {"bsd_stderr_mV", &CsPairSummary::bsd_se_mV, true},
    {"asd_stderr_mV", &CsPairSummary::asd_se_mV, true},
    {"mean_br_stderr_mV", &CsPairSummary::mean_br_se_mV, true},
    {"mean_mr_stderr_mV", &CsPairSummary::mean_mr_se_mV, true},
};

// RuntimeError for a summary value the CLI's summary.csv would refuse. Checked at the call: a
// NaN or inf deviation makes its pair's means NaN or inf, so this also catches the deviations
// before their arrays are made (each is checked again then).
void check_summary(const CsSummary& s, bool standard_errors, bool eq6, const char* prefix) {
  for (const SummaryField& f : kSummaryFields) {
    if (f.standard_error && !standard_errors) continue;
    const std::array<double, 3> v{s[0].*f.field, s[1].*f.field, s[2].*f.field};
    const bool allow_nan = !eq6 && std::string_view(f.name) == "eq6_mV";
    if (std::all_of(v.begin(), v.end(), [&](double x) { return std::isfinite(x) || (allow_nan && std::isnan(x)); }))
      continue;  // the name is made only for the message
    check_finite(v.data(), 3, fmt::format("{}{}", prefix, f.name), allow_nan);
  }
}

// A read-only view of a result's dict (types.MappingProxyType): the same object on every read,
// and nothing a caller does to it changes the result.
py::object read_only_mapping(const py::dict& d) {
  // Never destroyed: a static py::object would be released after the interpreter is gone.
  static const py::object* proxy = new py::object(py::module_::import("types").attr("MappingProxyType"));
  return (*proxy)(d);
}

// One read-only (3,) array per field of a CS summary, over the pairs: rows of one (fields, 3)
// array, made in one allocation.
py::object summary_mapping(const CsSummary& s, bool standard_errors) {
  std::vector<double> values;
  std::vector<const char*> names;
  for (const SummaryField& f : kSummaryFields)
    if (!f.standard_error || standard_errors) {
      for (const CsPairSummary& p : s) values.push_back(p.*f.field);
      names.push_back(f.name);
    }
  const auto rows = static_cast<py::ssize_t>(names.size());
  const py::array_t<double> all = take(std::move(values), {rows, 3});
  py::dict d;
  for (py::ssize_t k = 0; k < rows; ++k)  // row k as a (3,) view of `all`, which it keeps alive
    d[names[static_cast<std::size_t>(k)]] = read_only(py::array_t<double>({3}, all.data(k, 0), all));
  return read_only_mapping(d);
}

// ---- sweep: per-point fields written straight from the sink into preallocated arrays.

struct SweepField {
  const char* name;
  double (*get)(const CsPairSummary&);
  bool standard_error;
};
constexpr SweepField kSweepFields[] = {
    {"bsd_mV", [](const CsPairSummary& s) { return s.bsd_mV; }, false},
    {"asd_mV", [](const CsPairSummary& s) { return s.asd_mV; }, false},
    {"asd_bsd_pct", &asd_bsd_pct, false},
    {"mean_br_mV", [](const CsPairSummary& s) { return s.mean_br_mV; }, false},
    {"mean_mr_mV", [](const CsPairSummary& s) { return s.mean_mr_mV; }, false},
    {"eq6_mV", [](const CsPairSummary& s) { return s.eq6_mV; }, false},
    {"eq6_dev_pct", &eq6_dev_pct, false},
    {"bsd_stderr_mV", [](const CsPairSummary& s) { return s.bsd_se_mV; }, true},
    {"asd_stderr_mV", [](const CsPairSummary& s) { return s.asd_se_mV; }, true},
    {"mean_br_stderr_mV", [](const CsPairSummary& s) { return s.mean_br_se_mV; }, true},
    {"mean_mr_stderr_mV", [](const CsPairSummary& s) { return s.mean_mr_se_mV; }, true},
};

struct PySweep {
  std::vector<std::string> keys;
  py::dict axes;    // key → (count,) values
  py::tuple shape;  // the grid's shape
  py::dict fields;  // field → (*shape, 3)
  int steps = 0;
  bool standard_errors = false, eq6 = true;
};

GridAxis axis_of(const std::string& key, const py::handle& values) {
  if (py::isinstance<py::str>(values)) return GridAxis::parse(key + "=" + values.cast<std::string>());
  const DoubleArray a = as_array(values, ("grid['" + key + "']").c_str(), 0);
  if (a.ndim() > 1)
    throw py::value_error(fmt::format("grid['{}']: expected a 1-D array of values or a string "
                                      "'start:stop:count', got a {}-D array", key, a.ndim()));
  return GridAxis::list(key, std::vector<double>(a.data(), a.data() + a.size()));
}

// The memory the result arrays may take: half the machine's physical memory.
double result_memory_limit_bytes() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  return pages > 0 && page > 0 ? 0.5 * static_cast<double>(pages) * static_cast<double>(page) : 8.0 * (1ull << 30);
}

// RigError, before anything is allocated, when the grid's result arrays would not fit.
void check_sweep_memory(std::size_t points, std::size_t fields) {
  const double bytes = static_cast<double>(points) * 3.0 * sizeof(double) * static_cast<double>(fields);
  const double limit = result_memory_limit_bytes();
  constexpr double kGiB = 1024.0 * 1024.0 * 1024.0;
  if (bytes > limit)
    throw RigError(fmt::format(
        "grid: {} points need {:.1f} GiB for the result arrays ({} fields × 3 pairs × 8 bytes a "
        "point), more than half this machine's memory ({:.1f} GiB); sweep a smaller grid, or use "
        "`polrig sweep`, which streams sweep.csv", points, bytes / kGiB, fields, limit / kGiB));
}

// The grid's axes, in the dict's order; warns for keys the CS study ignores, as the CLI notes.
std::vector<GridAxis> grid_axes(const py::object& grid, std::vector<std::string>& keys) {
  if (!py::hasattr(grid, "items"))
    throw py::type_error("grid: expected a dict {key: values or 'start:stop:count'}");
  std::vector<GridAxis> axes;
  for (const py::handle item : py::iter(grid.attr("items")())) {
    const auto kv = item.cast<py::tuple>();
    if (!py::isinstance<py::str>(kv[0]))
      throw py::type_error(fmt::format("grid: keys are rig key names (str), got {}",
                                       py::repr(kv[0]).cast<std::string>()));
    keys.push_back(kv[0].cast<std::string>());
    axes.push_back(axis_of(keys.back(), kv[1]));
  }
  if (axes.empty()) throw py::value_error("grid: expected at least one key");
  const py::module_ warnings = py::module_::import("warnings");
  for (const RigKey* key : axes_the_cs_study_ignores(axes))  // the CLI's note
    warnings.attr("warn")(fmt::format("the CS study does not depend on '{}'; every point along "
                                      "that axis will be the same", key->path));
  return axes;
}

// Rig.sweep(out=...): the CLI's folder, through the same library function; returns its path.
py::object sweep_into_folder(const PyRig& self, const py::object& grid, int steps, std::optional<int> threads,
                             const py::object& progress, const std::filesystem::path& out, bool csv, bool resume,
                             bool force, bool plots) {
  std::vector<std::string> keys;
  const std::vector<GridAxis> axes = grid_axes(grid, keys);
  const LoadedRig loaded = self.loaded;  // the GIL is released below: nothing of self is read then
  turn_of(steps);  // the steps' check, with Rig.study_cs's message
  check_grid(loaded.rig, axes);
  if (plots && axes.size() <= 2 && !gnuplot_available())
    throw std::runtime_error("plots=True needs gnuplot, which was not found; install it "
                             "(scripts/setup-deps.sh) or pass plots=False");
  std::string grid_text;
  for (const GridAxis& a : axes) grid_text += fmt::format("{}'{}'", grid_text.empty() ? "" : ", ", a.text());
  const std::string command = fmt::format(
      "python: polrig.Rig({}).sweep(grid=[{}], steps={}, out='{}', csv={}, plots={})", loaded.origin, grid_text,
      steps, out.string(), csv ? "True" : "False", plots ? "True" : "False");
  const ThreadLimit limit(threads);
  const Progress p = progress_from(progress);
  std::filesystem::path written;
  {
    py::gil_scoped_release release;
    written = sweep_to_folder(loaded, axes, steps, {out, force, csv, plots, resume, command, "out=" + out.string()}, p);
  }
  return py::module_::import("pathlib").attr("Path")(written.string());
}

PySweep run_sweep(const PyRig& self, const py::object& grid, int steps, std::optional<int> threads,
                  const py::object& progress) {
  PySweep r;
  const std::vector<GridAxis> axes = grid_axes(grid, r.keys);
  const Rig rig = self.rig();
  const std::shared_ptr<const CsTurn> turn = turn_of(steps);
  check_grid(rig, axes);
  r.steps = steps;
  r.standard_errors = rig.light->has(Source::kStandardErrors);
  r.eq6 = rig.light->has(Source::kClosedFormEq6);
  std::size_t fields = 0;
  for (const SweepField& f : kSweepFields) fields += !f.standard_error || r.standard_errors;
  check_sweep_memory(grid_points(axes), fields);

  Shape shape;
  for (std::size_t a = 0; a < axes.size(); ++a) {
    std::vector<double> v(static_cast<std::size_t>(axes[a].count));
    for (int i = 0; i < axes[a].count; ++i) v[static_cast<std::size_t>(i)] = axes[a].value(i);
    r.axes[py::str(r.keys[a])] = read_only(take(std::move(v)));
    shape.push_back(axes[a].count);
  }
  r.shape = py::tuple(py::cast(shape));
  Shape field_shape = shape;
  field_shape.push_back(3);
  std::vector<std::pair<double*, double (*)(const CsPairSummary&)>> outputs;
  std::vector<std::pair<py::array_t<double>, const SweepField*>> arrays;
  for (const SweepField& f : kSweepFields) {
    if (f.standard_error && !r.standard_errors) continue;
    auto a = empty_array(field_shape);
    outputs.emplace_back(a.mutable_data(), f.get);
    arrays.emplace_back(a, &f);
  }

  const ThreadLimit limit(threads);
  const Progress p = progress_from(progress);
  {
    py::gil_scoped_release release;
    sweep(rig, axes, *turn,
          [&](std::size_t first, std::span<const CsSummary> block) {
            for (const auto& [out, get] : outputs)
              for (std::size_t k = 0; k < block.size(); ++k)
                for (std::size_t i = 0; i < 3; ++i) out[(first + k) * 3 + i] = get(block[k][i]);
          },
          p);
  }
  // NaN where sweep.csv allows it: the ratios, and Eq. 6 without its closed form.
  for (auto& [a, f] : arrays) {
    const std::string_view name = f->name;
    const bool allow_nan = name == "asd_bsd_pct" || name == "eq6_dev_pct" || (name == "eq6_mV" && !r.eq6);
    r.fields[f->name] = kept(std::move(a), f->name, allow_nan);
  }
  return r;
}

// ---- study adc

// `d=` of study_adc: the CLI's --d text (parse_d_list), or an array-like of values.
std::vector<double> d_values(const py::handle& d) {
  if (py::isinstance<py::str>(d)) return parse_d_list(d.cast<std::string>());
  const DoubleArray a = as_array(d, "d", 0);
  std::vector<double> ds(a.data(), a.data() + a.size());
  if (const auto problem = d_values_problem(ds)) throw py::value_error("d: " + *problem);
  return ds;
}

// ---- study calibration

struct PyTrials {
  py::array_t<std::int64_t> trial;
  py::array_t<std::uint64_t> seed;
  py::array_t<double> L_IS, alpha_IS, L_S, alpha_S, accuracy_deg;
  py::list failures;
  py::dict summary;
};

PyTrials to_python(const std::vector<Trial>& trials) {
  PyTrials r;
  std::vector<std::int64_t> index;
  std::vector<std::uint64_t> seed;
  for (const Trial& t : trials) {
    index.push_back(t.index);
    seed.push_back(t.seed);
  }
  r.trial = read_only(take(std::move(index)));
  r.seed = read_only(take(std::move(seed)));
  r.L_IS = kept(column_of(trials, [](const Trial& t) { return t.eccentricity.L_IS; }), "L_IS");
  r.alpha_IS = kept(column_of(trials, [](const Trial& t) { return t.eccentricity.alpha_IS; }), "alpha_IS");
  r.L_S = kept(column_of(trials, [](const Trial& t) { return t.eccentricity.L_S; }), "L_S");
  r.alpha_S = kept(column_of(trials, [](const Trial& t) { return t.eccentricity.alpha_S; }), "alpha_S");
  // NaN where a fit failed, as trials.csv.
  r.accuracy_deg = kept(rows_of(trials, 3, [](const Trial& t) -> const auto& { return t.accuracy_deg; }),
                        "accuracy_deg", true);
  for (const Trial& t : trials)
    for (std::size_t m = 0; m < 3; ++m)
      if (!t.fit[m].usable()) {
        py::dict f;
        f["trial"] = t.index;
        f["method"] = std::string(method_name(kAllMethods[m]));
        f["termination"] = std::string(termination_name(t.fit[m].termination));
        f["iterations"] = t.fit[m].iterations;
        f["evaluations"] = t.fit[m].evaluations;
        f["reason"] = t.fit[m].message;
        r.failures.append(f);
      }
  for (const TrialSummary& s : summarize_trials(trials)) {
    py::dict d, ends;
    d["succeeded"] = s.succeeded;
    d["failed"] = s.failed;
    d["median_deg"] = s.median_deg;
    d["p05_deg"] = s.p05_deg;
    d["p95_deg"] = s.p95_deg;
    d["mean_deg"] = s.mean_deg;
    for (std::size_t k = 0; k < s.terminations.size(); ++k)
      ends[py::str(std::string(termination_name(kAllTerminations[k])))] = s.terminations[k];
    d["terminations"] = ends;
    r.summary[py::str(std::string(method_name(s.method)))] = d;
  }
  return r;
}

// ---- docstrings

constexpr const char* kSimulateDoc = R"doc(
Simulates the rig's calibration run over its table schedule (the CLI's `polrig simulate`):
table pose → light at the six photodiodes → films and log amplifiers → noise → ADC, every stop.

Arguments:
  samples: also return every quantized sample (the CLI's --samples, samples.csv).
  out: a folder (str or os.PathLike) to write the dataset into, as `polrig simulate -o OUT`
       writes it (stops.csv, samples.csv with samples=True, rig.yaml, manifest.yaml; the same
       bytes, the manifest's command aside); it appears whole or not at all. None: no files.
  force: replace `out` if it exists (the CLI's --force); without it an existing folder is an
         error and nothing is computed.
  plots: also draw the PNG plots (needs gnuplot; the CLI draws them unless --no-plots).
  {threads}
  {progress}

Returns a polrig.Simulation whose arrays are the columns of the CLI's stops.csv, bit for bit
(N stops, S samples per stop; volts unless named otherwise):
  theta_R_deg (N,) table angle, deg;  t_s (N,) seconds since the first stop;
  theta_deg (N,) the light's angle in the sensor frame, deg;  d (N,) its degree of polarization;
  E_Wm2 (N, 6) irradiance at each photodiode, W/m²;
  V_ideal, V_ecc, V_mean, V_std (N, 3) pair voltages: eccentricity-free, with eccentricity,
  the mean and sample standard deviation of the noisy quantized samples (stops.csv's V1..V3
  are V_mean);  samples (N, S, 3) or None.
The result does not depend on `threads` (each noise value is a function of seed, stop, channel
and sample).

Raises polrig.RigError for a rig the source cannot run (the CLI's message).
)doc";

constexpr const char* kStudyCsDoc = R"doc(
The central-symmetry (CS) study over a full turn of the table (the CLI's `polrig study cs`;
paper Figs. 8–9): ΔV_br(θ_R) = V − V_ideal for each pair, its CS average ΔV_mr(θ_R) =
[ΔV_br(θ_R) + ΔV_br(θ_R + 180°)]/2, and their BSD, ASD and means. No noise, no ADC.

Arguments:
  steps: table angles per turn, even, in [2, 3600000] (θ_R = 360°·k/steps).
  {threads}
  {progress}

Returns a polrig.CsStudy: theta_R_deg (steps,); deviations_mV (steps, 3, 2) in mV, [angle,
pair, (br, mr)] as deviations.csv; deviations_stderr_mV (same shape) or None; summary, a read-only
mapping of (3,) arrays over the pairs in mV (summary.csv's columns); coaxial (mapping) or None;
flags.
Its arrays are read-only (made on first read, then the same array on every read).

Raises ValueError for a bad `steps`; polrig.RigError from the rig's source; RuntimeError
naming the field and index for a value that is not finite (the CLI refuses to write it).
)doc";

constexpr const char* kSweepDoc = R"doc(
The CS study at every point of a grid of rig keys (the CLI's `polrig sweep`; paper Figs. 10–12).

Arguments:
  grid: a dict {key: values}, in axis order (the last key varies fastest, as sweep.csv's rows).
    values is either a 1-D array-like of explicit values (np.linspace(1e-3, 1, 200),
    np.arange(360), [0.1, 0.2]) in the key's unit, or a string "start:stop:count" read exactly as
    the CLI's --grid key=start:stop:count (count values, both ends included, rounded to 15
    significant digits). Keys are real-valued rig keys (polrig.rig_keys()).
  steps: table angles per turn of each CS study, even, in [2, 3600000].
  {threads}
  {progress}
  out: a folder (str or os.PathLike) to write the sweep into, as `polrig sweep -o OUT` writes it
       (sweep.h5, sweep.csv with csv=True, the plots with plots=True, manifest.yaml, rig.yaml;
       the same bytes, the manifest's command and working directory aside), streamed as it is
       computed: memory does not grow with the grid. It appears whole or not at all. None: no
       files, the arrays are returned.
  csv: also write sweep.csv (the CLI's --csv).
  resume: continue an interrupted sweep into `out` (the CLI's --resume): the same grid, steps,
       rig and options; the result is the same bytes as an uninterrupted run.
  force: replace `out` if it exists, and without resume, discard an interrupted run's staging
       folder (the CLI's --force).
  plots: also draw the PNG plots (needs gnuplot; the CLI draws them unless --no-plots).

With out=, returns the folder's path (a pathlib.Path) and keeps no arrays in memory, so that a
grid of any size fits: read the results from OUT/sweep.h5 (h5py.File(path / "sweep.h5"): one
dataset per sweep.csv column, shaped as the grid, the axes as dimension scales). Without it,
returns a polrig.SweepResult: keys (axis order), axes {key: (count,) values}, shape (the grid's
shape), and per-point arrays of shape (*shape, 3) over the pairs, written straight from the
library into NumPy (no Python object per point): bsd_mV, asd_mV, asd_bsd_pct, mean_br_mV,
mean_mr_mV, eq6_mV, eq6_dev_pct (sweep.csv's pairN_* columns; NaN only where sweep.csv allows
it: the two ratios, and eq6_mV without Eq. 6's closed form) and, for a source with standard
errors, bsd_stderr_mV, asd_stderr_mV, mean_br_stderr_mV, mean_mr_stderr_mV. All read-only.

Raises polrig.RigError naming the key and value for an unknown or non-real key, a value outside
the key's range or NaN (an explicit list also names the value's index), a key the rig's source
does not read, a grid point the rig's cross-key rules refuse, or a grid whose result arrays
would need more than half the machine's physical memory (named with the points and GiB,
before anything is allocated; `polrig sweep` streams instead); TypeError for a grid that is
not a dict; RuntimeError naming the field and index for a value that is not finite. Warns (UserWarning) for a key the CS study does not read, as the CLI notes.
)doc";

constexpr const char* kStudyAdcDoc = R"doc(
The accuracy limit the ADC alone sets (the CLI's `polrig study adc`; paper Fig. 6): an ideal
sensor with the rig's electronics and film axes, uniform light, no noise.

Arguments:
  d: degrees of polarization, each in (0, 1): an array-like, or a string read as the CLI's --d,
    "a,b,c" or "start:stop:count" (default "0.05:0.95:19").
  step: the θ step of the search, deg, in [1e-4, 10].
  {threads}

Returns a dict of (len(d),) arrays, accuracy_limit.csv's columns: d; vmax_mV, the largest
pair voltage over θ (mV); limit_deg, max |θ12 − θ| over θ with quantized voltages (deg).

Raises ValueError naming the element for a bad array value; polrig.RigError with the CLI's
message ("--d TEXT: …") for bad text.
)doc";

constexpr const char* kStudyCalibrationDoc = R"doc(
Monte-Carlo calibrations (the CLI's `polrig study calibration`): `trials` simulated calibration
runs, each with its own noise seed and an eccentricity drawn uniformly (L_IS in [0, L_IS_max],
L_S in [0, L_S_max] mm, both angles in [0°, 360°)), calibrated by all three types.

Arguments:
  trials: the number of runs, in [1, 1e7].
  L_IS_max, L_S_max: the largest offsets drawn, mm, in [0, 100]; None: twice the rig's offset
    (at most 100), as the CLI.
  d_a: the stated degree of polarization for decoupling, in (0, 1); None: the rig's device.d.
  nc_threshold: noncontinuous rule, keep a voltage where |dV/dθ| ≥ this × its largest slope, [0, 1].
  nc_min_points: noncontinuous rule, keep at least this many points per voltage, [6, 100000].
  {threads}
  {progress}

Returns a polrig.CalibrationTrials: per trial (T,) arrays trial, seed (uint64), L_IS, alpha_IS,
L_S, alpha_S and accuracy_deg (T, 3), the θ_sec accuracy in degrees of the types (methods:
"section", "cs", "cs-nc"; NaN where the fit failed), as trials.csv; failures, a list of dicts
as failures.csv; summary {method: {succeeded, failed, median_deg, p05_deg, p95_deg, mean_deg,
terminations}} as summary.csv. Independent of `threads`.

Raises polrig.RigError (a ValueError) naming the argument for trials, L_IS_max, L_S_max,
nc_threshold or nc_min_points out of range, ValueError for a bad d_a.
)doc";

constexpr const char* kLightDoc = R"doc(
The light reaching the six photodiodes at table angle theta_R_deg (deg), t_s seconds after the
first stop (a time-dependent source such as the sky; ignored otherwise): the stops.csv columns
theta_deg, d and E1..E6_Wm2 of a simulated stop at that pose.

theta_R_deg: a number or an array-like of N angles (finite). t_s: finite seconds.
Returns a dict: E_Wm2 (6,) W/m², theta_deg (deg, [0, 180)), d; for an array of angles
E_Wm2 (N, 6), theta_deg (N,), d (N,).
)doc";

// The docstring with the shared arguments' documentation in place of {threads} and {progress}.
std::string doc(const char* text) {
  std::string s = text;
  for (const auto& [mark, what] : {std::pair{"{threads}", kThreadsDoc}, std::pair{"{progress}", kProgressDoc}})
    if (const auto at = s.find(mark); at != std::string::npos) s.replace(at, std::strlen(mark), what);
  return s;
}

// A copy of a result's nested lists and dicts, so that changing it leaves the result as it was.
py::object deep_copy(const py::object& o) { return py::module_::import("copy").attr("deepcopy")(o); }

}  // namespace

void bind_studies(py::module_& m) {
  auto rig = rig_class(m);

  py::class_<PySimulation>(m, "Simulation",
                           "The stops of a simulated calibration run (Rig.simulate): stops.csv's "
                           "columns as NumPy arrays; volts unless named otherwise.")
      .def_readonly("theta_R_deg", &PySimulation::theta_R_deg, "(N,) table angle of each stop, deg")
      .def_readonly("t_s", &PySimulation::t_s, "(N,) seconds since the first stop, from the schedule's speed and dwell (stops.csv has this column only for a time-dependent light)")
      .def_readonly("theta_deg", &PySimulation::theta_deg, "(N,) polarization angle in the sensor frame, deg, [0, 180)")
      .def_readonly("d", &PySimulation::d, "(N,) degree of linear polarization of the light")
      .def_readonly("E_Wm2", &PySimulation::E_Wm2, "(N, 6) irradiance at each photodiode, W/m² (E1_Wm2..E6_Wm2)")
      .def_readonly("V_ideal", &PySimulation::V_ideal, "(N, 3) pair voltages without eccentricity, V (V1_ideal..)")
      .def_readonly("V_ecc", &PySimulation::V_ecc, "(N, 3) pair voltages with the pose's light, before noise and ADC, V")
      .def_readonly("V_mean", &PySimulation::V_mean, "(N, 3) mean of the noisy quantized samples, V (stops.csv's V1..V3)")
      .def_readonly("V_std", &PySimulation::V_std, "(N, 3) their sample standard deviation (n - 1), V; 0 for one sample")
      .def_readonly("samples", &PySimulation::samples, "(N, S, 3) every quantized sample, V, or None unless simulate(samples=True)")
      .def_readonly("samples_per_stop", &PySimulation::samples_per_stop, "S, samples per stop")
      .def_readonly("time_dependent", &PySimulation::time_dependent, "whether the light changes during the run (the sky)")
      .def("__len__", [](const PySimulation& s) { return s.theta_R_deg.size(); })
      .def("__repr__", [](const PySimulation& s) {
        return fmt::format("<polrig.Simulation: {} stops × {} samples{}>", s.theta_R_deg.size(),
                           s.samples_per_stop, s.time_dependent ? ", time-dependent light" : "");
      });

  py::class_<PyCsStudy>(m, "CsStudy",
                        "A central-symmetry study over a full turn (Rig.study_cs): deviations.csv "
                        "and summary.csv as NumPy arrays, in mV.")
      .def_property_readonly("theta_R_deg", [](PyCsStudy& c) -> py::object {
        if (c.theta_R_deg.is_none()) c.theta_R_deg = kept(take(std::move(c.s.theta_R_deg)), "theta_R_deg");
        return c.theta_R_deg;
      }, "(steps,) table angles, deg: 360·k/steps")
      .def_property_readonly("deviations_mV", [](PyCsStudy& c) -> py::object {
        if (c.deviations.is_none()) c.deviations = c.pairs_mV(c.s.dv_br_V, c.s.dv_mr_V, "deviations_mV");
        return c.deviations;
      }, "(steps, 3, 2) deviations in mV, [angle, pair, (br, mr)]: ΔV_br = V − V_ideal before CS, "
         "ΔV_mr after (deviations.csv's dv_br_mV, dv_mr_mV)")
      .def_property_readonly("deviations", [](py::object self) { return self.attr("deviations_mV"); },
                             "the same array as deviations_mV (mV)")
      .def_property_readonly("deviations_stderr_mV", [](PyCsStudy& c) -> py::object {
        if (!c.s.standard_errors) return py::none();
        if (c.deviations_se.is_none())
          c.deviations_se = c.pairs_mV(c.s.dv_br_se_V, c.s.dv_mr_se_V, "deviations_stderr_mV");
        return c.deviations_se;
      }, "(steps, 3, 2) standard errors of deviations_mV, mV (deviations.csv's dv_br_stderr_mV, "
         "dv_mr_stderr_mV), or None when the source has none (standard_errors False)")
      .def_property_readonly("summary", [](PyCsStudy& c) -> py::object {
        if (c.summary.is_none()) c.summary = summary_mapping(c.s.summary, c.s.standard_errors);
        return c.summary;
      }, "read-only mapping (types.MappingProxyType) of read-only (3,) arrays over the pairs, mV, named as summary.csv's columns: "
         "bsd_mV, asd_mV, mean_br_mV, mean_mr_mV, eq6_mV (NaN without Eq. 6's closed form) and, "
         "with standard errors, bsd_stderr_mV, asd_stderr_mV, mean_br_stderr_mV, "
         "mean_mr_stderr_mV")
      .def_property_readonly("coaxial", [](PyCsStudy& c) -> py::object {
        if (!c.s.coaxial_reference) return py::none();
        if (c.coaxial.is_none()) {
          const py::object all = summary_mapping(c.s.coaxial, false);
          py::dict d;
          for (const char* k : {"bsd_mV", "asd_mV", "mean_br_mV"}) d[k] = all[k];
          c.coaxial = read_only_mapping(d);
        }
        return c.coaxial;
      }, "when coaxial_reference: the coaxial rig's own deviations, a dict of (3,) arrays in mV "
         "(summary.csv's coaxial_bsd_mV, coaxial_asd_mV, coaxial_mean_br_mV); else None")
      .def_property_readonly("standard_errors", [](const PyCsStudy& c) { return c.s.standard_errors; },
                             "whether the source gives standard errors (several shifts)")
      .def_property_readonly("coaxial_reference", [](const PyCsStudy& c) { return c.s.coaxial_reference; },
                             "whether ΔV refers to the coaxial rig (no uniform reference)")
      .def_property_readonly("eq6", [](const PyCsStudy& c) { return c.s.eq6; },
                             "whether Eq. 6's closed form exists (else eq6_mV is NaN)")
      .def("__repr__", [](const PyCsStudy& c) {
        return fmt::format("<polrig.CsStudy: {} table angles; ASD {:.6g}, {:.6g}, {:.6g} mV>",
                           c.steps, c.s.summary[0].asd_mV, c.s.summary[1].asd_mV,
                           c.s.summary[2].asd_mV);
      });

  auto sweep_class = py::class_<PySweep>(
      m, "SweepResult",
      "The CS study over a grid of rig keys (Rig.sweep). Per-point fields have shape (*shape, 3): "
      "grid index per key, in key order, then the pair; sweep.csv's row p is the C-order "
      "(row-major) point p, i.e. field.reshape(-1, 3)[p].");
  sweep_class
      .def_readonly("keys", &PySweep::keys, "the swept keys, in axis order")
      .def_property_readonly("axes", [](const PySweep& s) { return read_only_mapping(s.axes); },
                             "read-only mapping {key: (count,) read-only values} in the key's unit")
      .def_readonly("shape", &PySweep::shape, "the grid's shape: one count per key")
      .def_property_readonly("fields", [](const PySweep& s) { return read_only_mapping(s.fields); },
                             "read-only mapping {field: (*shape, 3) read-only array}: every per-point field below")
      .def_readonly("steps", &PySweep::steps, "table angles per turn of each CS study")
      .def_readonly("standard_errors", &PySweep::standard_errors, "whether the *_stderr_mV fields exist")
      .def_readonly("eq6", &PySweep::eq6, "whether Eq. 6's closed form exists (else eq6_mV is NaN)")
      .def("__len__", [](const PySweep& s) {
        py::ssize_t n = 1;
        for (const auto& c : s.shape) n *= c.cast<py::ssize_t>();
        return n;
      }, "the number of grid points")
      .def("__repr__", [](const PySweep& s) {
        std::string keys;
        for (const auto& k : s.keys) keys += (keys.empty() ? "" : ", ") + k;
        return fmt::format("<polrig.SweepResult: {} over ({}), steps={}>",
                           py::repr(s.shape).cast<std::string>(), keys, s.steps);
      });
  for (const SweepField& f : kSweepFields) {
    const std::string name = f.name;
    std::string what = fmt::format("(*shape, 3) sweep.csv's pairN_{}", name);
    if (name == "asd_bsd_pct") what = "(*shape, 3) ASD/BSD, %; NaN where BSD is rounding (< 1e-9 mV)";
    if (name == "eq6_dev_pct") what = "(*shape, 3) (eq6 − mean_mr)/mean_mr, %; NaN where mean_mr is rounding";
    if (f.standard_error) what = fmt::format("(*shape, 3) standard error of {}, mV; None without standard errors",
                                             name.substr(0, name.size() - 10) + "_mV");
    sweep_class.def_property_readonly(f.name, [name](const PySweep& s) -> py::object {
      if (!s.fields.contains(name)) return py::none();
      return s.fields[py::str(name)];
    }, what.c_str());
  }

  py::class_<PyTrials>(m, "CalibrationTrials",
                       "Monte-Carlo calibrations (Rig.study_calibration): trials.csv, "
                       "failures.csv and summary.csv as arrays and dicts.")
      .def_readonly("trial", &PyTrials::trial, "(T,) trial index (int64)")
      .def_readonly("seed", &PyTrials::seed, "(T,) each trial's noise seed (uint64)")
      .def_readonly("L_IS", &PyTrials::L_IS, "(T,) drawn port offset, mm")
      .def_readonly("alpha_IS", &PyTrials::alpha_IS, "(T,) its direction, deg")
      .def_readonly("L_S", &PyTrials::L_S, "(T,) drawn sensor offset, mm")
      .def_readonly("alpha_S", &PyTrials::alpha_S, "(T,) its direction, deg")
      .def_readonly("accuracy_deg", &PyTrials::accuracy_deg,
                    "(T, 3) θ_sec accuracy, deg, per type in `methods` order; NaN where the fit failed")
      .def_property_readonly("methods", [](const PyTrials&) {
        std::vector<std::string> names;
        for (CalibrationMethod mm : kAllMethods) names.emplace_back(method_name(mm));
        return names;
      }, "the calibration types of accuracy_deg's columns: section, cs, cs-nc")
      .def_property_readonly("failures", [](const PyTrials& t) { return deep_copy(t.failures); },
                    "list of dicts (trial, method, termination, iterations, evaluations, reason) "
                    "for every fit that is not usable (failures.csv)")
      .def_property_readonly("summary", [](const PyTrials& t) { return deep_copy(t.summary); },
                    "{method: {succeeded, failed, median_deg, p05_deg, p95_deg, mean_deg, "
                    "terminations: {name: count}}} (summary.csv)")
      .def("__len__", [](const PyTrials& t) { return t.trial.size(); })
      .def("__repr__", [](const PyTrials& t) {
        return fmt::format("<polrig.CalibrationTrials: {} trials, {} failed fits>", t.trial.size(),
                           t.failures.size());
      });

  rig.def("simulate", [](const PyRig& self, bool samples, std::optional<std::filesystem::path> out,
                         bool force, bool plots, std::optional<int> threads,
                         const py::object& progress) {
    require(self, Instrument::kPairVoltages, "simulate");
    const LoadedRig loaded = self.loaded;  // the GIL is released below: nothing of self is read then
    const Rig& r = loaded.rig;
    if (out && plots && !gnuplot_available())
      throw std::runtime_error("plots=True needs gnuplot, which was not found; install it "
                               "(scripts/setup-deps.sh) or pass plots=False");
    // Opened before computing, as the CLI does: an existing folder fails at once.
    std::optional<OutputDir> dir;
    if (out) {
      try {
        dir.emplace(*out, force);
      } catch (const std::runtime_error& e) {
        throw std::runtime_error(fmt::format("out={}: {}", out->string(), e.what()));
      }
    }
    const ThreadLimit limit(threads);
    const Progress p = progress_from(progress);
    Simulation sim;
    {
      py::gil_scoped_release release;
      sim = simulate(r, samples, p);
      if (dir) {
        const std::string command = fmt::format(
            "python: polrig.Rig({}).simulate(samples={}, out='{}', plots={})", loaded.origin,
            samples ? "True" : "False", out->string(), plots ? "True" : "False");
        write_manifest(dir->staging(), {command, &loaded, report_simulation(dir->staging(), sim, plots)});
        dir->commit();
      }
    }
    return to_python(sim);
  }, doc(kSimulateDoc).c_str(), py::kw_only(), py::arg("samples") = false,
     py::arg("out") = py::none(), py::arg("force") = false, py::arg("plots") = false,
     py::arg("threads") = py::none(), py::arg("progress") = py::none());

  m.def("trace", [](const std::filesystem::path& scene_file, const std::filesystem::path& out,
                    std::optional<long long> photons, bool force, bool plots,
                    std::optional<int> threads, const py::object& progress) {
    SceneSpec scene = load_scene(scene_file);
    if (const auto problem = set_trace_photons(scene.trace, photons))
      throw RigError(fmt::format("photons={}: {}", *photons, *problem));
    if (plots && !gnuplot_available())
      throw std::runtime_error("plots=True needs gnuplot, which was not found; install it "
                               "(scripts/setup-deps.sh) or pass plots=False");
    std::optional<OutputDir> dir;
    try {
      dir.emplace(out, force);
    } catch (const std::runtime_error& e) {
      throw std::runtime_error(fmt::format("out={}: {}", out.string(), e.what()));
    }
    const ThreadLimit limit(threads);
    const Progress p = progress_from(progress);
    std::vector<std::string> names;
    {
      py::gil_scoped_release release;
      const std::string command = fmt::format("python: polrig.trace('{}', out='{}', photons={}, plots={})",
                                              scene_file.string(), out.string(), scene.trace.photons,
                                              plots ? "True" : "False");
      LightOrigin light;
      Manifest manifest{command, nullptr, trace_scene(dir->staging(), scene, plots, p, &light), {scene_file.string()}};
      manifest.light = light;
      write_manifest(dir->staging(), manifest);
      dir->commit();
      for (const DatasetFile& f : manifest.files) names.push_back(f.name);
    }
    return names;
  }, doc(R"doc(
Traces a scene's integrating sphere (Embree photon tracing) and the light below its port, and
writes what `polrig trace SCENE -o OUT` writes (docs/formats.md, "polrig trace"): the wall
radiance and port-plane maps (EXR), their CSV tables, trace_summary.yaml, manifest.yaml and,
with plots=True, the PNG previews (needs gnuplot). The folder appears whole or not at all.

Arguments:
  scene: the scene file (YAML, str or os.PathLike), e.g. "scenes/jf500.yaml".
  out: the output folder; an existing one is an error unless force=True.
  photons: photons for the sphere solve, in [1000, 1e11] and at least 100 per batch (None: the
           scene's trace.photons); rounded down to whole batches, as traced.
  {threads}
  {progress}

Returns the names of the files written (relative to `out`). Raises polrig.RigError naming the
scene file, line and key, or the photon count.
)doc").c_str(), py::arg("scene"), py::arg("out"), py::kw_only(), py::arg("photons") = py::none(),
        py::arg("force") = false, py::arg("plots") = false, py::arg("threads") = py::none(),
        py::arg("progress") = py::none());

  rig.def("study_cs", [](const PyRig& self, int steps, std::optional<int> threads,
                         const py::object& progress) {
    require(self, Instrument::kPairVoltages, "study cs");
    const std::shared_ptr<const CsTurn> turn = turn_of(steps);
    const Rig r = self.rig();
    const ThreadLimit limit(threads);
    const Progress p = progress_from(progress);
    PyCsStudy out;
    {
      py::gil_scoped_release release;
      out.s = cs_study(r, *turn, p);
    }
    check_summary(out.s.summary, out.s.standard_errors, out.s.eq6, "summary ");
    if (out.s.coaxial_reference)  // the three fields summary.csv writes (coaxial_bsd_mV, …)
      for (const auto f : {&CsPairSummary::bsd_mV, &CsPairSummary::asd_mV, &CsPairSummary::mean_br_mV}) {
        const std::array<double, 3> v{out.s.coaxial[0].*f, out.s.coaxial[1].*f, out.s.coaxial[2].*f};
        check_finite(v.data(), 3, "coaxial", false);
      }
    out.steps = out.s.theta_R_deg.size();
    return out;
  }, doc(kStudyCsDoc).c_str(), py::arg("steps") = kDefaultCsSteps, py::kw_only(),
     py::arg("threads") = py::none(), py::arg("progress") = py::none());

  rig.def("sweep", [](const PyRig& self, const py::object& grid, int steps, std::optional<int> threads,
                      const py::object& progress, std::optional<std::filesystem::path> out, bool csv, bool resume,
                      bool force, bool plots) -> py::object {
    require(self, Instrument::kPairVoltages, "sweep");
    if (!out) {
      if (csv || resume || force || plots)
        throw py::value_error("csv=, resume=, force= and plots= are options of out=: pass out=FOLDER");
      return py::cast(run_sweep(self, grid, steps, threads, progress));
    }
    return sweep_into_folder(self, grid, steps, threads, progress, *out, csv, resume, force, plots);
  }, doc(kSweepDoc).c_str(), py::arg("grid"), py::arg("steps") = kDefaultCsSteps,
     py::kw_only(), py::arg("threads") = py::none(), py::arg("progress") = py::none(),
     py::arg("out") = py::none(), py::arg("csv") = false, py::arg("resume") = false, py::arg("force") = false,
     py::arg("plots") = false);

  rig.def("study_adc", [](const PyRig& self, const py::object& d, double step,
                          std::optional<int> threads) {
    require(self, Instrument::kPairVoltages, "study adc");
    const std::vector<double> ds = d_values(d);
    finite_in(step, kMinAdcStep, kMaxAdcStep, "step", "deg");
    if (const auto problem = adc_work_problem(ds.size(), step)) throw py::value_error("d, step: " + *problem);
    const Rig r = self.rig();
    const ThreadLimit limit(threads);
    std::vector<AdcLimit> limits;
    {
      py::gil_scoped_release release;
      limits = adc_accuracy_limits(ds, r.electronics, r.device.film_axis_deg, step);
    }
    py::dict out;
    out["d"] = kept(column_of(limits, [](const AdcLimit& l) { return l.d; }), "d");
    out["vmax_mV"] = kept(column_of(limits, [](const AdcLimit& l) { return l.vmax_mV; }), "vmax_mV");
    out["limit_deg"] = kept(column_of(limits, [](const AdcLimit& l) { return l.limit_deg; }), "limit_deg");
    return out;
  }, doc(kStudyAdcDoc).c_str(), py::kw_only(), py::arg("d") = std::string(kDefaultAdcD),
     py::arg("step") = kDefaultAdcStep,
     py::arg("threads") = py::none());

  rig.def("study_calibration", [](const PyRig& self, int trials, std::optional<double> L_IS_max,
                                  std::optional<double> L_S_max, std::optional<double> d_a,
                                  double nc_threshold, int nc_min_points, std::optional<int> threads,
                                  const py::object& progress) {
    require(self, Instrument::kPairVoltages, "study calibration");
    if (d_a && !(*d_a > 0 && *d_a < 1))
      throw py::value_error(fmt::format("d_a={}: expected a degree of polarization in (0, 1)", *d_a));
    const NoncontinuousRule rule{nc_threshold, nc_min_points};
    if (const auto problem = noncontinuous_rule_problem(rule)) throw py::value_error(*problem);
    const Rig r = self.rig();
    CalibrationOptions options = calibration_options(r, d_a ? d_a : std::optional<double>(r.device.d), rule);
    options.d_a_source = d_a ? "d_a" : "the rig's device.d";
    const TrialSettings s = trial_settings_for(r, trials, L_IS_max, L_S_max, std::move(options));
    const ThreadLimit limit(threads);
    const Progress p = progress_from(progress);
    std::vector<Trial> result;
    {
      py::gil_scoped_release release;
      result = calibration_trials(r, s, p);
    }
    return to_python(result);
  }, doc(kStudyCalibrationDoc).c_str(), py::kw_only(), py::arg("trials") = TrialSettings{}.trials,
     py::arg("L_IS_max") = py::none(), py::arg("L_S_max") = py::none(), py::arg("d_a") = py::none(),
     py::arg("nc_threshold") = NoncontinuousRule{}.min_relative_slope,
     py::arg("nc_min_points") = NoncontinuousRule{}.min_points, py::arg("threads") = py::none(),
     py::arg("progress") = py::none());

  rig.def("light_at_pose", [](const PyRig& self, const py::object& theta_R_deg, double t_s) {
    require(self, Instrument::kPairVoltages, "light_at_pose");
    const DoubleArray a = as_array(theta_R_deg, "theta_R_deg", 0);
    if (a.ndim() > 1) throw py::value_error("theta_R_deg: expected a number or a 1-D array");
    const std::vector<double> angles = finite_values(a, "theta_R_deg");
    if (!std::isfinite(t_s)) throw py::value_error(fmt::format("t_s={}: expected a finite number of seconds", t_s));
    const Rig r = self.rig();
    std::vector<PoseLight> lights;
    {
      py::gil_scoped_release release;
      r.light->prepare({});
      for (double th : angles) lights.push_back(light_at_pose(r, th, t_s));
    }
    py::dict out;
    if (a.ndim() == 0) {
      out["E_Wm2"] = to_array(lights[0].E_Wm2);
      out["theta_deg"] = lights[0].theta_deg;
      out["d"] = lights[0].d;
    } else {
      out["E_Wm2"] = rows_of(lights, 6, [](const PoseLight& l) -> const auto& { return l.E_Wm2; });
      out["theta_deg"] = column_of(lights, [](const PoseLight& l) { return l.theta_deg; });
      out["d"] = column_of(lights, [](const PoseLight& l) { return l.d; });
    }
    return out;
  }, kLightDoc, py::arg("theta_R_deg"), py::arg("t_s") = 0.0);
}

}  // namespace polrig::python
