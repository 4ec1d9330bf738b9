#pragma once
// Iterative least squares for Eq. 15 (spec §4): Levenberg–Marquardt (Eigen) with the exact,
// analytic Jacobian of calib/model.h.
#include <stdexcept>
#include <vector>

#include <Eigen/Core>

#include "polrig/calib/model.h"

namespace polrig {

// A calibration that cannot give a trustworthy answer: too few observations, parameters the
// data cannot determine, a fit that does not converge. what() is the message for the user.
class CalibrationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One measured voltage: pair i (0-based) at reference angle θ (degrees).
struct Observation {
  double theta_deg;
  int pair;
  double volts;
};

struct FitOptions {
  int max_evaluations = 4000;
  double tolerance = 1e-13;        // relative tolerance on parameters and residual norm
  double min_singular_ratio = 1e-9;  // σ_min/σ_max of the scaled Jacobian below this: rank deficient
};

struct FitResult {
  FitParams params;
  FitParams standard_error;  // √diag(s²·(JᵀJ)⁻¹), s² = RSS/(N − 18); NaN when N = 18 (no redundancy)
  double residual_rms_V = 0;
  int observations = 0;
  int iterations = 0;
  int evaluations = 0;
};

// Fits the 18 unknowns from `start`. Throws CalibrationError when a pair has fewer than 6
// observations, when the Jacobian at the solution is rank deficient (names the parameter the
// data leave undetermined), or when the iteration fails to converge.
FitResult fit_eq15(const std::vector<Observation>& data, const FitParams& start,
                   double volts_per_decade, const FitOptions& options = {});

// The Jacobian of the residuals (rows: observations; columns: the 18 unknowns).
Eigen::MatrixXd eq15_jacobian(const std::vector<Observation>& data, const FitParams& p,
                              double volts_per_decade);

}  // namespace polrig
