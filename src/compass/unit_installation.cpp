#include "polrig/compass/unit_installation.h"

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include <Eigen/Dense>
#include <fmt/format.h>
#include <unsupported/Eigen/LevenbergMarquardt>

#include "polrig/lm_status.h"
#include "polrig/units.h"

namespace polrig {

namespace {

Axes3 rot(int axis, double rad) {
  const double c = std::cos(rad), s = std::sin(rad);
  if (axis == 0) return {Vec3{1, 0, 0}, Vec3{0, c, s}, Vec3{0, -s, c}};
  if (axis == 1) return {Vec3{c, 0, -s}, Vec3{0, 1, 0}, Vec3{s, 0, c}};
  return {Vec3{c, s, 0}, Vec3{-s, c, 0}, Vec3{0, 0, 1}};
}

// C·Rx(δx)·Ry(δy)·Rz(δz), δ in radians.
Axes3 with_error(const Axes3& C, const double* d) {
  return vec3::compose(C, vec3::compose(rot(0, d[0]), vec3::compose(rot(1, d[1]), rot(2, d[2]))));
}

double axial_residual(double a) {
  a = std::remainder(a, std::numbers::pi);  // (−π/2, π/2]
  return a;
}

struct Sample {
  Vec3 sun_b;
  double aop_rad;
};

struct InstallationResiduals : Eigen::DenseFunctor<double> {
  InstallationResiduals(const Axes3& C, const std::vector<Sample>& s)
      : Eigen::DenseFunctor<double>(3, static_cast<int>(s.size())), C_nom(C), samples(s) {}
  int operator()(const InputType& x, ValueType& r) const {
    const double d[3] = {x(0), x(1), x(2)};
    const Axes3 C = with_error(C_nom, d);
    for (std::size_t k = 0; k < samples.size(); ++k)
      r(static_cast<Eigen::Index>(k)) = axial_residual(samples[k].aop_rad - predicted_unit_aop_rad(C, samples[k].sun_b));
    return 0;
  }
  // Central differences (h = 1e-7 rad: the truncation error h²·φ''' ~ 1e-14 and the rounding
  // 1e-16/h ~ 1e-9 of the derivative, far below what moves the fit).
  int df(const InputType& x, JacobianType& J) const {
    constexpr double h = 1e-7;
    ValueType rp(values()), rm(values());
    for (int j = 0; j < 3; ++j) {
      InputType xp = x, xm = x;
      xp(j) += h;
      xm(j) -= h;
      (*this)(xp, rp);
      (*this)(xm, rm);
      for (Eigen::Index k = 0; k < values(); ++k) J(k, j) = axial_residual(rp(k) - rm(k)) / (2 * h);
    }
    return 0;
  }
  const Axes3& C_nom;
  const std::vector<Sample>& samples;
};

double rms_deg(const Eigen::VectorXd& r) {
  return r.size() ? rad2deg(std::sqrt(r.squaredNorm() / static_cast<double>(r.size()))) : 0.0;
}

}  // namespace

Axes3 installed_frame(const Axes3& nominal, const std::array<double, 3>& error_deg) {
  const double d[3] = {deg2rad(error_deg[0]), deg2rad(error_deg[1]), deg2rad(error_deg[2])};
  return with_error(nominal, d);
}

double predicted_unit_aop_rad(const Axes3& C_mb, const Vec3& sun_b) {
  const Vec3 e = vec3::cross(sun_b, C_mb[2]);
  const Vec3 k = vec3::mul(C_mb[2], -1.0);
  double a = std::atan2(vec3::dot(e, vec3::cross(k, C_mb[0])), vec3::dot(e, C_mb[0]));
  if (a < 0) a += std::numbers::pi;
  if (a >= std::numbers::pi) a -= std::numbers::pi;
  return a;
}

std::vector<UnitInstallation> calibrate_installation(std::span<const UnitMount> nominal,
                                                     std::span<const InstallationEpoch> epochs,
                                                     const UnitInstallationSettings& settings) {
  for (std::size_t k = 0; k < epochs.size(); ++k)
    if (epochs[k].readings.size() != nominal.size())
      throw std::invalid_argument(fmt::format("calibrate_installation: epoch {} has {} readings for {} units", k,
                                              epochs[k].readings.size(), nominal.size()));
  std::vector<UnitInstallation> out(nominal.size());
  for (std::size_t i = 0; i < nominal.size(); ++i) {
    UnitInstallation& u = out[i];
    u.C_mb = nominal[i].C_mb;
    std::vector<Sample> samples;
    for (const InstallationEpoch& ep : epochs) {
      const UnitReading& r = ep.readings[i];
      if (!std::isfinite(r.aop_rad) || !(r.dop >= settings.min_dop)) continue;
      samples.push_back({vec3::apply_transpose(ep.C_bn, ep.sun_enu), r.aop_rad});
    }
    u.used = static_cast<int>(samples.size());
    if (samples.size() < 4) {
      u.termination = "too-few-readings";
      u.standard_error_deg.fill(std::numeric_limits<double>::quiet_NaN());  // no fit: none exists
      continue;
    }
    InstallationResiduals f(nominal[i].C_mb, samples);
    Eigen::VectorXd x = Eigen::VectorXd::Zero(3), r(f.values());
    f(x, r);
    u.rms_before_deg = rms_deg(r);
    Eigen::LevenbergMarquardt<InstallationResiduals> lm(f);
    lm.setMaxfev(settings.max_iterations * 10);
    lm.setXtol(1e-14);
    lm.setFtol(1e-14);
    lm.setGtol(0);
    auto status = lm.minimizeInit(x);  // NotStarted, or ImproperInputParameters
    if (status != Eigen::LevenbergMarquardtSpace::ImproperInputParameters) do
        status = lm.minimizeOneStep(x);
      while (status == Eigen::LevenbergMarquardtSpace::Running && static_cast<int>(lm.njev()) < settings.max_iterations);
    u.iterations = static_cast<int>(lm.njev());
    u.termination = lm_status_name(status, u.converged);
    f(x, r);
    u.rms_after_deg = rms_deg(r);
    Eigen::MatrixXd J(f.values(), 3);
    f.df(x, J);
    const Eigen::Matrix3d JtJ = J.transpose() * J;
    const double dof = static_cast<double>(f.values()) - 3.0;
    const double sigma2 = dof > 0 ? r.squaredNorm() / dof : 0.0;
    // Readings that fix fewer than three angles (a static run confounds a tilted unit's tilt and
    // roll errors): JᵀJ singular to rounding, no standard error exists, and the fit is not used.
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(JtJ);
    const double lo = eig.eigenvalues().minCoeff(), hi = eig.eigenvalues().maxCoeff();
    const bool determined = JtJ.allFinite() && hi > 0 && lo > 1e-10 * hi && dof > 0;
    const Eigen::Matrix3d cov = sigma2 * JtJ.inverse();
    for (int a = 0; a < 3; ++a) {
      u.error_deg[static_cast<std::size_t>(a)] = rad2deg(x(a));
      u.standard_error_deg[static_cast<std::size_t>(a)] =
          determined ? rad2deg(std::sqrt(cov(a, a))) : std::numeric_limits<double>::quiet_NaN();
    }
    if (!determined) {
      u.converged = false;
      u.termination = "RankDeficient";
    }
    const double d[3] = {x(0), x(1), x(2)};
    u.C_mb = with_error(nominal[i].C_mb, d);
  }
  return out;
}

}  // namespace polrig
