#include "convert.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>
#include <fmt/ranges.h>

namespace polrig::python {

py::array_t<double> empty_array(std::vector<py::ssize_t> shape) {
  return py::array_t<double>(std::move(shape));
}

void check_finite(const double* values, std::size_t n, const std::string& name, bool allow_nan,
                  const std::vector<py::ssize_t>& shape) {
  // Fast path, branch-free so that it vectorizes: is any exponent all ones (inf or NaN)?
  constexpr std::uint64_t kExponent = 0x7ff0000000000000ull;
  bool any_not_finite = false;
  for (std::size_t i = 0; i < n; ++i) {
    std::uint64_t bits;
    std::memcpy(&bits, values + i, sizeof bits);
    any_not_finite |= (bits & kExponent) == kExponent;
  }
  if (!any_not_finite) return;
  for (std::size_t i = 0; i < n; ++i) {
    const double v = values[i];
    if (std::isfinite(v) || (allow_nan && std::isnan(v))) continue;
    std::string index = fmt::format("{}", i);
    if (shape.size() > 1) {  // the flat index as one index per dimension, C order
      std::vector<std::size_t> at(shape.size());
      std::size_t rest = i;
      for (std::size_t d = shape.size(); d-- > 0;) {
        at[d] = rest % static_cast<std::size_t>(shape[d]);
        rest /= static_cast<std::size_t>(shape[d]);
      }
      index = fmt::format("{}", fmt::join(at, ", "));
    }
    throw std::runtime_error(fmt::format(
        "a result is not finite: {}[{}] is {}; the inputs are beyond what the model can "
        "represent (the CLI refuses to write it)", name, index, v));
  }
}

namespace {
std::string shape_text(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t d = 0; d < a.ndim(); ++d) s += fmt::format("{}{}", d ? ", " : "", a.shape(d));
  return s + (a.ndim() == 1 ? ",)" : ")");
}
}  // namespace

DoubleArray as_array(const py::handle& obj, const char* name, int ndim, py::ssize_t columns) {
  const DoubleArray a = DoubleArray::ensure(obj);  // a null array on failure (pybind11 clears the error)
  if (!a) {
    // Ask NumPy why: a huge broadcast or strided view fails for memory, being copied whole, not for its type.
    try {
      py::module_::import("numpy").attr("ascontiguousarray")(obj, "float64");
    } catch (py::error_already_set& e) {
      if (e.matches(PyExc_MemoryError)) {
        const std::string size = py::str(py::module_::import("numpy").attr("size")(obj)).cast<std::string>();
        throw py::value_error(fmt::format(
            "{}: {} numbers do not fit in memory as one contiguous float64 array ({}); a broadcast or a strided "
            "view is copied whole before polrig reads it", name, size, e.what()));
      }
    }
    throw py::type_error(fmt::format("{}: expected an array of numbers, got {}", name,
                                     py::str(py::type::of(obj)).cast<std::string>()));
  }
  const bool shape_ok = (ndim == 0 || a.ndim() == ndim) &&
                        (columns == 0 || (a.ndim() >= 1 && a.shape(a.ndim() - 1) == columns));
  if (!shape_ok) {
    const std::string want =
        columns ? (ndim == 2 ? fmt::format("a 2-D array of shape (N, {})", columns)
                             : fmt::format("an array whose last dimension is {}", columns))
                : fmt::format("a {}-D array", ndim);
    throw py::value_error(fmt::format("{}: expected {}, got shape {}", name, want, shape_text(a)));
  }
  return a;
}

std::vector<double> finite_values(const DoubleArray& a, const char* name) {
  std::vector<double> v(a.data(), a.data() + a.size());
  for (std::size_t i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i]))
      throw py::value_error(fmt::format("{}: element {} is {}; expected a finite number", name, i, v[i]));
  return v;
}

namespace {
// Nanoseconds since the epoch (a datetime64[ns]) as parse_utc reads the same instant's ISO text.
UtcTime from_unix_ns(long long ns) {
  long long seconds = ns / 1000000000, rest = ns % 1000000000;
  if (rest < 0) {
    --seconds;
    rest += 1000000000;
  }
  return utc_from_unix_ns(seconds, static_cast<std::int32_t>(rest));
}

UtcTime one_utc(const py::handle& obj, const std::string& where) {
  if (py::isinstance<py::str>(obj)) {
    try {
      return parse_utc(obj.cast<std::string>());
    } catch (const std::invalid_argument& e) {
      throw py::value_error(fmt::format("{}: {}", where, e.what()));
    }
  }
  const py::module_ datetime = py::module_::import("datetime");
  if (py::isinstance(obj, datetime.attr("datetime"))) {
    if (obj.attr("utcoffset")().is_none())
      throw py::value_error(fmt::format("{}: {} has no time zone; give a UTC time "
                                        "(tzinfo=datetime.timezone.utc) or an ISO 8601 string with Z",
                                        where, py::repr(obj).cast<std::string>()));
    // Whole seconds and microseconds, exactly (timestamp() would round through a float).
    const py::object utc = obj.attr("astimezone")(datetime.attr("timezone").attr("utc"));
    const long long seconds = py::module_::import("calendar").attr("timegm")(utc.attr("utctimetuple")()).cast<long long>();
    return utc_from_unix_ns(seconds, utc.attr("microsecond").cast<std::int32_t>() * 1000);
  }
  const py::module_ np = py::module_::import("numpy");
  if (py::isinstance(obj, np.attr("datetime64"))) {
    const py::object ns = np.attr("datetime64")(obj, "ns");
    if (py::bool_(np.attr("isnat")(ns)))
      throw py::value_error(fmt::format("{}: NaT is not a time", where));
    return from_unix_ns(ns.attr("astype")("int64").cast<long long>());
  }
  throw py::type_error(fmt::format("{}: expected a UTC time (ISO 8601 string with Z, aware "
                                   "datetime or numpy.datetime64), got {}", where,
                                   py::str(py::type::of(obj)).cast<std::string>()));
}
}  // namespace

std::vector<UtcTime> utc_times(const py::handle& obj, const char* name) {
  const py::module_ np = py::module_::import("numpy");
  if (py::isinstance<py::array>(obj) &&
      py::bool_(np.attr("issubdtype")(obj.attr("dtype"), np.attr("datetime64")))) {
    const py::array ns = np.attr("ravel")(obj).attr("astype")("datetime64[ns]");
    if (py::bool_(np.attr("any")(np.attr("isnat")(ns))))
      throw py::value_error(fmt::format("{}: NaT is not a time (element {})", name,
                                        np.attr("argmax")(np.attr("isnat")(ns)).cast<long long>()));
    const auto ints = ns.attr("view")("int64").cast<py::array_t<long long, py::array::c_style | py::array::forcecast>>();
    std::vector<UtcTime> out(static_cast<std::size_t>(ints.size()));
    for (std::size_t i = 0; i < out.size(); ++i) out[i] = from_unix_ns(ints.data()[i]);
    return out;
  }
  if (py::isinstance<py::str>(obj) || !py::isinstance<py::iterable>(obj)) return {one_utc(obj, name)};
  // Any nesting (a 2-D list, an object or str array): its elements in C order, named by flat index.
  const py::object flat = np.attr("ravel")(np.attr("asarray")(obj, py::arg("dtype") = "object"));
  std::vector<UtcTime> out;
  std::size_t i = 0;
  for (const py::handle item : py::iter(flat))
    out.push_back(one_utc(item, fmt::format("{} (element {})", name, i++)));
  return out;
}

UtcTime utc_time(const py::handle& obj, const char* name) { return one_utc(obj, name); }

ThreadLimit::ThreadLimit(std::optional<int> threads) {
  if (!threads) return;
  if (*threads < 1 || *threads > 1024)
    throw py::value_error(fmt::format("threads={}: expected a whole number in [1, 1024] or None", *threads));
  control_ = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                   static_cast<std::size_t>(*threads));
}

ThreadLimit::~ThreadLimit() = default;

Progress progress_from(const py::object& progress) {
  if (progress.is_none()) return {};
  if (PyBool_Check(progress.ptr())) {
    if (!progress.cast<bool>()) return {};
    return Progress([](const ProgressReport& r) {
      const bool done = r.fraction >= 1;
      std::fprintf(stderr, "\rpolrig: %s\033[K%s", format_progress(r).c_str(), done ? "\n" : "");
      std::fflush(stderr);
    }, 0.5);
  }
  if (!PyCallable_Check(progress.ptr()))
    throw py::type_error("progress: expected None, a bool or a callable f(stage, fraction, eta_s)");
  // The callable outlives this call only inside the Progress, which the call's computation owns;
  // it is released with the GIL held.
  auto f = std::shared_ptr<py::object>(new py::object(progress), [](py::object* p) {
    py::gil_scoped_acquire gil;
    delete p;
  });
  return Progress([f](const ProgressReport& r) {
    py::gil_scoped_acquire gil;
    try {
      (*f)(r.stage, r.fraction, r.eta_s);
    } catch (py::error_already_set& e) {
      e.discard_as_unraisable("polrig progress callback");
    }
  }, 0.5);
}

}  // namespace polrig::python
