#pragma once
// Installation calibration of a unit-array compass (Z21 §3.2.2 and Table 2; spec sky-and-compasses.md
// §4.6 item 5; docs/physics.md §19.1): each unit's three mounting errors δ_i, fitted by
// Levenberg–Marquardt to its readings over a static sequence whose sun is known (the ephemeris)
// and whose attitude is known (the INS or a turntable). Frames and senses as compass/unit_array.h.
//
// Model: unit i truly at C_mi^b·Rx(δx)·Ry(δy)·Rz(δz); at epoch k the sun in b is
// s_k^b = C_n^b,k·s_k^n and the unit's view v = C·Z; its predicted reading is the spec's angle (§1.3)
// of e = s^b × v in that frame, φ̂ = atan2(e·(k × X), e·X), k = −Z; residual r_k = φ_k − φ̂_k wrapped
// to (−90°, 90°]. A misalignment of the whole compass is the same body rotation in every unit's
// δ and is absorbed by them (the fit returns the true frames, whatever the split).
#include <array>
#include <span>
#include <string>
#include <vector>

#include "polrig/compass/unit_array.h"

namespace polrig {

struct InstallationEpoch {
  Axes3 C_bn;                         // the body's attitude (C_b^n by columns)
  Vec3 sun_enu{};                     // the ephemeris sun, ENU unit vector
  std::vector<UnitReading> readings;  // one per unit, as the mounts
};

struct UnitInstallationSettings {
  double min_dop = 0.05;       // readings below this DoP are left out [C]
  int max_iterations = 100;    // Levenberg–Marquardt iterations per unit
};

// One unit's fit; failures are data.
struct UnitInstallation {
  std::array<double, 3> error_deg{0, 0, 0};           // δ (x, y, z about the unit's own axes)
  std::array<double, 3> standard_error_deg{0, 0, 0};  // from σ²·(JᵀJ)⁻¹, σ² = Σr²/(m − 3); nan when rank deficient
  double rms_before_deg = 0;  // the residuals with δ = 0 (the nominal frame)
  double rms_after_deg = 0;   // at the fit
  int used = 0;               // readings with d ≥ min_dop and a finite angle
  int iterations = 0;
  // Eigen's status ("RelativeErrorTooSmall" …; "IterationLimit" where Eigen still runs), "RankDeficient"
  // (JᵀJ singular to 1e-10: the readings fix fewer than three angles), or "too-few-readings" (< 4).
  std::string termination;
  bool converged = false;
  Axes3 C_mb{};               // the calibrated frame C_mi^b·R(δ)
};

// Every unit, independently. Throws std::invalid_argument when an epoch's readings are not one per mount.
std::vector<UnitInstallation> calibrate_installation(std::span<const UnitMount> nominal,
                                                     std::span<const InstallationEpoch> epochs,
                                                     const UnitInstallationSettings& settings = {});

// The frame of a unit mounted with error δ (x, y, z, degrees): C_mi^b·Rx(δx)·Ry(δy)·Rz(δz), as the fit
// models it (UnitInstallation::C_mb), for a calibration read back from its file.
Axes3 installed_frame(const Axes3& nominal, const std::array<double, 3>& error_deg);

// The predicted reading φ̂ (spec sense, [0, π)) of a unit with frame C_mb seeing the sun s^b.
double predicted_unit_aop_rad(const Axes3& C_mb, const Vec3& sun_b);

}  // namespace polrig
