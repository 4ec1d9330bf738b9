#pragma once
// What every binding shares: NumPy arrays in and out without per-element Python work, the thread
// limit, progress reports, and how a long call releases the GIL.
#include <array>
#include <cstddef>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <tbb/global_control.h>

#include "polrig/progress.h"
#include "polrig/sky/sun.h"

namespace polrig::python {
namespace py = pybind11;

// A float64 input array: any object NumPy can convert, copied only when it is not already a
// C-contiguous float64 array.
using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// A NumPy array that takes over a vector's storage: no copy, freed when the array is.
template <class T>
py::array_t<T> take(std::vector<T>&& values, std::vector<py::ssize_t> shape) {
  auto* owned = new std::vector<T>(std::move(values));
  py::capsule free_when_done(owned, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return py::array_t<T>(std::move(shape), owned->data(), free_when_done);
}
template <class T>
py::array_t<T> take(std::vector<T>&& values) {
  const auto n = static_cast<py::ssize_t>(values.size());
  return take(std::move(values), {n});
}

// A fresh array of the given shape, for results written in place (a sweep's columns).
py::array_t<double> empty_array(std::vector<py::ssize_t> shape);

// `a` made read-only (NumPy's writeable flag cleared): a result object hands out the same array
// on every read, so writing into it would change what later reads see. Writing raises ValueError.
template <class A>
A read_only(A a) {
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

// No NaN or inf leaves a call where the CLI would refuse to write it (its CsvTable): every value
// of a result must be finite, or NaN where `allow_nan` (a ratio over a zero denominator, a closed
// form the source lacks: the CLI's allow_undefined columns). Else RuntimeError naming `name` and
// the element's index in `shape` (the flat index when shape is empty).
void check_finite(const double* values, std::size_t n, const std::string& name, bool allow_nan,
                  const std::vector<py::ssize_t>& shape = {});
inline void check_finite(const py::array_t<double>& a, const std::string& name, bool allow_nan) {
  check_finite(a.data(), static_cast<std::size_t>(a.size()), name, allow_nan,
               std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim()));
}

// Copies of fixed-size C++ arrays: a (n,) array.
template <std::size_t N>
py::array_t<double> to_array(const std::array<double, N>& a) {
  return take(std::vector<double>(a.begin(), a.end()));
}

// `obj` as a float64 array of `ndim` dimensions (0: any), or ValueError naming `name` and the
// shape it has: "V: expected a 2-D array of shape (N, 3), got shape (4,)". `columns` > 0 fixes
// the last dimension.
DoubleArray as_array(const py::handle& obj, const char* name, int ndim = 1, py::ssize_t columns = 0);
// The array's values in a vector; each must be finite, else ValueError naming `name` and the index.
std::vector<double> finite_values(const DoubleArray& a, const char* name);

// UTC instants from Python: an ISO 8601 string with a Z ("2018-11-16T08:09:40Z", as the CLI's
// --utc), a timezone-aware datetime.datetime, a numpy.datetime64 (read as UTC), or a sequence or
// array of these (a datetime64 array converts without per-element Python work). ValueError naming
// `name`, the index and the text otherwise (sky/sun.h's parse_utc message).
std::vector<UtcTime> utc_times(const py::handle& obj, const char* name);
// Exactly one instant (a scalar of the forms above).
UtcTime utc_time(const py::handle& obj, const char* name);

// `threads=` of every parallel call: the most worker threads TBB may use while it lives (None:
// all cores). Results do not depend on it. ValueError outside [1, 1024].
class ThreadLimit {
 public:
  explicit ThreadLimit(std::optional<int> threads);
  ~ThreadLimit();
  ThreadLimit(const ThreadLimit&) = delete;
  ThreadLimit& operator=(const ThreadLimit&) = delete;

 private:
  std::unique_ptr<tbb::global_control> control_;
};

// `progress=` of every long call: None or False, no reports; True, the CLI's line on stderr
// ("polrig: study cs: poses  42 %  ETA 0:13"); a callable, called as f(stage, fraction, eta_s)
// with the GIL held (eta_s < 0 while unknown). An exception in the callable is reported as
// unraisable and does not stop the computation.
Progress progress_from(const py::object& progress);

// Documentation of the shared keyword arguments, appended to docstrings.
inline constexpr const char* kThreadsDoc =
    "threads: the most worker threads (None: all cores); results do not depend on it.";
inline constexpr const char* kProgressDoc =
    "progress: None/False (quiet), True (a line on stderr, as the CLI), or a callable "
    "f(stage: str, fraction: float, eta_s: float).";

// A docstring with the marks {threads} and {progress} replaced by the two texts above.
inline std::string with_shared(const char* text) {
  std::string s = text;
  for (const auto& [mark, what] : {std::pair{"{threads}", kThreadsDoc}, std::pair{"{progress}", kProgressDoc}})
    if (const auto at = s.find(mark); at != std::string::npos) s.replace(at, std::strlen(mark), what);
  return s;
}

// An array argument as the caller gave it (a list, an int array, ...), converted later by
// as_array, whose errors name the argument; help() shows it as numpy.typing.ArrayLike instead of
// pybind11's "handle".
struct ArrayLike {
  py::object obj;
};

}  // namespace polrig::python

namespace pybind11::detail {
template <>
struct type_caster<polrig::python::ArrayLike> {
  PYBIND11_TYPE_CASTER(polrig::python::ArrayLike, const_name("numpy.typing.ArrayLike"));
  bool load(handle src, bool) {
    value.obj = reinterpret_borrow<object>(src);
    return true;
  }
  static handle cast(const polrig::python::ArrayLike& a, return_value_policy, handle) {
    return a.obj.inc_ref();
  }
};
}  // namespace pybind11::detail
