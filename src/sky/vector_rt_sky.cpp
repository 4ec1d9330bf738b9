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
    const double h = kMinSunElevationDeg + k * kElevationStepDeg;
    f = std::make_shared<const DiffuseField>(solve_vector_rt(settings_, std::sin(h * kDeg), view_mu()));
  }
  return f;
}

SunField VectorRtSky::for_sun(double h) const {
  if (!(h >= kMinSunElevationDeg && h <= 90))
    throw std::invalid_argument(fmt::format(
        "vector-rt sky: the sun's elevation {}° is outside [{}°, 90°] (a plane-parallel atmosphere's direct "
        "beam is too long below it)", h, kMinSunElevationDeg));
  static const std::vector<double> elevations = [] {
    std::vector<double> t;
    for (double e = kMinSunElevationDeg; e <= 90 + 1e-9; e += kElevationStepDeg) t.push_back(e);
    return t;
  }();
  const int j0 = stencil_start(elevations, h);
  const std::array<double, 4> w = lagrange4(&elevations[j0], h);
  SunField out;
  const std::size_t n = view_mu().size();
  for (auto& c : out.coefficients_) c.assign(n, Eigen::Vector3d::Zero());
  for (int i = 0; i < 4; ++i) {
    const std::shared_ptr<const DiffuseField> f = node(j0 + i);
    for (std::size_t m = 0; m < f->down.size(); ++m)
      for (std::size_t k = 0; k < n; ++k) out.coefficients_[m][k] += w[i] * f->down[m][k].head<3>();
  }
  out.zenith_I_ = out.coefficients_[0].back()(0);
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
  // cos mφ, sin mφ for m = 0, 1, 2 by the double-angle formulas.
  const double cm[3] = {1, cos_phi, 2 * cos_phi * cos_phi - 1}, sm[3] = {0, sin_phi, 2 * sin_phi * cos_phi};
  Eigen::Vector3d out = Eigen::Vector3d::Zero();
  for (std::size_t m = 0; m < coefficients_.size(); ++m) {
    const Eigen::Vector3d* c = &coefficients_[m][static_cast<std::size_t>(j0)];
    const Eigen::Vector3d v = w[0] * c[0] + w[1] * c[1] + w[2] * c[2] + w[3] * c[3];
    out += Eigen::Vector3d(cm[m] * v(0), cm[m] * v(1), sm[m] * v(2));
  }
  return out;
}

std::shared_ptr<const VectorRtSky> vector_rt_sky(const VectorRtSettings& s) {
  static std::mutex mutex;
  static std::map<std::tuple<double, double, double, int>, std::shared_ptr<const VectorRtSky>> skies;
  const auto key = std::make_tuple(s.tau_rayleigh, s.depolarization, s.ground_albedo, s.streams);
  std::lock_guard<std::mutex> lock(mutex);
  auto& sky = skies[key];
  if (!sky) sky = std::make_shared<const VectorRtSky>(s);
  return sky;
}

}  // namespace polrig
