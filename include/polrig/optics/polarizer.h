#pragma once
// Stokes vectors and the Mueller matrix of a sheet linear polarizer (spec §4: τM parallel, τm
// crossed; g_up = (τM + τm)/2, g_tp = (τM − τm)/2), at normal incidence.
#include <Eigen/Core>

namespace polrig {

using Stokes = Eigen::Vector4d;          // (S0, S1, S2, S3), angles from the frame's x-axis
using MuellerMatrix = Eigen::Matrix4d;

// Linear polarizer with transmittances τM along its axis and τm across it, axis at `axis_deg`.
MuellerMatrix linear_polarizer(double tau_M, double tau_m, double axis_deg);
// Rotation of the reference frame by `deg` (anticlockwise): S' = R(deg)·S.
MuellerMatrix frame_rotation(double deg);

Stokes unpolarized(double S0);
// Light of irradiance S0, degree of linear polarization d, angle `angle_deg`.
Stokes linearly_polarized(double S0, double d, double angle_deg);

}  // namespace polrig
