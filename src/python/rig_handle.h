#pragma once
// The Python Rig: a rig and how it was made (its text, origin and overrides), so that setting a
// key re-reads the rig with one more override and runs exactly the checks of `--set`.
#include <pybind11/pybind11.h>

#include "polrig/io/rig_yaml.h"

namespace polrig::python {

struct PyRig {
  LoadedRig loaded;
  const Rig& rig() const { return loaded.rig; }
};

// The registered class polrig.Rig, for the parts that add methods to it (study_bindings.cpp).
// The CLI's capability check (rig/rig.h), with the rig's origin: the same message as the CLI's.
inline void require(const PyRig& r, Instrument::Flag needs, std::string_view what) {
  require_instrument(r.rig(), needs, what, r.loaded.origin);
}

inline pybind11::class_<PyRig> rig_class(pybind11::module_& m) {
  return pybind11::reinterpret_borrow<pybind11::class_<PyRig>>(m.attr("Rig"));
}

}  // namespace polrig::python
