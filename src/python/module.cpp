// The compiled part of the Python package polrig (python/polrig/__init__.py re-exports it).
#include <pybind11/pybind11.h>

#include <iostream>
#include <string>

#include "bindings.h"
#include "polrig/calib/fit.h"
#include "polrig/freed_memory.h"
#include "polrig/io/measured.h"
#include "polrig/io/sphere_cache.h"
#include "polrig/rig/error.h"
#include "polrig/version.h"

namespace polrig::python {

void bind_errors(pybind11::module_& m) {
  // The library's errors keep their messages (file, line, key and value, as the CLI prints
  // them). Bad rigs and data are ValueErrors; a calibration that cannot be formed is a
  // RuntimeError. std::invalid_argument and std::out_of_range become ValueError and IndexError.
  pybind11::register_exception<RigError>(m, "RigError", PyExc_ValueError).doc() =
      "A bad rig: a rig file, a key's value, a grid or a scene it names (the CLI's exit 2).";
  pybind11::register_exception<DataError>(m, "DataError", PyExc_ValueError).doc() =
      "Bad data: a CSV or YAML file's file, line, column and value (the CLI's exit 2).";
  pybind11::register_exception<CalibrationError>(m, "CalibrationError", PyExc_RuntimeError).doc() =
      "Stops that cannot form a calibration (unpaired CS stops, d_a outside (0, 1)).";
}

}  // namespace polrig::python

PYBIND11_MODULE(_polrig, m) {
  // The sphere cache, as the CLI's (docs/cli.md): from POLRIG_CACHE_DIR at import; its warnings
  // go to stderr as the CLI's do (they may come from a worker thread, without the GIL).
  polrig::install_sphere_cache(polrig::sphere_cache_from_environment(true, [](const std::string& warning) {
    std::cerr << "polrig: warning: " << warning << "\n";
  }));
  m.doc() = "polrig: simulation and calibration of polarization-sensor calibration rigs "
            "(docs/python.md).";
  m.attr("__version__") = POLRIG_VERSION;
  m.attr("git_revision") = POLRIG_GIT_REVISION;
  m.def("keep_freed_memory", &polrig::keep_freed_memory,
        "Keep freed buffers for reuse instead of giving them back to the system (glibc's malloc: "
        "its mmap threshold at its 32 MiB ceiling, trimming past 1 GiB), as the CLI does: a loop "
        "over a dataset's stops then stops paying the kernel to map and zero each stop's images "
        "again. Process-wide; the process keeps about its peak memory. Call it once, early.");
  polrig::python::bind_errors(m);
  polrig::python::bind_rig(m);
  polrig::python::bind_studies(m);
  polrig::python::bind_calibration(m);
  polrig::python::bind_sky(m);
  polrig::python::bind_compass(m);
  polrig::python::bind_orientation(m);
  polrig::python::bind_dofp_calibration(m);
  polrig::python::bind_dofp_polarization(m);
  polrig::python::bind_dofp_dataset_calibration(m);
  polrig::python::bind_dofp(m);
  polrig::python::bind_position(m);
  polrig::python::bind_four_camera(m);
  polrig::python::bind_four_camera_calibration(m);
  polrig::python::bind_navigation(m);
  polrig::python::bind_sky_study(m);
  polrig::python::bind_four_camera_geometry(m);
}
