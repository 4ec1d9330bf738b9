#pragma once
// Eq. 15 as a function of the calibration's 18 unknowns (spec §4, Wang et al. 2019 §3.4–3.5).
//
// d and (1 + kd_m) appear only as products, so the fit estimates c_m = (1 + kd_m)·d; the
// decoupling step then picks d_a and sets kd_m = c_m/d_a − 1.
#include <array>

#include <Eigen/Core>

#include "polrig/device/params.h"

namespace polrig {

struct FitParams {
  static constexpr int kCount = 18;
  using Vector = Eigen::Matrix<double, kCount, 1>;

  std::array<double, 6> alpha_deg{};  // doubled-angle installation angles
  std::array<double, 3> k_mV{};
  std::array<double, 3> kv{};
  std::array<double, 6> c{};          // (1 + kd_m)·d

  // Layout of the vector: α_1..6, k_1..3, kv_1..3, c_1..6.
  Vector vector() const;
  static FitParams from_vector(const Vector& x);
  static constexpr int alpha_index(int m) { return m; }
  static constexpr int k_index(int i) { return 6 + i; }
  static constexpr int kv_index(int i) { return 9 + i; }
  static constexpr int c_index(int m) { return 12 + m; }

  // c_m = (1 + kd_m)·d.
  static FitParams coupled(const CalibrationParams& p, double d);
  // kd_m = c_m/d_a − 1 (§3.5). The choice of d_a changes the reported d, never θ.
  CalibrationParams decoupled(double d_a) const;
};

// Eq. 15 for pair i (0-based) at polarization angle θ:
//   V_i = kv_i·v_dec·log10[(1 + r·c_j·cos(2θ + α_j)) / (1 − r·c_h·cos(2θ + α_h))] + k_i.
// r = d(t)/d(t_0) is the light's degree of polarization at this observation relative to the
// one c describes (1 for a source whose d does not change; the sky's zenith d follows the sun,
// spec sky-and-compasses.md §1.4). Returns NaN where a bracket is not positive.
double eq15_voltage(const FitParams& p, double volts_per_decade, int pair, double theta_deg,
                    double d_ratio = 1.0);

// ∂V_i/∂x for the 18 unknowns (degrees for α, mV for k); only pair i's six are non-zero.
FitParams::Vector eq15_gradient(const FitParams& p, double volts_per_decade, int pair,
                                double theta_deg, double d_ratio = 1.0);

}  // namespace polrig
