#pragma once
// What each unit of Z21's unit-array compass reads (spec sky-and-compasses.md §4.1–4.2, §1.3;
// docs/physics.md §19): the sky along the unit's true view, through the six-photodiode sensor's own
// chain — its films and log amplifiers (device/sensor.h: pair_voltages with the rig's device.truth,
// equal irradiance on the six channels: the sky is at infinity), Gaussian noise per sample
// (electronics.noise_sigma_V), the ADC, the mean of schedule.samples_per_stop samples, and
// measured_angles (calib/angles.h, `polrig apply`) with the unit's calibration model
// (device.units.apply). Its AoP and DoP are then the ones `apply` gives: θ_sec and the d of the
// pair it used.
//
// Sense: the chain's θ is polrig's sensor frame (physics.md §1, §10: from X_m towards Y_m,
// right-handed about the view); a unit reports the spec's sense (§0: right-handed about k = −v),
// φ = −θ mod π, which compass/unit_array.h's E^m = [cos φ, −sin φ, 0] expects.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "polrig/device/unit_array.h"
#include "polrig/rig/rig.h"
#include "polrig/sky/sky.h"
#include "polrig/vec3.h"

namespace polrig {

struct UnitSample {
  double aop_rad = 0;              // φ in the unit's frame (spec sense), [0, π); NaN with a problem
  double dop = 0;                  // d of the pair θ_sec used; NaN with a problem
  std::array<double, 3> V{};       // pair voltages, the mean of the quantised samples (V)
  std::string problem;             // measured_angles' reason when there is no angle, else ""
  double true_aop_rad = 0;         // the sky along the true view, in the true frame (spec sense)
  double true_dop = 0;             // P(γ) there
  Vec3 view_enu{};                 // the unit's true view in n
};

// Each unit of `truth` at time t, the body's axes C_bn (C_b^n by columns: compass/unit_array.h's
// body_axes_enu) under `sky` (its site, sun settings and model; sky.first_stop is not used).
// Noise: standard_normal(seed, sample_index, 3·unit + pair, k) for sample k: a pure function of
// its counters, bit-identical for any thread count and order. The rig gives device.truth,
// electronics, schedule.samples_per_stop and device.units.apply.
std::vector<UnitSample> read_units(const Rig& rig, const UnitArrayTruth& truth, const Sky& sky, UtcTime t,
                                   const Axes3& C_bn, std::uint64_t seed, std::uint64_t sample_index);
// The same with the sun's direction in n (unit ENU vector) given, from an ephemeris computed once
// by the caller, and the sky's model.
std::vector<UnitSample> read_units(const Rig& rig, const UnitArrayTruth& truth, const Vec3& sun_enu,
                                   const SkyModel& model, const Axes3& C_bn, std::uint64_t seed,
                                   std::uint64_t sample_index);
// The same with the rig's compass: unit_array_truth(rig.units, rig.seed).
std::vector<UnitSample> read_units(const Rig& rig, const Sky& sky, UtcTime t, const Axes3& C_bn,
                                   std::uint64_t seed, std::uint64_t sample_index);

// The truth variant: no sensor, no noise: φ = atan2(e·(k × X_m), e·X_m) mod π (spec §1.3's θ_meas,
// k = −Z_m) and d = P(γ) of the exact single-scattering sky, e = s × v/|s × v| (sky/rayleigh.h).
// V is zero. Along the sun's line (e undefined) φ = 0, d = 0.
std::vector<UnitSample> read_units_truth(const UnitArrayTruth& truth, const Sky& sky, UtcTime t,
                                         const Axes3& C_bn);

}  // namespace polrig
