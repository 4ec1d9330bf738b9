#pragma once
// The six-photodiode polarization sensor of Wang et al. 2019 (spec §1, §2, §4): six film
// channels on a ring, paired (1,2), (3,4), (5,6) into three log amplifiers.
#include <array>
#include <cmath>
#include <string>
#include <numbers>

#include "polrig/device/params.h"
#include "polrig/device/electronics.h"
#include "polrig/geometry/geometry.h"

namespace polrig {

struct SensorSpec {
  PhotodiodeRing ring;
  std::array<double, 6> film_axis_deg = kWang2019FilmAxesDeg;  // sensor frame, degrees
  double d = 0.55;  // degree of linear polarization of the light reaching the sensor, in (0, 1)
  CalibrationParams truth = CalibrationParams::wang2019_indoor();
  // A params.yaml (written by `polrig calibrate`) whose α, k, kv, kd replace `truth` when the
  // rig is loaded; empty for none. The loader resolves it, so a loaded rig has it empty.
  std::string truth_from;

  CalibrationParams theory() const { return CalibrationParams::theory(film_axis_deg); }
};

// Channel indices of pair i (0-based): j = 2i, h = 2i + 1 (the paper's j = 2i − 1, h = 2i).
constexpr int pair_j(int i) { return 2 * i; }
constexpr int pair_h(int i) { return 2 * i + 1; }

// Relative response of channel m to light (d, θ), Eq. 15's bracket:
// 1 + (1+kd_m)·d·cos(2θ + α_m) for a j channel, 1 − (1+kd_m)·d·cos(2θ + α_m) for an h channel.
// It is the film's transmission normalised by its unpolarized gain g_up (spec §4).
double channel_response(const CalibrationParams& p, int m, double theta_deg, double d);

// The analyzer film that Eq. 15's α_m stands for: its axis φ_m in the sensor frame, with
// cos(2θ + α_m) = ±cos 2(θ − φ_m) (the inverse of CalibrationParams::theory). Its polarizing
// efficiency is 1 + kd_m.
double film_axis_from_alpha_deg(const CalibrationParams& p, int m);

// Voltage of pair i whose channels receive irradiances E_j and E_h (any common unit), Eq. 15
// with Eq. 5's unequal-irradiance term, both through the amplifier:
//   V_i = kv_i·v_dec·log10[(E_j·R_j) / (E_h·R_h)] + k_i,      v_dec = 0.5 V/decade.
// Responsivity and area are equal in every channel and cancel in the ratio.
double pair_voltage(const CalibrationParams& p, const Electronics& e, int i, double E_j,
                    double E_h, double theta_deg, double d);

std::array<double, 3> pair_voltages(const CalibrationParams& p, const Electronics& e,
                                    const std::array<double, 6>& E, double theta_deg, double d);

// Eq. 5: the part of V_i due to unequal irradiance alone, kv_i·v_dec·log10(E_j/E_h).
// Inline: it is the inner loop of the CS study and of sweeps.
inline double eccentricity_bias_of_log(const CalibrationParams& p, const Electronics& e, int i,
                                       double ln_Ej_over_Eh) {
  return p.kv[i] * e.volts_per_decade * (ln_Ej_over_Eh * (1.0 / std::numbers::ln10));
}
// The same from the irradiances (the CS study takes the logarithms of its ratios in vectors and
// calls eccentricity_bias_of_log).
inline double eccentricity_bias(const CalibrationParams& p, const Electronics& e, int i,
                                double E_j, double E_h) {
  return eccentricity_bias_of_log(p, e, i, std::log(E_j / E_h));
}

}  // namespace polrig
