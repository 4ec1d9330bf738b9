// Berry's sky fitted to the vector-RT sky (include/polrig/sky/berry_fit.h).
#include "polrig/sky/berry_fit.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <tuple>
#include <vector>

#include <Eigen/Core>
#include <fmt/format.h>

#include "polrig/lm_status.h"
#include "polrig/sky/rayleigh.h"
#include "polrig/units.h"

namespace polrig {

namespace {

constexpr double kMinDop = 0.02;       // the views whose AoP the fit and its errors use
constexpr double kStartDeg = 15;       // both distances' start (clear skies: 10°–25°)
constexpr double kMaxDistanceDeg = 89;  // BerryField takes [0°, 90°)
constexpr int kRows = 30;               // view rows every 3° of elevation
constexpr int kEquatorViews = 120;      // views around the lowest row (every 3°), fewer higher up

// A view and the exact sky's polarization direction there, as (cos 2χ, sin 2χ) in v's meridian frame.
struct ExactView {
  Vec3 v, e_theta, e_phi;
  double cos2chi, sin2chi;
};

// The grid uniform in solid angle above the horizon (rows at the middle of each 3° band, their
// views ∝ cos e), the sun at math azimuth 0, kept where the exact DoP ≥ kMinDop.
std::vector<ExactView> exact_views(const SunField& field) {
  std::vector<ExactView> out;
  for (int k = 0; k < kRows; ++k) {
    const double e = (k + 0.5) * (90.0 / kRows) * kDeg;
    const int n = std::max(1, static_cast<int>(std::lround(kEquatorViews * std::cos(e))));
    for (int j = 0; j < n; ++j) {
      const double phi = (j + 0.5) * 2 * M_PI / n;
      const Eigen::Vector3d x = field.stokes(std::sin(e), phi);
      const double lp = std::hypot(x(1), x(2));
      if (!(lp >= kMinDop * x(0))) continue;
      ExactView w;
      w.v = {std::cos(e) * std::cos(phi), std::cos(e) * std::sin(phi), std::sin(e)};
      meridian_frame(w.v, w.e_theta, w.e_phi);
      w.cos2chi = x(1) / lp, w.sin2chi = x(2) / lp;
      out.push_back(w);
    }
  }
  return out;
}

BerryDistances clamped(const Eigen::VectorXd& x) {
  return {std::clamp(x(0), 0.0, kMaxDistanceDeg), std::clamp(x(1), 0.0, kMaxDistanceDeg)};
}

// Two residuals per view, ½(e^{2iχ_Berry} − e^{2iχ_exact}): their norm is |sin Δχ|, and they are
// smooth where Δχ passes ±90° (a residual sin Δχ would jump there).
struct BerryResiduals : Eigen::DenseFunctor<double> {
  BerryResiduals(const std::vector<ExactView>& views, const Vec3& sun)
      : Eigen::DenseFunctor<double>(2, static_cast<int>(2 * views.size())), views(views), sun(sun) {}

  int operator()(const Eigen::VectorXd& x, Eigen::VectorXd& r) const {
    const BerryField berry(sun, clamped(x));
    for (std::size_t k = 0; k < views.size(); ++k) {
      const ExactView& w = views[k];
      const Vec3 e = berry.at(w.v).e_vector;
      const double c = vec3::dot(e, w.e_theta), s = vec3::dot(e, w.e_phi);
      r(static_cast<Eigen::Index>(2 * k)) = 0.5 * ((c * c - s * s) - w.cos2chi);
      r(static_cast<Eigen::Index>(2 * k + 1)) = 0.5 * (2 * c * s - w.sin2chi);
    }
    return 0;
  }
  // Central differences of 1e-4°: the residuals are smooth in the distances on that scale.
  int df(const Eigen::VectorXd& x, Eigen::MatrixXd& J) const {
    constexpr double h = 1e-4;
    Eigen::VectorXd rp(values()), rm(values());
    for (int j = 0; j < 2; ++j) {
      Eigen::VectorXd xp = x, xm = x;
      xp(j) += h, xm(j) -= h;
      (*this)(xp, rp);
      (*this)(xm, rm);
      J.col(j) = (rp - rm) / (2 * h);
    }
    return 0;
  }
  const std::vector<ExactView>& views;
  Vec3 sun;
};

// |Δχ| in degrees of a polarization direction against the exact one.
double aop_error_deg(const Vec3& e, const ExactView& w) {
  const double chi = std::atan2(vec3::dot(e, w.e_phi), vec3::dot(e, w.e_theta));
  const double chi_exact = 0.5 * std::atan2(w.sin2chi, w.cos2chi);
  return std::abs(std::remainder(chi - chi_exact, M_PI)) / kDeg;
}

}  // namespace

BerryFitResult fit_berry(const SunField& field, double sun_el_deg) {
  BerryFitResult out;
  out.sun_el_deg = sun_el_deg;
  const Vec3 sun{std::cos(sun_el_deg * kDeg), 0, std::sin(sun_el_deg * kDeg)};
  const std::vector<ExactView> views = exact_views(field);
  out.summary.views = static_cast<int>(views.size());
  if (views.size() < 2) {
    out.summary.status = "TooFewViews";
    return out;
  }
  BerryResiduals f(views, sun);
  Eigen::VectorXd x = Eigen::VectorXd::Constant(2, kStartDeg);
  Eigen::LevenbergMarquardt<BerryResiduals> lm(f);
  lm.setXtol(1e-10);
  lm.setFtol(1e-12);
  lm.setGtol(0);
  auto status = lm.minimizeInit(x);
  if (status != Eigen::LevenbergMarquardtSpace::ImproperInputParameters) do
      status = lm.minimizeOneStep(x);
    while (status == Eigen::LevenbergMarquardtSpace::Running && lm.njev() < 100);
  out.summary.status = lm_status_name(status, out.summary.converged);
  out.summary.iterations = static_cast<int>(lm.njev());
  out.distances = clamped(x);

  const BerryField berry(sun, out.distances);
  std::vector<double> errors;
  double ss_berry = 0, ss_single = 0;
  for (const ExactView& w : views) {
    const double d = aop_error_deg(berry.at(w.v).e_vector, w);
    const Vec3 c = vec3::cross(sun, w.v);  // single scattering: e ⊥ the scattering plane
    const double d_single = aop_error_deg(vec3::mul(c, 1 / vec3::norm(c)), w);
    errors.push_back(d);
    ss_berry += d * d, ss_single += d_single * d_single;
  }
  const double n = static_cast<double>(views.size());
  out.summary.aop_rms_deg = std::sqrt(ss_berry / n);
  out.summary.single_aop_rms_deg = std::sqrt(ss_single / n);
  std::sort(errors.begin(), errors.end());
  out.summary.aop_p95_deg = errors[static_cast<std::size_t>(std::ceil(0.95 * n)) - 1];
  return out;
}

BerryFit::BerryFit(std::shared_ptr<const VectorRtSky> sky) : sky_(std::move(sky)) {
  if (!sky_) throw std::logic_error("BerryFit without a vector-RT sky");
}

BerryFitResult BerryFit::at_node(int k) const {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (const auto it = nodes_.find(k); it != nodes_.end()) return it->second;
  }
  // Fitted outside the lock (a pure function of k: a second thread's fit is the same bits).
  const double h = VectorRtSky::kMinSunElevationDeg + k * VectorRtSky::kElevationStepDeg;
  const BerryFitResult r = fit_berry(sky_->for_sun(h), h);
  std::lock_guard<std::mutex> lock(mutex_);
  return nodes_.emplace(k, r).first->second;
}

BerryDistances BerryFit::distances(double h) const {
  if (!(h >= VectorRtSky::kMinSunElevationDeg && h <= 90))
    throw std::invalid_argument(fmt::format("Berry's sky with fitted distances (sky.berry.*: fit, fitted to the "
                                            "vector-rt sky): the sun's elevation {}° is outside [{}°, 90°] (give "
                                            "sky.berry.babinet_deg and sky.berry.brewster_deg for a lower sun)",
                                            h, VectorRtSky::kMinSunElevationDeg));
  const double t = (h - VectorRtSky::kMinSunElevationDeg) / VectorRtSky::kElevationStepDeg;
  const int last = static_cast<int>(std::lround((90 - VectorRtSky::kMinSunElevationDeg) / VectorRtSky::kElevationStepDeg));
  const int k = std::min(static_cast<int>(std::floor(t)), last - 1);
  const double f = t - k;
  const BerryFitResult a = at_node(k), b = at_node(k + 1);
  for (const BerryFitResult* r : {&a, &b})
    if (!r->summary.usable())
      throw std::invalid_argument(fmt::format("Berry's sky: the fit to the vector-RT sky at a sun elevation of {}° "
                                              "ended {} ({} views): sky.berry.* fit cannot be used there",
                                              r->sun_el_deg, r->summary.status, r->summary.views));
  return {a.distances.babinet_deg + f * (b.distances.babinet_deg - a.distances.babinet_deg),
          a.distances.brewster_deg + f * (b.distances.brewster_deg - a.distances.brewster_deg)};
}

std::shared_ptr<const BerryFit> berry_fit(const VectorRtSettings& s) {
  static std::mutex mutex;
  static std::map<std::tuple<double, double, double, int, double, double, const PhaseMatrixTable*, bool>,
                  std::shared_ptr<const BerryFit>> fits;
  const auto key = std::make_tuple(s.tau_rayleigh, s.depolarization, s.ground_albedo, s.streams, s.aerosol.tau,
                                   s.aerosol.ssa, s.aerosol.phase.get(), s.pseudo_spherical);
  std::lock_guard<std::mutex> lock(mutex);
  auto& fit = fits[key];
  if (!fit) fit = std::make_shared<const BerryFit>(vector_rt_sky(s));
  return fit;
}

BerryDistances berry_distances(const BerrySkySettings& b, double sun_el_deg) {
  BerryDistances d;
  if (!b.babinet_deg || !b.brewster_deg) {
    if (!b.fit) throw std::logic_error("a fitted Berry sky without its fit");
    d = b.fit->distances(sun_el_deg);
  }
  if (b.babinet_deg) d.babinet_deg = *b.babinet_deg;
  if (b.brewster_deg) d.brewster_deg = *b.brewster_deg;
  return d;
}

}  // namespace polrig
