#pragma once
// Iterative least squares for Eq. 15 (spec §4): Levenberg–Marquardt (Eigen) with the exact,
// analytic Jacobian of calib/model.h. A fit that fails is an outcome, not an exception: its
// FitSummary (after Ceres Solver's Solver::Summary) says how and why it stopped.
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <string_view>
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

// One measured voltage: pair i (0-based) at reference angle θ (degrees), from point `row` of
// the data being calibrated (a stop or a CS point). d_ratio = d(t)/d(t_0) when the light's
// degree of polarization changes during the run (the sky, --drift per-stop); 1 otherwise.
struct Observation {
  double theta_deg;
  int pair;
  double volts;
  std::size_t row = 0;
  double d_ratio = 1.0;
};

// Work is bounded by counts, never by time, so that a fit is the same on any machine. A good
// Eq. 15 fit needs 4–7 iterations; every iteration costs one Jacobian and a QR of N × 18.
struct FitOptions {
  int max_iterations = 50;      // Jacobian evaluations (Ceres's default max_num_iterations)
  int max_evaluations = 200;    // residual evaluations, rejected trial steps included
  double function_tolerance = 1e-13;   // relative reduction of the residual norm (MINPACK ftol)
  double parameter_tolerance = 1e-13;  // relative size of the step (MINPACK xtol)
  double gradient_tolerance = 0;       // cosine between residual and Jacobian columns (gtol)
  double min_singular_ratio = 1e-9;  // σ_min/σ_max of the scaled Jacobian below this: rank deficient
};

// How a fit ended. Only Converged gives parameters to use.
enum class FitTermination {
  Converged,          // a convergence test was met, in Eq. 15's domain, every parameter determined
  NoConvergence,      // the iteration or evaluation limit came first
  OutsideDomain,      // ended where Eq. 15 is undefined (1 ± c·cos ≤ 0) or with a gain kv ≤ 0
  RankDeficient,      // the data cannot determine every parameter (or the angle signal vanishes)
  TooFewObservations  // a pair has fewer observations than its 6 unknowns
};
inline constexpr FitTermination kAllTerminations[] = {
    FitTermination::Converged, FitTermination::NoConvergence, FitTermination::OutsideDomain,
    FitTermination::RankDeficient, FitTermination::TooFewObservations};
// "converged", "no_convergence", "outside_domain", "rank_deficient", "too_few_observations".
std::string_view termination_name(FitTermination t);

struct FitSummary {
  FitTermination termination = FitTermination::TooFewObservations;
  std::string message;         // why it stopped, for the user
  std::string solver_status;   // Eigen's LevenbergMarquardtSpace::Status, "" if LM did not run
  double initial_cost = std::numeric_limits<double>::quiet_NaN();  // ½·Σr² at the start, in cost_unit
  double final_cost = std::numeric_limits<double>::quiet_NaN();    // ½·Σr² at the end
  const char* cost_unit = "V^2";  // Eq. 15's voltages; each other fit names its residuals' unit
  int iterations = 0;   // Jacobian evaluations
  int evaluations = 0;  // residual evaluations
  int observations = 0;

  bool usable() const { return termination == FitTermination::Converged; }
  // One line: termination, iterations, evaluations, observations, costs and the message
  // ("not fitted" instead of the counts when the solver did not run).
  std::string brief_report() const;
};

// How Eigen's Levenberg–Marquardt ended, for every fit that runs it: its
// LevenbergMarquardtSpace::Status (as an int), the status's name, the termination it means and a
// message for the user.
struct SolverOutcome {
  const char* name;
  FitTermination termination;
  const char* message;
};
SolverOutcome levenberg_marquardt_outcome(int eigen_status);

struct FitResult {
  FitParams params;          // where the fit ended (meaningful only when summary.usable())
  FitParams standard_error;  // √diag(s²·(JᵀJ)⁻¹), s² = RSS/(N − 18); NaN when N = 18 (no redundancy)
  double residual_rms_V = std::numeric_limits<double>::quiet_NaN();
  FitSummary summary;
};

// Fits the 18 unknowns from `start`. Never throws for data that cannot be fitted: the summary
// says why (too few observations per pair, no convergence within the limits, a solution
// outside Eq. 15's domain, a rank-deficient Jacobian naming the least determined parameter).
// Throws std::invalid_argument for a programming error (unknown pair, non-finite observation,
// invalid options).
FitResult fit_eq15(const std::vector<Observation>& data, const FitParams& start,
                   double volts_per_decade, const FitOptions& options = {});

// The Jacobian of the residuals (rows: observations; columns: the 18 unknowns).
Eigen::MatrixXd eq15_jacobian(const std::vector<Observation>& data, const FitParams& p,
                              double volts_per_decade);

}  // namespace polrig
