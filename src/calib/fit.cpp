#include "polrig/calib/fit.h"

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

struct Eq15Residuals : Eigen::DenseFunctor<double> {
  Eq15Residuals(const std::vector<Observation>& d, double v_dec)
      : Eigen::DenseFunctor<double>(FitParams::kCount, static_cast<int>(d.size())),
        data(d),
        volts_per_decade(v_dec) {}

  int operator()(const InputType& x, ValueType& r) const {
    const FitParams p = FitParams::from_vector(x);
    for (std::size_t n = 0; n < data.size(); ++n) {
      const double v = eq15_voltage(p, volts_per_decade, data[n].pair, data[n].theta_deg);
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

Eigen::MatrixXd eq15_jacobian(const std::vector<Observation>& data, const FitParams& p,
                              double v_dec) {
  Eigen::MatrixXd J(static_cast<Eigen::Index>(data.size()), FitParams::kCount);
  for (std::size_t n = 0; n < data.size(); ++n)
    J.row(static_cast<Eigen::Index>(n)) =
        eq15_gradient(p, v_dec, data[n].pair, data[n].theta_deg).transpose();
  return J;
}

FitResult fit_eq15(const std::vector<Observation>& data, const FitParams& start, double v_dec,
                   const FitOptions& options) {
  std::array<int, 3> per_pair{0, 0, 0};
  for (const Observation& o : data) {
    if (o.pair < 0 || o.pair > 2) throw CalibrationError("observation of an unknown pair");
    if (!std::isfinite(o.volts) || !std::isfinite(o.theta_deg))
      throw CalibrationError("an observation is not a finite number");
    ++per_pair[static_cast<std::size_t>(o.pair)];
  }
  for (int i = 0; i < 3; ++i)
    if (per_pair[static_cast<std::size_t>(i)] < 6)
      throw CalibrationError(fmt::format(
          "V{} has {} observation(s); Eq. 15 has 6 unknowns per pair, so at least 6 are needed",
          i + 1, per_pair[static_cast<std::size_t>(i)]));

  Eq15Residuals f(data, v_dec);
  Eigen::LevenbergMarquardt<Eq15Residuals> lm(f);
  lm.setXtol(options.tolerance);
  lm.setFtol(options.tolerance);
  lm.setMaxfev(options.max_evaluations);
  Eigen::VectorXd x = start.vector();
  const auto status = lm.minimize(x);
  using S = Eigen::LevenbergMarquardtSpace::Status;
  for (const Observation& o : data)
    if (!std::isfinite(eq15_voltage(FitParams::from_vector(x), v_dec, o.pair, o.theta_deg)))
      throw CalibrationError("the fit ended outside Eq. 15's domain ((1 ± c·cos) ≤ 0): the data "
                             "are not those of this sensor model");
  if (status == S::TooManyFunctionEvaluation || status == S::ImproperInputParameters)
    throw CalibrationError(fmt::format("the fit did not converge in {} evaluations",
                                       options.max_evaluations));

  FitResult result;
  result.params = FitParams::from_vector(x);
  for (int i = 0; i < 3; ++i)
    if (!(result.params.kv[i] > 0.0))
      throw CalibrationError(fmt::format(
          "the fit gives kv_{} = {:.3g}, not a log-amplifier gain: the voltages do not vary with the "
          "angle as Eq. 15 says (is the light polarized?)", i + 1, result.params.kv[i]));
  result.observations = static_cast<int>(data.size());
  result.iterations = static_cast<int>(lm.iterations());
  result.evaluations = static_cast<int>(lm.nfev());

  // Identifiability: the Jacobian with unit-norm columns (so units do not matter) must have
  // full rank. The right singular vector of the smallest σ names the undetermined direction.
  const Eigen::MatrixXd J = eq15_jacobian(data, result.params, v_dec);
  const Eigen::VectorXd norms = J.colwise().norm().transpose();
  for (int c = 0; c < FitParams::kCount; ++c)
    if (!(norms(c) > 0))
      throw CalibrationError(fmt::format("the data cannot determine {} (it has no effect on any "
                                         "voltage; d may be too small)", parameter_name(c)));
  const Eigen::MatrixXd Js = J * norms.cwiseInverse().asDiagonal();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(Js, Eigen::ComputeThinV);
  const Eigen::VectorXd sigma = svd.singularValues();
  if (sigma(sigma.size() - 1) < options.min_singular_ratio * sigma(0)) {
    Eigen::Index worst = 0;
    svd.matrixV().col(sigma.size() - 1).cwiseAbs().maxCoeff(&worst);
    throw CalibrationError(fmt::format(
        "the data cannot determine the parameters (rank-deficient Jacobian, σ_min/σ_max = {:.1e}); "
        "{} is the least determined: measure over a wider range of angles or with more stops",
        sigma(sigma.size() - 1) / sigma(0), parameter_name(static_cast<int>(worst))));
  }

  Eigen::VectorXd r(static_cast<Eigen::Index>(data.size()));
  f(x, r);
  const double rss = r.squaredNorm();
  result.residual_rms_V = std::sqrt(rss / static_cast<double>(data.size()));
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
  return result;
}

}  // namespace polrig
