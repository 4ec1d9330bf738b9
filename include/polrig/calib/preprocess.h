#pragma once
// Preparing stops for the fit: central-symmetry pairing (spec §3) and the noncontinuous
// selection (spec §3, Eq. 10).
#include <array>
#include <string>
#include <vector>

#include "polrig/calib/fit.h"

namespace polrig {

// The voltages recorded at one table stop. `label` names it in error messages
// ("stops.csv:12" or "stop 11").
struct StopVoltages {
  double theta_R_deg;
  std::array<double, 3> V;
  std::string label;
};

// A CS point: stops a and b with θ_R,b − θ_R,a ≡ 180° (mod 360°), V = (V_a + V_b)/2, at the
// reference angle θ_R,a. Both see the same polarization angle.
struct CsPoint {
  double theta_R_deg;
  std::array<double, 3> V;
  std::size_t first, second;  // indices into the stops
};

// Every pair a < b of stops 180° apart (within tol_deg). The paper's 0°:10°:360° schedule gives
// 19 points (a stop may belong to two pairs: 180° pairs with 0° and with 360°). Rows with the
// same θ_R (exactly) are repeated measurements of one stop, e.g. a samples.csv: they are
// averaged into one stop first, which keeps its first row's index. O(N log N): the stops are
// sorted by their angle mod 360°. Throws CalibrationError naming any stop that has no partner.
std::vector<CsPoint> central_symmetry_points(const std::vector<StopVoltages>& stops,
                                             double tol_deg = 1e-6);

// The noncontinuous method's rule: keep an observation of V_i where its slope |dV_i/dθ| is at
// least `min_relative_slope` times the largest slope of V_i over the points; if fewer than
// `min_points` pass, keep the `min_points` steepest.
struct NoncontinuousRule {
  double min_relative_slope = 0.5;
  int min_points = 6;
};

// Applies the rule with the slopes dV_i/dθ of `model` (Eq. 10 generalised to Eq. 15: with
// theory parameters it is −2·d·sin(2θ − φ_i)/(ln10·(1 − d²cos²(2θ − φ_i)))).
std::vector<Observation> select_noncontinuous(const std::vector<Observation>& data,
                                              const FitParams& model, double volts_per_decade,
                                              const NoncontinuousRule& rule);

// dV_i/dθ of Eq. 15, in volts per radian of θ (d_ratio as in eq15_voltage).
double eq15_slope(const FitParams& p, double volts_per_decade, int pair, double theta_deg,
                  double d_ratio = 1.0);

}  // namespace polrig
