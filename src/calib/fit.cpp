#include "polrig/calib/fit.h"

#include <array>
#include <cmath>

#include <Eigen/Dense>
#include <Eigen/SVD>
#include <fmt/format.h>
#include <unsupported/Eigen/LevenbergMarquardt>

namespace polrig {
namespace {

const char* parameter_name(int x) {
  static const char* const kNames[FitParams::kCount] = {
      "alpha_1", "alpha_2", "alpha_3", "alpha_4", "alpha_5", "alpha_6", "k_1", "k_2", "k_3",
      "kv_1",    "kv_2",    "kv_3",    "c_1",     "c_2",     "c_3",     "c_4", "c_5", "c_6"};
  return kNames[x];
}

constexpr double kOutsideDomain_V = 1e3;

// Every status Eigen's Levenberg–Marquardt can return, as a termination. MINPACK's statuses 6–8
// (Ftol/Xtol/GtolTooSmall) say that no further improvement is possible in double precision:
// the iteration has converged as far as it can.
using StatusOutcome = SolverOutcome;
StatusOutcome outcome_of(Eigen::LevenbergMarquardtSpace::Status s) {
  using S = Eigen::LevenbergMarquardtSpace::Status;
  using T = FitTermination;
  switch (s) {
    case S::NotStarted:
      return {"NotStarted", T::NoConvergence, "the iteration did not start"};
    case S::Running:
      return {"Running", T::NoConvergence, "the iteration limit came before convergence"};
    case S::ImproperInputParameters:
      // After fit_eq15's own count of observations (≥ 6 per pair) this can only be the QR
      // step's numerical failure, or tolerances the solver refuses.
      return {"ImproperInputParameters", T::NoConvergence,
              "the solver refused its input or its QR step failed numerically"};
    case S::RelativeReductionTooSmall:
      return {"RelativeReductionTooSmall", T::Converged,
              "the relative reduction of the residual norm is below the function tolerance"};
    case S::RelativeErrorTooSmall:
      return {"RelativeErrorTooSmall", T::Converged,
              "the relative step is below the parameter tolerance"};
    case S::RelativeErrorAndReductionTooSmall:
      return {"RelativeErrorAndReductionTooSmall", T::Converged,
              "the relative reduction and the relative step are below their tolerances"};
    case S::CosinusTooSmall:
      return {"CosinusTooSmall", T::Converged,
              "the residuals are orthogonal to the Jacobian (gradient tolerance)"};
    case S::TooManyFunctionEvaluation:
      return {"TooManyFunctionEvaluation", T::NoConvergence,
              "the evaluation limit came before convergence"};
    case S::FtolTooSmall:
      return {"FtolTooSmall", T::Converged,
              "no further reduction of the residuals is possible in double precision"};
    case S::XtolTooSmall:
      return {"XtolTooSmall", T::Converged,
              "no further improvement of the parameters is possible in double precision"};
    case S::GtolTooSmall:
      return {"GtolTooSmall", T::Converged,
              "the residuals are orthogonal to the Jacobian to double precision"};
    case S::UserAsked:
      return {"UserAsked", T::NoConvergence, "the residual function stopped the iteration"};
  }
  return {"unknown", T::NoConvergence, "unknown solver status"};
}

struct Eq15Residuals : Eigen::DenseFunctor<double> {
  Eq15Residuals(const std::vector<Observation>& d, double v_dec)
      : Eigen::DenseFunctor<double>(FitParams::kCount, static_cast<int>(d.size())),
        data(d),
        volts_per_decade(v_dec) {}

  int operator()(const InputType& x, ValueType& r) const {
    const FitParams p = FitParams::from_vector(x);
    for (std::size_t n = 0; n < data.size(); ++n) {
      const double v = eq15_voltage(p, volts_per_decade, data[n].pair, data[n].theta_deg, data[n].d_ratio);
      // A trial step outside Eq. 15's domain (1 ± c·cos ≤ 0) gets a large residual, so LM
      // rejects it and damps; only a solution outside the domain is an error.
      r(static_cast<Eigen::Index>(n)) = std::isfinite(v) ? v - data[n].volts : kOutsideDomain_V;
    }
    return 0;
  }
  int df(const InputType& x, JacobianType& J) const {
    J = eq15_jacobian(data, FitParams::from_vector(x), volts_per_decade);
    return 0;
  }

  const std::vector<Observation>& data;
  double volts_per_decade;
};

}  // namespace

SolverOutcome levenberg_marquardt_outcome(int eigen_status) {
  return outcome_of(static_cast<Eigen::LevenbergMarquardtSpace::Status>(eigen_status));
}

Eigen::MatrixXd eq15_jacobian(const std::vector<Observation>& data, const FitParams& p,
                              double v_dec) {
  Eigen::MatrixXd J(static_cast<Eigen::Index>(data.size()), FitParams::kCount);
  for (std::size_t n = 0; n < data.size(); ++n)
    J.row(static_cast<Eigen::Index>(n)) =
        eq15_gradient(p, v_dec, data[n].pair, data[n].theta_deg, data[n].d_ratio).transpose();
  return J;
}

std::string_view termination_name(FitTermination t) {
  switch (t) {
    case FitTermination::Converged: return "converged";
    case FitTermination::NoConvergence: return "no_convergence";
    case FitTermination::OutsideDomain: return "outside_domain";
    case FitTermination::RankDeficient: return "rank_deficient";
    case FitTermination::TooFewObservations: return "too_few_observations";
  }
  return "?";
}

std::string FitSummary::brief_report() const {
  if (solver_status.empty())
    return fmt::format("{}: not fitted, {} observations; {}", termination_name(termination),
                       observations, message);
  return fmt::format("{}: {} iterations, {} evaluations, {} observations, cost {:.6g} -> {:.6g} {}; {}",
                     termination_name(termination), iterations, evaluations, observations,
                     initial_cost, final_cost, cost_unit, message);
}

FitResult fit_eq15(const std::vector<Observation>& data, const FitParams& start, double v_dec,
                   const FitOptions& options) {
  if (!(options.max_iterations > 0 && options.max_evaluations > 0 &&
        options.function_tolerance >= 0 && options.parameter_tolerance >= 0 &&
        options.gradient_tolerance >= 0))
    throw std::invalid_argument("fit_eq15: limits must be positive and tolerances ≥ 0");
  FitResult result;
  FitSummary& summary = result.summary;
  summary.observations = static_cast<int>(data.size());
  std::array<int, 3> per_pair{0, 0, 0};
  for (const Observation& o : data) {
    if (o.pair < 0 || o.pair > 2) throw std::invalid_argument("fit_eq15: observation of an unknown pair");
    if (!std::isfinite(o.volts) || !std::isfinite(o.theta_deg))
      throw std::invalid_argument("fit_eq15: an observation is not a finite number");
    if (!(o.d_ratio > 0.0 && std::isfinite(o.d_ratio)))
      throw std::invalid_argument("fit_eq15: an observation's d ratio is not a finite number > 0");
    ++per_pair[static_cast<std::size_t>(o.pair)];
  }
  result.params = start;
  for (int i = 0; i < 3; ++i)
    if (per_pair[static_cast<std::size_t>(i)] < 6) {
      summary.termination = FitTermination::TooFewObservations;
      summary.message = fmt::format(
          "V{} has {} observation(s); Eq. 15 has 6 unknowns per pair, so at least 6 are needed",
          i + 1, per_pair[static_cast<std::size_t>(i)]);
      return result;
    }

  Eq15Residuals f(data, v_dec);
  Eigen::LevenbergMarquardt<Eq15Residuals> lm(f);
  lm.setXtol(options.parameter_tolerance);
  lm.setFtol(options.function_tolerance);
  lm.setGtol(options.gradient_tolerance);
  lm.setMaxfev(options.max_evaluations);
  Eigen::VectorXd x = start.vector();
  using S = Eigen::LevenbergMarquardtSpace::Status;
  S status = lm.minimizeInit(x);
  summary.initial_cost = 0.5 * lm.fvec().squaredNorm();
  if (status == S::NotStarted) {
    status = S::Running;
    while (status == S::Running && lm.njev() < options.max_iterations)
      status = lm.minimizeOneStep(x);
  }
  const StatusOutcome outcome = outcome_of(status);
  summary.solver_status = outcome.name;
  summary.iterations = static_cast<int>(lm.njev());
  summary.evaluations = static_cast<int>(lm.nfev());
  result.params = FitParams::from_vector(x);

  Eigen::VectorXd r(static_cast<Eigen::Index>(data.size()));
  f(x, r);
  const double rss = r.squaredNorm();
  summary.final_cost = 0.5 * rss;
  result.residual_rms_V = std::sqrt(rss / static_cast<double>(data.size()));

  const auto stop = [&](FitTermination t, std::string message) {
    summary.termination = t;
    summary.message = std::move(message);
    return result;
  };
  for (const Observation& o : data)
    if (!std::isfinite(eq15_voltage(result.params, v_dec, o.pair, o.theta_deg, o.d_ratio)))
      return stop(FitTermination::OutsideDomain,
                  fmt::format("the fit ended outside Eq. 15's domain ((1 ± c·cos) ≤ 0): the data "
                              "are not those of this sensor model (solver: {})", outcome.message));
  for (int i = 0; i < 3; ++i)
    if (!(result.params.kv[i] > 0.0))
      return stop(FitTermination::OutsideDomain,
                  fmt::format("the fit gives kv_{} = {:.3g}, not a log-amplifier gain: the voltages "
                              "do not vary with the angle as Eq. 15 says (is the light polarized? "
                              "solver: {})", i + 1, result.params.kv[i], outcome.message));
  if (outcome.termination != FitTermination::Converged)
    return stop(outcome.termination,
                fmt::format("{} ({} iterations, {} evaluations allowed; solver status {})",
                            outcome.message, options.max_iterations, options.max_evaluations,
                            outcome.name));

  // Identifiability: the Jacobian with unit-norm columns (so units do not matter) must have
  // full rank. The right singular vector of the smallest σ names the undetermined direction.
  const Eigen::MatrixXd J = eq15_jacobian(data, result.params, v_dec);
  const Eigen::VectorXd norms = J.colwise().norm().transpose();
  for (int c = 0; c < FitParams::kCount; ++c)
    if (!(norms(c) > 0))
      return stop(FitTermination::RankDeficient,
                  fmt::format("the data cannot determine {} (it has no effect on any voltage; d "
                              "may be too small)", parameter_name(c)));
  const Eigen::MatrixXd Js = J * norms.cwiseInverse().asDiagonal();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(Js, Eigen::ComputeThinV);
  const Eigen::VectorXd sigma = svd.singularValues();
  if (sigma(sigma.size() - 1) < options.min_singular_ratio * sigma(0)) {
    Eigen::Index worst = 0;
    svd.matrixV().col(sigma.size() - 1).cwiseAbs().maxCoeff(&worst);
    return stop(FitTermination::RankDeficient,
                fmt::format("the data cannot determine the parameters (rank-deficient Jacobian, "
                            "σ_min/σ_max = {:.1e}); {} is the least determined: measure over a "
                            "wider range of angles or with more stops",
                            sigma(sigma.size() - 1) / sigma(0),
                            parameter_name(static_cast<int>(worst))));
  }

  const int dof = static_cast<int>(data.size()) - FitParams::kCount;
  FitParams::Vector se = FitParams::Vector::Constant(std::numeric_limits<double>::quiet_NaN());
  if (dof > 0) {
    // (JᵀJ)⁻¹ through the SVD of the scaled Jacobian: V·Σ⁻²·Vᵀ, then undo the column scaling.
    const Eigen::MatrixXd V = svd.matrixV();
    const Eigen::VectorXd inv_s2 = sigma.cwiseAbs2().cwiseInverse();
    const double s2 = rss / dof;
    for (int c = 0; c < FitParams::kCount; ++c)
      se(c) = std::sqrt(s2 * (V.row(c).cwiseAbs2() * inv_s2)(0)) / norms(c);
  }
  result.standard_error = FitParams::from_vector(se);
  return stop(FitTermination::Converged, outcome.message);
}

}  // namespace polrig
