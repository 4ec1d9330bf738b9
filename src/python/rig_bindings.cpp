// polrig.Rig: built from a file, a YAML string or a dict; every rig key readable and settable
// with the checks of --set; written back as YAML. polrig.rig_keys(): the one table of keys.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "bindings.h"
#include "convert.h"
#include "polrig/rig/keys.h"
#include "rig_handle.h"

namespace polrig::python {
namespace {

// A Python value as the YAML text of a `--set key=value`.
std::string yaml_text(const py::handle& v, const std::string& path) {
  if (PyBool_Check(v.ptr())) return v.cast<bool>() ? "true" : "false";
  if (py::isinstance<py::str>(v)) return v.cast<std::string>();
  if (PyLong_Check(v.ptr()) || py::isinstance(v, py::module_::import("numpy").attr("integer")))
    return py::str(py::int_(py::reinterpret_borrow<py::object>(v))).cast<std::string>();
  if (PyFloat_Check(v.ptr()) || py::isinstance(v, py::module_::import("numpy").attr("floating")))
    return fmt::format("{}", v.cast<double>());  // shortest form that reads back exactly
  if (py::isinstance<py::sequence>(v) || py::isinstance<py::array>(v)) {
    std::string s = "[";
    bool first = true;
    for (const py::handle item : py::iter(v)) {
      s += (first ? "" : ", ") + yaml_text(item, path);
      first = false;
    }
    return s + "]";
  }
  throw py::type_error(fmt::format("rig key '{}': cannot use a {} as a value (expected a number, "
                                   "a string or a sequence of numbers)", path,
                                   py::str(py::type::of(v)).cast<std::string>()));
}

// Flattens {"eccentricity": {"L_S": 0.05}} and {"eccentricity.L_S": 0.05} into overrides.
void flatten(const py::dict& d, const std::string& prefix, std::vector<RigOverride>& out) {
  for (const auto& [k, v] : d) {
    if (!py::isinstance<py::str>(k))
      throw py::type_error(fmt::format("rig dict: keys must be strings, got {} under '{}'",
                                       py::repr(k).cast<std::string>(), prefix.empty() ? "(top)" : prefix));
    const std::string path = prefix.empty() ? k.cast<std::string>() : prefix + "." + k.cast<std::string>();
    if (py::isinstance<py::dict>(v) && !find_rig_key(path))
      flatten(v.cast<py::dict>(), path, out);
    else
      out.push_back({path, yaml_text(v, path)});
  }
}

std::vector<RigOverride> overrides_of(const std::optional<py::dict>& set) {
  std::vector<RigOverride> out;
  if (set) flatten(*set, "", out);
  return out;
}

const RigKey& key_or_throw(const std::string& path) {
  const RigKey* k = find_rig_key(path);
  if (!k)
    throw py::key_error(fmt::format("unknown rig key '{}' (polrig.rig_keys() and docs/formats.md "
                                    "list them)", path));
  return *k;
}

py::object value_of(const Rig& rig_in, const RigKey& k) {
  Rig rig = rig_in;  // the accessors take a mutable rig
  using K = RigKey::Kind;
  switch (k.kind) {
    case K::Real: return py::float_(k.real(rig));
    case K::Integer: return py::int_(k.integer(rig));
    case K::Seed: return py::int_(k.seed(rig));
    case K::Text: return py::str(k.text(rig));
    case K::RealArray: {
      const std::span<double> a = k.array(rig);
      return take(std::vector<double>(a.begin(), a.end()));
    }
    case K::RealList: return take(std::vector<double>(k.list(rig)));
    case K::Bool: return py::bool_(k.boolean(rig));
  }
  return py::none();
}

// Whether the rig's source and instrument read the key (Rig.keys(), `in`).
bool reads_key(const PyRig& r, const RigKey& k) {
  return k.read_by_source(r.rig().source.model) && k.read_by_instrument(r.rig().device_kind) &&
         (r.rig().source.model != "sky" || k.read_by_sky_model(r.rig().source.sky.model));
}

PyRig reparsed(const PyRig& r, const std::vector<RigOverride>& more) {
  std::vector<RigOverride> overrides = r.loaded.overrides;
  overrides.insert(overrides.end(), more.begin(), more.end());
  return {parse_rig(r.loaded.text, r.loaded.origin, overrides)};
}

py::dict key_info(const RigKey& k) {
  static const char* kinds[] = {"real", "integer", "seed", "text", "real array", "real list", "bool"};
  Rig defaults;
  py::dict d;
  d["path"] = std::string(k.path);
  d["kind"] = kinds[static_cast<int>(k.kind)];
  d["unit"] = std::string(k.unit);
  d["default"] = value_of(defaults, k);
  d["expects"] = k.expects;
  d["doc"] = std::string(k.doc);
  d["why"] = std::string(k.why);
  d["read_by"] = k.studies_text();
  d["sources"] = k.sources.empty() ? std::string("all") : std::string(k.sources);
  d["instruments"] = k.instruments.empty() ? std::string("all") : std::string(k.instruments);
  return d;
}

}  // namespace

void bind_rig(py::module_& m) {
  py::class_<PyRig> rig(m, "Rig", R"doc(
A calibration rig: the sensor on the rotary table under the integrating sphere's port (or under
the sky). Rig() is the seed paper's indoor rig (rigs/wang2019-indoor.yaml).

Every rig key (docs/formats.md, polrig.rig_keys()) reads as rig["eccentricity.L_IS"] and sets as
rig["eccentricity.L_IS"] = 0.1, in the key's unit (mm, degrees, V, ...), with the checks of the
CLI's --set: a bad value raises polrig.RigError and leaves the rig unchanged.
)doc");
  rig.def(py::init([] { return PyRig{parse_rig("", "(default rig)")}; }),
          "The default rig (the values of rigs/wang2019-indoor.yaml).")
      .def_static("load", [](const std::filesystem::path& path, const std::optional<py::dict>& set, bool dataset) {
            return PyRig{load_rig(path, overrides_of(set), dataset ? RigUse::ReadDataset : RigUse::Run)};
          }, py::arg("path"), py::kw_only(), py::arg("set") = py::none(), py::arg("dataset") = false,
          R"doc(Reads a rig file (YAML).

path: the rig file (str or os.PathLike), e.g. "rigs/wang2019-indoor.yaml"; a scene it names is
      found relative to it.
set: overrides, as the CLI's --set: {"eccentricity.L_S": 0.05} or nested
     {"eccentricity": {"L_S": 0.05}}; values in the key's unit.
dataset: read it for a recorded unit-array dataset, as navigate --rig does (a simulated run's own
     rules, such as a trajectory of whole IMU intervals, are not applied: a 125.057 Hz log's rig
     loads); simulate_navigation and study_navigation then check those rules themselves.
Raises polrig.RigError naming the file, line, key and value.)doc")
      .def_static("from_yaml", [](const std::string& text, const std::optional<py::dict>& set, const std::string& origin,
                                  bool dataset) {
            return PyRig{parse_rig(text, origin, overrides_of(set), dataset ? RigUse::ReadDataset : RigUse::Run)};
          }, py::arg("text"), py::kw_only(), py::arg("set") = py::none(),
          py::arg("origin") = "(yaml string)", py::arg("dataset") = false,
          "A rig from YAML text; `origin` names it in error messages (and is the folder a "
          "relative scene path is read from when it is a file path); `dataset` as Rig.load's.")
      .def_static("from_dict", [](const py::dict& d, const std::optional<py::dict>& set) {
            std::vector<RigOverride> o;
            flatten(d, "", o);
            const std::vector<RigOverride> more = overrides_of(set);
            o.insert(o.end(), more.begin(), more.end());
            return PyRig{parse_rig("", "(dict)", o)};
          }, py::arg("values"), py::kw_only(), py::arg("set") = py::none(),
          "The default rig with the dict's keys set: {\"eccentricity.L_S\": 0.05} or nested "
          "{\"eccentricity\": {\"L_S\": 0.05}}; every value is checked as --set checks it.")
      .def("to_yaml", [](const PyRig& r) { return rig_to_yaml(r.rig()); },
           "The complete effective rig, every key written: text that Rig.from_yaml reads back "
           "to the same rig (as `polrig rig show`).")
      .def("to_dict", [](const PyRig& r) {
            py::dict d;
            for (const RigKey& k : rig_keys())
              if (written_for(k, r.rig())) d[py::str(std::string(k.path))] = value_of(r.rig(), k);
            return d;
          }, "The effective rig as a flat dict, the keys to_yaml writes: {\"eccentricity.L_IS\": "
             "0.05, ...}; Rig.from_dict reads it back to the same rig (unset optional keys are "
             "left out).")
      .def("keys", [](const PyRig& r) {
            std::vector<std::string> out;
            for (const RigKey& k : rig_keys())
              if (reads_key(r, k)) out.emplace_back(k.path);
            return out;
          }, "The keys this rig's source and instrument read, in the table's order.")
      .def("__getitem__", [](const PyRig& r, const std::string& path) {
            const RigKey& k = key_or_throw(path);
            return value_of(r.rig(), k);
          }, py::arg("key"), "A key's value in its unit: a float, int, str or a float64 array.")
      .def("__setitem__", [](PyRig& r, const std::string& path, const py::handle& value) {
            r = reparsed(r, {{path, yaml_text(value, path)}});
          }, py::arg("key"), py::arg("value"),
          "Sets a key with the checks of --set; raises polrig.RigError and leaves the rig "
          "unchanged on a bad value.")
      .def("update", [](PyRig& r, const py::dict& values) {
            std::vector<RigOverride> o;
            flatten(values, "", o);
            r = reparsed(r, o);
          }, py::arg("values"), "Sets several keys at once (all or none).")
      .def("__contains__", [](const PyRig& r, const std::string& path) {
            const RigKey* k = find_rig_key(path);
            return k && reads_key(r, *k);
          }, py::arg("key"), "Whether `key` is one of rig.keys() (a key this rig's source and "
                             "instrument read).")
      .def("copy", [](const PyRig& r) { return r; }, "An independent copy.")
      .def("__copy__", [](const PyRig& r) { return r; })
      .def("__deepcopy__", [](const PyRig& r, py::dict) { return r; }, py::arg("memo"))
      .def_property_readonly("instrument", [](const PyRig& r) { return std::string(r.rig().instrument().kind()); },
                             "The instrument's kind, as device.kind names it: \"six-photodiode\" "
                             "or \"dofp-camera\" (ask Rig.can what it measures, not the kind).")
      .def_property_readonly("capabilities", [](const PyRig& r) {
            std::vector<std::string> out;
            for (const InstrumentFlagInfo& f : instrument_flags())
              if (r.rig().instrument().has(f.flag)) out.emplace_back(f.name);
            return out;
          }, "What the rig's instrument measures (its flags): \"pair_voltages\" (the "
             "six-photodiode sensor: simulate, the studies, calibrate's Eq. 15 methods), "
             "\"frames\" (the cameras), \"mosaic\" (the DoFP camera's polarizer mosaic), "
             "\"camera_array\" (W16's four cameras).")
      .def("can", [](const PyRig& r, const std::string& capability) {
            for (const InstrumentFlagInfo& f : instrument_flags())
              if (f.name == capability) return r.rig().instrument().has(f.flag);
            std::string known;
            for (const InstrumentFlagInfo& f : instrument_flags())
              known += fmt::format("{}{}", known.empty() ? "" : ", ", f.name);
            throw py::value_error(fmt::format("unknown capability '{}' (expected one of {})",
                                              capability, known));
          }, py::arg("capability"),
          "Whether the rig's instrument has `capability` (\"pair_voltages\" or \"frames\"); "
          "raises ValueError for another name.")
      .def_property_readonly("origin", [](const PyRig& r) { return r.loaded.origin; },
                             "The file the rig was read from, or \"(default rig)\", \"(dict)\", ...")
      .def_property_readonly("overrides", [](const PyRig& r) {
            std::vector<std::string> out;
            for (const RigOverride& o : r.loaded.overrides) out.push_back(o.path + "=" + o.value);
            return out;
          }, "The overrides applied to the origin's text, oldest first (\"key=value\").")
      .def("__repr__", [](const PyRig& r) {
            return fmt::format("<polrig.Rig {} ({} overrides), source.model {}{}>", r.loaded.origin,
                               r.loaded.overrides.size(), r.rig().source.model,
                               r.rig().device_kind == kDefaultDeviceKind
                                   ? std::string()
                                   : ", device.kind " + r.rig().device_kind);
          })
      .def(py::pickle(
          [](const PyRig& r) {
            py::list o;
            for (const RigOverride& x : r.loaded.overrides) o.append(py::make_tuple(x.path, x.value));
            // A rig file's folder resolves the scene it names: keep it absolute, so that the rig
            // unpickles in another working directory (a multiprocessing worker).
            std::string origin = r.loaded.origin;
            std::error_code ec;
            if (std::filesystem::is_regular_file(origin, ec)) origin = std::filesystem::absolute(origin).string();
            return py::make_tuple(r.loaded.text, origin, o);
          },
          [](const py::tuple& t) {
            std::vector<RigOverride> o;
            for (const py::handle x : t[2].cast<py::list>())
              o.push_back({x.cast<py::tuple>()[0].cast<std::string>(), x.cast<py::tuple>()[1].cast<std::string>()});
            return PyRig{parse_rig(t[0].cast<std::string>(), t[1].cast<std::string>(), o)};
          }));

  m.def("rig_keys", [] {
        py::list out;
        for (const RigKey& k : rig_keys()) out.append(key_info(k));
        return out;
      }, "Every rig key, as the table `polrig rig keys` prints: a list of dicts with path, kind, "
         "unit, default, expects, doc, why, read_by (the studies), sources (the source models) and "
         "instruments (the device.kind values that read it; \"all\" for every one).");
}

}  // namespace polrig::python
