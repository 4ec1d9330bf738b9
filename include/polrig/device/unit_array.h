#pragma once
// Z21's unit-array polarization compass (Zhang et al. 2021, Sensors 21:1055; spec
// sky-and-compasses.md §4.1): n six-photodiode units on a hemisphere, each looking along its own
// axis. This file is the geometry: the layout, each unit's frame m_i in the body frame b and the
// true mounting errors. What each unit reads: calib/unit_array.h (the six-photodiode chain, REUSED);
// the sun from two units: compass/unit_array.h. docs/physics.md §19.
//
// Frames: b is RFU (X_b right, Y_b forward, Z_b up). Unit i's frame m_i: Z_m along its view, X_m
// its zero direction (the six-photodiode sensor's x-axis, through photodiode 1), Y_m = Z_m × X_m.
// C_mi^b is given by its columns (X_m, Y_m, Z_m written in b: vec3.h's Axes3).
//
// Nominal placement (tilt β, azimuth a, roll ρ), azimuth a from X_b towards Y_b (anticlockwise seen
// from above, Z21 Eq. 7's body azimuth):
//   C_mi^b = Rz(a)·Ry(β)·Rz(ρ)      ⇒ Z_m = (sin β·cos a, sin β·sin a, cos β);
// at β = ρ = 0 the unit's frame is the body's (X_m = X_b), and X_m lies in the vertical plane of the
// view for ρ = 0 (pointing away from the zenith). R_a is the active right-hand rotation about axis a.
// True frame, with the unit's mounting error δ_i (about its own axes) and the compass's
// misalignment μ to the body (about the body's axes):
//   C_mi^b,true = Rx(μx)·Ry(μy)·Rz(μz) · C_mi^b · Rx(δx)·Ry(δy)·Rz(δz).
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "polrig/vec3.h"

namespace polrig {

struct UnitPlacement {
  double tilt_deg = 0;     // β: the view's angle from Z_b
  double azimuth_deg = 0;  // a: the view's azimuth, from X_b towards Y_b
  double roll_deg = 0;     // ρ: a turn of the unit about its own view
};

// The rig's device.units.* keys (device.kind unit-array).
struct UnitArraySpec {
  // Default [C] (spec §4.1): one unit at the zenith (index 0) plus eight on a ring tilted 30°, at
  // azimuths 0°, 45°, …, 315°.
  bool zenith_unit = true;
  double ring_tilt_deg = 30.0;
  std::vector<double> ring_azimuths_deg{0, 45, 90, 135, 180, 225, 270, 315};
  // An explicit layout (replaces zenith_unit and the ring when given): one entry per unit, the
  // three lists of equal length (roll may be empty: 0).
  std::vector<double> tilt_deg, azimuth_deg, roll_deg;
  // Mounting errors δ (x, y, z about the unit's own axes, degrees): drawn per unit from a normal
  // of this σ with the rig's seed, unless given explicitly (one entry per unit in each list).
  double mount_error_sd_deg = 0.0;
  std::vector<double> mount_error_x_deg, mount_error_y_deg, mount_error_z_deg;
  // The compass's misalignment μ to the body (about X_b, Y_b, Z_b, degrees): truth only.
  std::array<double, 3> misalignment_deg{0, 0, 0};
  // The calibration model each unit's voltages are read with: "truth" (the unit's own device.truth:
  // a perfectly calibrated sensor) or "theory" (the nominal parameters of its film axes).
  std::string apply = "truth";
  // The compass's output rate: one reading of every unit per 1/rate_hz (Z21 Table 1: 1 Hz).
  double rate_hz = 1.0;
};

// The units' nominal placements, the middle unit (if any) first.
std::vector<UnitPlacement> unit_placements(const UnitArraySpec& spec);
// Why the spec cannot make a layout ("device.units.azimuth_deg" and a message), or nothing:
// explicit lists of unequal length, no unit at all, explicit mounting errors of another length.
struct UnitArrayProblem {
  std::string path;
  std::string message;
};
std::optional<UnitArrayProblem> unit_array_problem(const UnitArraySpec& spec);

// Active right-hand rotations, and Rx(x)·Ry(y)·Rz(z) (degrees).
Axes3 rotation_x(double deg);
Axes3 rotation_y(double deg);
Axes3 rotation_z(double deg);
Axes3 rotation_xyz(double x_deg, double y_deg, double z_deg);

// C_mi^b of a placement: Rz(a)·Ry(β)·Rz(ρ).
Axes3 unit_axes(const UnitPlacement& p);

// The compass as built: each unit's nominal frame (what a user knows) and its true frame.
struct UnitArrayTruth {
  std::vector<UnitPlacement> placements;
  std::vector<std::array<double, 3>> mount_error_deg;  // δ_i (x, y, z)
  std::array<double, 3> misalignment_deg{0, 0, 0};     // μ
  std::vector<Axes3> nominal;                          // C_mi^b
  std::vector<Axes3> actual;                           // C_mi^b,true
};
// The spec's units with their mounting errors: explicit, or σ·standard_normal(seed, 0x554E4954, i,
// axis) (random.h: a pure function of the seed, the unit and the axis). Throws std::invalid_argument
// with unit_array_problem's message.
UnitArrayTruth unit_array_truth(const UnitArraySpec& spec, std::uint64_t seed);

}  // namespace polrig
