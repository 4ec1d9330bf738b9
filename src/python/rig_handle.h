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
inline pybind11::class_<PyRig> rig_class(pybind11::module_& m) {
  return pybind11::reinterpret_borrow<pybind11::class_<PyRig>>(m.attr("Rig"));
}

}  // namespace polrig::python
