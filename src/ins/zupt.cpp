#include "polrig/ins/zupt.h"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "polrig/statistics.h"

namespace polrig {

namespace {
constexpr double kMissQuantile = 4.753424308822899;  // the normal's 1 − 10⁻⁶ quantile
}  // namespace

ZeroVelocityTest ZeroVelocityDetector::test(std::span<const ImuSample> window, double t0_s,
                                            const RestModel& rest) const {
  const std::size_t W = window.size();
  if (W < 2) throw std::invalid_argument(fmt::format("zero-velocity test: {} samples, expected two or more", W));
  if (!(arw.minCoeff() > 0) || !(vrw.minCoeff() > 0))
    throw std::invalid_argument(fmt::format("zero-velocity test: the white-noise densities (ARW {}, {}, {} rad/√s; VRW "
                                            "{}, {}, {} m/s/√s) must be positive", arw.x(), arw.y(), arw.z(), vrw.x(),
                                            vrw.y(), vrw.z()));
  const double T = window.back().t_s - t0_s, dt = T / static_cast<double>(W);
  if (!(dt > 0)) throw std::invalid_argument(fmt::format("zero-velocity test: a window of {} s", T));
  Eigen::Vector3d f_mean = Eigen::Vector3d::Zero();
  for (const ImuSample& s : window) f_mean += s.dv;
  f_mean = f_mean / T - rest.accel_bias;
  const Eigen::Vector3d g_u = rest.g_mps2 * f_mean.normalized();
  // σ per sample of a rate averaged over Δt: N/√Δt.
  const Eigen::Vector3d sigma_f = vrw / std::sqrt(dt), sigma_w = arw / std::sqrt(dt);
  double sum = 0;
  double t_prev = t0_s;
  for (const ImuSample& s : window) {
    const double h = s.t_s - t_prev;
    t_prev = s.t_s;
    if (!(h > 0)) throw std::invalid_argument(fmt::format("zero-velocity test: an interval of {} s at {} s", h, s.t_s));
    const Eigen::Vector3d df = (s.dv / h - rest.accel_bias - g_u).cwiseQuotient(sigma_f);
    const Eigen::Vector3d dw = (s.dtheta / h - rest.omega_b).cwiseQuotient(sigma_w);
    sum += df.squaredNorm() + dw.squaredNorm();
  }
  const double dof = 6.0 * static_cast<double>(W) - 2;
  ZeroVelocityTest out;
  out.statistic = sum / dof;
  out.threshold = chi2_mean_quantile(dof, kMissQuantile);
  out.at_rest = out.statistic <= out.threshold;
  return out;
}

}  // namespace polrig
