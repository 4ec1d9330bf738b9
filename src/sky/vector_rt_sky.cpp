// The vector-RT sky on its interpolation grid (include/polrig/sky/vector_rt_sky.h).
#include "polrig/sky/vector_rt_sky.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <tuple>

#include <fmt/format.h>

#include "polrig/units.h"

namespace polrig {

namespace {

constexpr double kHorizonMu = 1e-6;  // the first view node: the horizon, where 1/μ is still finite

// The views' grid variable s, uniform at the nodes: θ = (π/2)(1 − s²). Near the horizon
// μ ≈ (π/2)s², so the nodes crowd where the field changes over δμ ~ τ (as √μ would); near the
// zenith θ ≈ π(1 − s) is analytic in s, and so are the terms m ≥ 1 (∝ sin^m θ), which in √μ have
// a square-root cusp at μ = 1 (the first interpolation in √μ missed the zenith's I by 3 %).
double grid_s(double mu) { return std::sqrt(std::max(0.0, 1 - 2 * std::acos(mu) / M_PI)); }
double grid_mu(double s) { return std::cos(M_PI / 2 * (1 - s * s)); }

std::vector<double> view_s() {
  std::vector<double> s{grid_s(kHorizonMu)};
  for (int k = 1; k < VectorRtSky::kViewNodes; ++k) s.push_back(k / double(VectorRtSky::kViewNodes - 1));
  return s;
}

// The 4-point Lagrange weights at t of the nodes t[j0 … j0 + 3].
std::array<double, 4> lagrange4(const double* t, double x) {
  std::array<double, 4> w;
  for (int i = 0; i < 4; ++i) {
    double p = 1;
    for (int j = 0; j < 4; ++j)
      if (j != i) p *= (x - t[j]) / (t[i] - t[j]);
    w[i] = p;
  }
  return w;
}

// The first of the four nodes around x on a rising grid of n ≥ 4 nodes.
int stencil_start(const std::vector<double>& t, double x) {
  const int n = static_cast<int>(t.size());
  const int j = static_cast<int>(std::upper_bound(t.begin(), t.end(), x) - t.begin()) - 1;
  return std::clamp(j - 1, 0, n - 4);
}

}  // namespace

const std::vector<double>& VectorRtSky::view_mu() {
  static const std::vector<double> mu = [] {
    std::vector<double> m;
    for (double s : view_s()) m.push_back(std::min(1.0, grid_mu(s)));
    return m;
  }();
  return mu;
}

VectorRtSky::VectorRtSky(const VectorRtSettings& s) : settings_(s) { check_vector_rt(s); }

std::shared_ptr<const DiffuseField> VectorRtSky::node(int k) const {
  std::lock_guard<std::mutex> lock(mutex_);
  auto& f = nodes_[k];
  if (!f) {
    const double h = kGridLowestDeg + k * kElevationStepDeg;
    f = std::make_shared<const DiffuseField>(solve_vector_rt(settings_, std::sin(h * kDeg), view_mu()));
  }
  return f;
}

SunField VectorRtSky::for_sun(double h) const {
  const double lowest = lowest_sun_elevation_deg();
  if (!(h >= lowest && h <= 90))
    throw std::invalid_argument(fmt::format(
        "vector-rt sky: the sun's elevation {}° is outside [{}°, 90°] ({})", h, lowest,
        settings_.pseudo_spherical ? "below it the refraction and the air's profile bend the beam by the sun's own size"
                                   : "a plane-parallel atmosphere's direct beam is too long below it; "
                                     "sky.rt.direct_beam: pseudo-spherical goes to 1°"));
  static const std::vector<double> elevations = [] {
    std::vector<double> t;
    for (double e = kGridLowestDeg; e <= 90 + 1e-9; e += kElevationStepDeg) t.push_back(e);
    return t;
  }();
  const int j0 = stencil_start(elevations, h);
  const std::array<double, 4> w = lagrange4(&elevations[j0], h);
  SunField out;
  const std::size_t n = view_mu().size();
  for (int i = 0; i < 4; ++i) {
    const std::shared_ptr<const DiffuseField> f = node(j0 + i);
    out.coefficients_.resize(f->down.size(), std::vector<Eigen::Vector3d>(n, Eigen::Vector3d::Zero()));
    for (std::size_t m = 0; m < f->down.size(); ++m)
      for (std::size_t k = 0; k < n; ++k) out.coefficients_[m][k] += w[i] * f->down[m][k].head<3>();
    out.single_ = f->single;
  }
  out.mu0_ = std::sin(h * kDeg);
  if (out.single_) out.sun_air_mass_ = out.single_->sun_air_mass(out.mu0_);
  out.zenith_I_ =
      out.coefficients_[0].back()(0) + (out.single_ ? out.single_->down(out.mu0_, out.sun_air_mass_, 1, 0)(0) : 0.0);
  return out;
}

Eigen::Vector3d SunField::stokes(double mu, double phi) const { return stokes(mu, std::cos(phi), std::sin(phi)); }

namespace {

// The view grid's interpolation: its nodes, and for every 4-node stencil the denominators
// Π_{j≠i}(s_i − s_j) of its Lagrange weights (the nodes past the first are uniform, so the stencil
// is found without a search).
struct ViewStencils {
  std::vector<double> s;
  std::vector<std::array<double, 4>> inverse_denominators;
  ViewStencils() : s(view_s()) {
    for (std::size_t j0 = 0; j0 + 4 <= s.size(); ++j0) {
      std::array<double, 4> d;
      for (int i = 0; i < 4; ++i) {
        double p = 1;
        for (int j = 0; j < 4; ++j)
          if (j != i) p *= s[j0 + static_cast<std::size_t>(i)] - s[j0 + static_cast<std::size_t>(j)];
        d[static_cast<std::size_t>(i)] = 1 / p;
      }
      inverse_denominators.push_back(d);
    }
  }
  int start(double x) const {
    const int n = static_cast<int>(s.size());
    const int j = x < s[1] ? 0 : std::min(n - 1, static_cast<int>(x * (n - 1)));
    return std::clamp(j - 1, 0, n - 4);
  }
};

}  // namespace

Eigen::Vector3d SunField::stokes(double mu, double cos_phi, double sin_phi) const {
  static const ViewStencils grid;
  const double x = grid_s(std::clamp(mu, kHorizonMu, 1.0));
  const int j0 = grid.start(x);
  const double* t = &grid.s[static_cast<std::size_t>(j0)];
  const std::array<double, 4>& inv = grid.inverse_denominators[static_cast<std::size_t>(j0)];
  const double d0 = x - t[0], d1 = x - t[1], d2 = x - t[2], d3 = x - t[3];
  const double w[4] = {d1 * d2 * d3 * inv[0], d0 * d2 * d3 * inv[1], d0 * d1 * d3 * inv[2], d0 * d1 * d2 * inv[3]};
  // cos mφ, sin mφ by Chebyshev's recurrence (for m = 2 the double-angle formulas).
  double c_prev = 1, s_prev = 0, c_m = 1, s_m = 0;
  Eigen::Vector3d out = Eigen::Vector3d::Zero();
  for (std::size_t m = 0; m < coefficients_.size(); ++m) {
    if (m == 1) c_m = cos_phi, s_m = sin_phi;
    if (m >= 2) {
      const double c_next = 2 * cos_phi * c_m - c_prev, s_next = 2 * cos_phi * s_m - s_prev;
      c_prev = c_m, s_prev = s_m, c_m = c_next, s_m = s_next;
    }
    const Eigen::Vector3d* c = &coefficients_[m][static_cast<std::size_t>(j0)];
    const Eigen::Vector3d v = w[0] * c[0] + w[1] * c[1] + w[2] * c[2] + w[3] * c[3];
    out += Eigen::Vector3d(c_m * v(0), c_m * v(1), s_m * v(2));
  }
  if (single_)
    out += single_->down(mu0_, sun_air_mass_, std::clamp(mu, kHorizonMu, 1.0), std::atan2(sin_phi, cos_phi)).head<3>();
  return out;
}

std::shared_ptr<const VectorRtSky> vector_rt_sky(const VectorRtSettings& s) {
  static std::mutex mutex;
  static std::map<std::tuple<double, double, double, int, double, double, const PhaseMatrixTable*, bool>,
                  std::shared_ptr<const VectorRtSky>> skies;
  const auto key = std::make_tuple(s.tau_rayleigh, s.depolarization, s.ground_albedo, s.streams, s.aerosol.tau,
                                   s.aerosol.ssa, s.aerosol.phase.get(), s.pseudo_spherical);
  std::lock_guard<std::mutex> lock(mutex);
  auto& sky = skies[key];
  if (!sky) sky = std::make_shared<const VectorRtSky>(s);
  return sky;
}

}  // namespace polrig
