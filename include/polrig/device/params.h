#pragma once
// The calibration parameters of the six-photodiode sensor, Eq. 15 of Wang et al. 2019
// (spec sensor-and-rig.md §4). They are both the ground truth a simulated device carries and
// what a calibration estimates.
#include <array>

namespace polrig {

struct CalibrationParams {
  // Installation angles α_m in the doubled-angle domain (degrees). Channel j = 2i−1 of pair i
  // responds to 1 + (1+kd_j)·d·cos(2θ + α_j), channel h = 2i to 1 − (1+kd_h)·d·cos(2θ + α_h).
  std::array<double, 6> alpha_deg{0, 0, -120, -120, 120, 120};
  std::array<double, 3> k_mV{0, 0, 0};     // additive offset of each pair's voltage
  std::array<double, 3> kv{1, 1, 1};       // log-amplifier reference (gain) deviation
  std::array<double, 6> kd{0, 0, 0, 0, 0, 0};  // non-ideal polarizer: (τM−τm)/(τM+τm) − 1 ≤ 0

  // Nominal values for films at the given axes (degrees in the sensor frame):
  // α_j = −2·f_j and α_h = 180° − 2·f_h, wrapped to (−180°, 180°]; k = 0, kv = 1, kd = 0.
  static CalibrationParams theory(const std::array<double, 6>& film_axis_deg);
  // Table 2, "Indoor" column of Wang et al. 2019.
  static CalibrationParams wang2019_indoor();

  bool operator==(const CalibrationParams&) const = default;
};

// The film axes of the seed sensor: 0°, 90°, 60°, 150°, 120°, 210° for m = 1..6.
inline constexpr std::array<double, 6> kWang2019FilmAxesDeg{0, 90, 60, 150, 120, 210};

}  // namespace polrig
