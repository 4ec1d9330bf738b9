#pragma once
// The parts of the Python module polrig._polrig (docs/python.md), one function per part of the
// library it exposes; module.cpp calls them in order. A thin layer: every binding converts
// arguments, calls polrig_lib and converts the result. No physics here.
#include <pybind11/pybind11.h>

namespace polrig {
struct FourCameraGeometryCalibration;
}

namespace polrig::python {

void bind_errors(pybind11::module_& m);       // module.cpp: exceptions carrying the CLI's messages
void bind_rig(pybind11::module_& m);          // rig_bindings.cpp: Rig, its keys and YAML
void bind_studies(pybind11::module_& m);      // study_bindings.cpp: simulate, CS study, sweep, adc, trials
void bind_calibration(pybind11::module_& m);  // calibration_bindings.cpp: calibrate, params, apply
void bind_sky(pybind11::module_& m);          // sky_bindings.cpp: sun, sky, drift, spectral
void bind_compass(pybind11::module_& m);          // compass_bindings.cpp: heading, study heading
void bind_orientation(pybind11::module_& m);  // orientation_bindings.cpp: DoFP sun vector, orient
void bind_dofp_calibration(pybind11::module_& m);          // dofp_calibration_bindings.cpp: the DoFP camera's calibration
void bind_dofp_polarization(pybind11::module_& m);         // dofp_calibration_bindings.cpp: a frame's per-cell AoP, DoP
void bind_dofp_dataset_calibration(pybind11::module_& m);  // dofp_calibration_bindings.cpp: a camera dataset
void bind_dofp(pybind11::module_& m);         // dofp_bindings.cpp: the DoFP camera's frames and dataset
void bind_four_camera(pybind11::module_& m);  // four_camera_bindings.cpp: W16's four cameras, fused image, dataset
void bind_position(pybind11::module_& m);     // position_bindings.cpp: fix_position, locate, Eq. 15, study positioning
void bind_four_camera_calibration(pybind11::module_& m);  // four_camera_calibration_bindings.cpp: W16's K, b, ε
void bind_four_camera_geometry(pybind11::module_& m);  // four_camera_geometry_bindings.cpp: the geometric calibration
void bind_navigation(pybind11::module_& m);   // navigation_bindings.cpp: Z21's unit array with an INS
void bind_sky_study(pybind11::module_& m);   // sky_study_bindings.cpp: study sky (each compass under the vector-RT sky)

// The geometric calibration's result as Python's dict (four_camera_geometry_bindings.cpp), for
// fit_four_camera_geometry and calibrate_four_camera's "geometry".
pybind11::dict geometry_calibration_dict(const FourCameraGeometryCalibration& calibration);

}  // namespace polrig::python
