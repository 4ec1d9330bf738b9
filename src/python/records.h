#pragma once
// What the sky and navigation bindings share: broadcasting several array arguments (and an array
// of UTC times) to one shape, and result records whose fields are NumPy arrays named as the CSV
// columns.
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "convert.h"

namespace polrig::python {
using namespace pybind11::literals;

// Arguments broadcast together (NumPy's rules), each flattened in C order into `values`, every
// element finite (ValueError naming the argument and the flat index otherwise).
struct Broadcast {
  std::vector<py::ssize_t> shape;
  std::size_t size = 0;
  std::vector<std::vector<double>> values;  // one per argument, in the order given
};

// An argument to broadcast: NaN allowed where it means "none" (a prior), never ±inf.
struct BroadcastArg {
  py::object obj;
  const char* name;
  bool nan_ok = false;
};

inline Broadcast broadcast(const std::vector<BroadcastArg>& args) {
  const py::module_ np = py::module_::import("numpy");
  std::vector<DoubleArray> arrays;
  std::string names;
  for (const auto& [obj, name, nan_ok] : args) {
    arrays.push_back(as_array(obj, name, 0));
    names += fmt::format("{}{}{}", names.empty() ? "" : ", ", name,
                         py::str(py::tuple(arrays.back().attr("shape"))).cast<std::string>());
  }
  py::tuple together;
  try {
    py::tuple objs(arrays.size());
    for (std::size_t i = 0; i < arrays.size(); ++i) objs[i] = arrays[i];
    together = np.attr("broadcast_arrays")(*objs);
  } catch (const py::error_already_set&) {
    throw py::value_error(fmt::format("these arguments do not broadcast to one shape: {}", names));
  }
  Broadcast b;
  for (std::size_t i = 0; i < arrays.size(); ++i) {
    // np.array, not np.ascontiguousarray, which makes a 0-d array 1-d.
    const DoubleArray a = DoubleArray::ensure(np.attr("array")(together[i], "dtype"_a = "float64", "order"_a = "C"));
    if (i == 0) {
      for (py::ssize_t d = 0; d < a.ndim(); ++d) b.shape.push_back(a.shape(d));
      b.size = static_cast<std::size_t>(a.size());
    }
    if (!args[i].nan_ok) {
      b.values.push_back(finite_values(a, args[i].name));
      continue;
    }
    std::vector<double> v(a.data(), a.data() + a.size());
    for (std::size_t k = 0; k < v.size(); ++k)
      if (std::isinf(v[k]))
        throw py::value_error(fmt::format("{}: element {} is {} (NaN means none)", args[i].name, k, v[k]));
    b.values.push_back(std::move(v));
  }
  return b;
}

// The shape of a UTC argument as utc_times reads it: () for one instant, else NumPy's shape.
inline py::object utc_shape(const py::handle& utc) {
  const py::module_ np = py::module_::import("numpy");
  if (py::isinstance<py::str>(utc) || !py::isinstance<py::iterable>(utc)) return py::tuple();
  if (py::isinstance<py::array>(utc)) return utc.attr("shape");
  return np.attr("shape")(np.attr("array")(utc, "dtype"_a = "object"));
}

// The index of each UTC instant after broadcasting: utc_times(utc) flattened, and its shape
// expressed as an array of indices that broadcasts with the numeric arguments.
inline py::object utc_index(const py::handle& utc) {
  const py::module_ np = py::module_::import("numpy");
  const py::object shape = utc_shape(utc);
  const py::ssize_t n = py::int_(np.attr("prod")(shape, "dtype"_a = "int64"));
  return np.attr("arange")(n, "dtype"_a = "float64").attr("reshape")(shape);
}

// A result: named fields (NumPy arrays or numbers), one Python class per kind of result.
struct Record {
  std::vector<std::pair<std::string, py::object>> fields;
  // Arrays are made read-only: the record is a result, its fields the CSV's columns.
  void add(std::string name, py::object value) {
    if (py::isinstance<py::array>(value)) value.attr("setflags")(py::arg("write") = false);
    fields.emplace_back(std::move(name), std::move(value));
  }
};

template <class Tag>
struct RecordOf : Record {
  RecordOf() = default;
  explicit RecordOf(Record r) : Record(std::move(r)) {}
};

// Binds RecordOf<Tag> as `name` with one read-only property per field (docs in `fields`, in the
// order the record stores them), keys(), to_dict() and a __repr__ showing each field's shape.
template <class Tag>
py::class_<RecordOf<Tag>> bind_record(py::module_& m, const char* name, const char* doc,
                                      const std::vector<std::pair<const char*, const char*>>& fields) {
  py::class_<RecordOf<Tag>> c(m, name, doc);
  for (const auto& [field, field_doc] : fields) {
    const std::string key = field, type = name;
    c.def_property_readonly(field, [key, type](const RecordOf<Tag>& r) -> py::object {
      for (const auto& [k, v] : r.fields)
        if (k == key) return v;
      throw std::logic_error(fmt::format("polrig.{}: the record has no field '{}'", type, key));
    }, field_doc);
  }
  c.def("keys", [](const RecordOf<Tag>& r) {
    std::vector<std::string> k;
    for (const auto& f : r.fields) k.push_back(f.first);
    return k;
  }, "The field names, in order (the CSV's columns where the CLI writes one).");
  c.def("to_dict", [](const RecordOf<Tag>& r) {
    py::dict d;
    for (const auto& [k, v] : r.fields) d[py::str(k)] = v;
    return d;
  }, "The fields as a dict {name: value} (the arrays themselves, not copies).");
  const std::string type = name;
  c.def("__repr__", [type](const RecordOf<Tag>& r) {
    std::string s = fmt::format("<polrig.{}:", type);
    for (std::size_t i = 0; i < r.fields.size(); ++i) {
      const py::object& v = r.fields[i].second;
      const std::string what = py::isinstance<py::array>(v)
                                   ? py::str(v.attr("shape")).cast<std::string>()
                                   : fmt::format("<{}>", py::str(py::type::of(v).attr("__name__")).cast<std::string>());
      s += fmt::format("{} {} {}", i ? "," : "", r.fields[i].first, what);
    }
    s += ">";
    return s;
  });
  return c;
}

}  // namespace polrig::python
