// Adding–doubling for the polarized Rayleigh sky (spec skies.md §2; docs/physics.md §21).
//
// Per Fourier term m, a layer is described by radiance-to-radiance operators on the quadrature
// streams (μ_j, w_j: Gauss–Legendre in √μ on (0, 1] in each hemisphere, `streams`/2 of them), each a
// block of Stokes components: R (lit from above, leaving the top), T (lit from above, leaving the
// bottom, the direct e^{−δ/μ} on its diagonal), R* and T* (lit from below). Columns of the
// collimated sun and rows of the asked views (zero quadrature weight) ride along. A layer of
// δ = τ/2ⁿ starts as single scattering (its error is O(δ) relative) and is doubled n times
// (van de Hulst's adding equations for two identical layers); the ground is added at the end.
#include "polrig/sky/vector_rt.h"

#include "polrig/quadrature.h"
#include "polrig/sky/phase_matrix.h"

#include <Eigen/LU>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace polrig {

using Eigen::MatrixXd;
using Eigen::VectorXd;

namespace {

constexpr int kRayleighTerms = 3;      // m = 0, 1, 2: Rayleigh's phase matrix has no others
constexpr int kAzimuths = 6;           // > 2·(highest m): the azimuth sums below are exact
constexpr double kStartDepth = 1e-10;  // the first layer's δ is at most this (its O(δ) error)
constexpr int kStokes = 3;             // I, Q, U: Rayleigh never couples V to them

// The m-th Fourier kernel of the phase matrix between two cosines (signed: > 0 upward), the
// factor 1/4π of the scattering integral included:
//   K^m = (1/4π)∫₀^{2π} Z(μ, φ; μ', 0)∘W_m(φ) dφ,
// W_m = cos mφ on the (I, Q)×(I, Q) and (U, V)×(U, V) blocks, −sin mφ on (I, Q)×(U, V) and
// +sin mφ on (U, V)×(I, Q): with I(φ) = Σ_m Φ_m(φ)c_m, Φ_m = diag(cos, cos, sin, sin)(mφ),
// (1/4π)∫∫Z·I dφ' dμ' = Σ_m Φ_m(φ)∫K^m(μ, μ')c_m(μ')dμ'.
struct Kernels {
  Eigen::Matrix4d K[kRayleighTerms];
};

Kernels fourier_kernels(double mu_out, double mu_in, double rho) {
  Kernels out;
  for (auto& K : out.K) K.setZero();
  const Direction in = direction(mu_in, 0);
  for (int k = 0; k < kAzimuths; ++k) {
    // A grid shifted by half a step never meets the forward or backward direction exactly.
    const double phi = (k + 0.5) * 2 * M_PI / kAzimuths;
    const Direction o = direction(mu_out, phi);
    const Eigen::Matrix4d Z = phase_matrix(in, o, rayleigh_elements(vec3::dot(in.k, o.k), rho));
    for (int m = 0; m < kRayleighTerms; ++m) {
      const double c = std::cos(m * phi), s = std::sin(m * phi);
      Eigen::Matrix4d W;
      W << c, c, -s, -s, c, c, -s, -s, s, s, c, c, s, s, c, c;
      out.K[m] += Z.cwiseProduct(W) * (2 * M_PI / kAzimuths / (4 * M_PI));
    }
  }
  return out;
}

// expm1(x)/x, 1 at x = 0.
double phi1(double x) { return std::abs(x) < 1e-8 ? 1 + x / 2 : std::expm1(x) / x; }

// Single scattering in a layer of thickness δ, from direction μ' (> 0) into μ (> 0):
// reflection (1/μ)∫₀^δ e^{−t/μ'}e^{−t/μ}dt and transmission (1/μ)∫₀^δ e^{−t/μ'}e^{−(δ−t)/μ}dt.
double path_reflected(double delta, double mu, double mu_in) {
  const double a = 1 / mu + 1 / mu_in;
  return delta / mu * std::exp(-a * delta) * phi1(a * delta);
}
double path_transmitted(double delta, double mu, double mu_in) {
  return delta / mu * std::exp(-delta / mu) * phi1((1 / mu - 1 / mu_in) * delta);
}

// One Fourier term of a layer (see the top of the file). n = N·kStokes node components; the view
// rows are nu·kStokes. The transmissions are kept as their departures from the identity
// (T = E + T_minus_E, e = 1 + e_minus_1): a first layer of δ ~ 1e-10 would otherwise keep only
// six digits of what it scatters (1 − δ/μ rounds at 1e-16).
struct Layer {
  MatrixXd R, T_minus_E, Rs, Ts_minus_E;  // node → node
  VectorXd r_sun, t_sun;                  // diffuse response at the nodes to the collimated sun
  double e_sun_minus_1 = 0;               // the sun beam's direct transmission, less 1
  MatrixXd Ru, Tu, Rsu, Tsu;              // node → view, diffuse only
  VectorXd ru_sun, tu_sun;                // sun → view, diffuse
  VectorXd e_view_minus_1;                // each view's direct transmission, less 1, per Stokes row
  MatrixXd T() const { return T_minus_E + MatrixXd::Identity(R.rows(), R.cols()); }
  MatrixXd Ts() const { return Ts_minus_E + MatrixXd::Identity(R.rows(), R.cols()); }
  double e_sun() const { return 1 + e_sun_minus_1; }
  VectorXd e_view() const { return e_view_minus_1.array() + 1; }
};

struct Geometry {
  std::vector<double> mu, w;  // quadrature on (0, 1]
  std::vector<double> view_mu;
  double mu0 = 1;
};

// Puts the kStokes×kStokes block of `K`, scaled, at (row block i, column block j).
void put(MatrixXd& M, int i, int j, const Eigen::Matrix4d& K, double scale) {
  M.block(i * kStokes, j * kStokes, kStokes, kStokes) = K.topLeftCorner(kStokes, kStokes) * scale;
}
void put_column(VectorXd& v, int i, const Eigen::Matrix4d& K, double scale) {
  v.segment(i * kStokes, kStokes) = K.col(0).head(kStokes) * scale;
}

// The thin layer δ for every Fourier term: single scattering with ϖ = 1.
std::vector<Layer> thin_layers(const Geometry& g, double delta, double rho) {
  const int N = static_cast<int>(g.mu.size()), nu = static_cast<int>(g.view_mu.size());
  const int n = N * kStokes, nv = nu * kStokes;
  std::vector<Layer> L(kRayleighTerms);
  for (int m = 0; m < kRayleighTerms; ++m) {
    Layer& l = L[m];
    l.R = l.T_minus_E = l.Rs = l.Ts_minus_E = MatrixXd::Zero(n, n);
    l.r_sun = l.t_sun = VectorXd::Zero(n);
    l.Ru = l.Tu = l.Rsu = l.Tsu = MatrixXd::Zero(nv, n);
    l.ru_sun = l.tu_sun = VectorXd::Zero(nv);
    l.e_sun_minus_1 = std::expm1(-delta / g.mu0);
    l.e_view_minus_1.resize(nv);
  }
  // A node column carries its quadrature weight w_j (K already holds the azimuth integral); the
  // sun's column the collimated beam's (2 − δ_m0)/2π from the Fourier series of its source.
  auto fill_rows = [&](double mu, int i, MatrixXd Layer::*R, MatrixXd Layer::*T, MatrixXd Layer::*Rs,
                       MatrixXd Layer::*Ts, VectorXd Layer::*r_sun, VectorXd Layer::*t_sun) {
    for (int j = 0; j < N; ++j) {
      const double mj = g.mu[j], wj = g.w[j];
      const double pr = path_reflected(delta, mu, mj), pt = path_transmitted(delta, mu, mj);
      const Kernels down_from_down = fourier_kernels(-mu, -mj, rho);
      const Kernels up_from_down = fourier_kernels(mu, -mj, rho);
      const Kernels down_from_up = fourier_kernels(-mu, mj, rho);
      const Kernels up_from_up = fourier_kernels(mu, mj, rho);
      for (int m = 0; m < kRayleighTerms; ++m) {
        Layer& l = L[m];
        put(l.*R, i, j, up_from_down.K[m], wj * pr);
        put(l.*T, i, j, down_from_down.K[m], wj * pt);
        put(l.*Rs, i, j, down_from_up.K[m], wj * pr);
        put(l.*Ts, i, j, up_from_up.K[m], wj * pt);
      }
    }
    const Kernels up_from_sun = fourier_kernels(mu, -g.mu0, rho);
    const Kernels down_from_sun = fourier_kernels(-mu, -g.mu0, rho);
    for (int m = 0; m < kRayleighTerms; ++m) {
      const double c = (m == 0 ? 1.0 : 2.0) / (2 * M_PI);
      put_column(L[m].*r_sun, i, up_from_sun.K[m], c * path_reflected(delta, mu, g.mu0));
      put_column(L[m].*t_sun, i, down_from_sun.K[m], c * path_transmitted(delta, mu, g.mu0));
    }
  };
  for (int i = 0; i < N; ++i) {
    fill_rows(g.mu[i], i, &Layer::R, &Layer::T_minus_E, &Layer::Rs, &Layer::Ts_minus_E, &Layer::r_sun,
              &Layer::t_sun);
    const double e_minus_1 = std::expm1(-delta / g.mu[i]);
    for (auto& l : L)
      for (int s = 0; s < kStokes; ++s) {
        const int k = i * kStokes + s;
        l.T_minus_E(k, k) += e_minus_1, l.Ts_minus_E(k, k) += e_minus_1;
      }
  }
  for (int u = 0; u < nu; ++u) {
    fill_rows(g.view_mu[u], u, &Layer::Ru, &Layer::Tu, &Layer::Rsu, &Layer::Tsu, &Layer::ru_sun, &Layer::tu_sun);
    for (auto& l : L) l.e_view_minus_1.segment(u * kStokes, kStokes).setConstant(std::expm1(-delta / g.view_mu[u]));
  }
  return L;
}

// Two identical layers a (above) and b (below) as one (van de Hulst 1980; Hansen & Travis 1974
// Eqs. 3.41–3.48 with the sun's and the views' columns and rows).
Layer doubled(const Layer& l) {
  const auto n = l.R.rows();
  const MatrixXd I = MatrixXd::Identity(n, n);
  const MatrixXd T = l.T(), Ts = l.Ts();
  const Eigen::PartialPivLU<MatrixXd> A(I - l.Rs * l.R);  // (E − R*_a R_b): lit from above
  const Eigen::PartialPivLU<MatrixXd> B(I - l.R * l.Rs);  // (E − R_b R*_a): lit from below
  const double e = l.e_sun();
  Layer o;
  // Lit from above: D = (E − R*R)⁻¹T down and U up at the interface; (E − R*R)⁻¹ = E + (E − R*R)⁻¹R*R.
  const MatrixXd X = A.solve(l.Rs * (l.R * T));
  const MatrixXd D = T + X, U = l.R * D;
  // Lit from below: U' up and D' down at the interface.
  const MatrixXd Y = B.solve(l.R * (l.Rs * Ts));
  const MatrixXd Up = Ts + Y, Dp = l.Rs * Up;
  o.R = l.R + Ts * U;
  o.T_minus_E = 2 * l.T_minus_E + l.T_minus_E * l.T_minus_E + T * X;  // T·D − E
  o.Rs = l.Rs + T * Dp;
  o.Ts_minus_E = 2 * l.Ts_minus_E + l.Ts_minus_E * l.Ts_minus_E + Ts * Y;
  // The sun: its direct beam reaches b after a's e.
  const VectorXd d_sun = A.solve(l.t_sun + l.Rs * (l.r_sun * e));
  const VectorXd u_sun = l.R * d_sun + l.r_sun * e;
  o.r_sun = l.r_sun + Ts * u_sun;
  o.t_sun = T * d_sun + l.t_sun * e;
  o.e_sun_minus_1 = l.e_sun_minus_1 * (2 + l.e_sun_minus_1);
  // The views: their radiance at the interface, then through a (up) or b (down).
  const VectorXd ev = l.e_view();
  const auto Ev = ev.asDiagonal();
  const MatrixXd Du = l.Tu + l.Rsu * U, Uu = l.Ru * D;
  const MatrixXd Upu = l.Tsu + l.Ru * Dp, Dpu = l.Rsu * Up;
  o.Ru = l.Ru + l.Tsu * U + Ev * Uu;
  o.Tu = l.Tu * D + Ev * Du;
  o.Rsu = l.Rsu + l.Tu * Dp + Ev * Dpu;
  o.Tsu = l.Tsu * Up + Ev * Upu;
  const VectorXd Dus = l.tu_sun + l.Rsu * u_sun, Uus = l.Ru * d_sun + l.ru_sun * e;
  o.ru_sun = l.ru_sun + l.Tsu * u_sun + Ev * Uus;
  o.tu_sun = l.Tu * d_sun + Ev * Dus + l.tu_sun * e;
  o.e_view_minus_1 = l.e_view_minus_1.cwiseProduct(l.e_view_minus_1) + 2 * l.e_view_minus_1;  // e² − 1
  return o;
}

// The layer's diffuse field with a Lambertian ground of albedo A under it (m = 0 only: the ground
// reflects isotropically, L = (A/π)·(downward flux)). Returns the views' down and up coefficients
// and the nodes' (for fluxes).
struct Emerging {
  VectorXd down_nodes, up_nodes, down_views, up_views;
};

Emerging with_ground(const Layer& l, const Geometry& g, double A, bool m0) {
  const auto n = l.R.rows();
  const int N = static_cast<int>(g.mu.size()), nu = static_cast<int>(g.view_mu.size());
  Emerging e;
  if (!m0 || A == 0) {
    e.down_nodes = l.t_sun, e.up_nodes = l.r_sun;
    e.down_views = l.tu_sun, e.up_views = l.ru_sun;
    return e;
  }
  // The ground's reflection of node radiances (flux 2π Σ w_j μ_j I_j) and of the direct beam.
  MatrixXd Rg = MatrixXd::Zero(n, n);
  VectorXd rg_sun = VectorXd::Zero(n);
  for (int i = 0; i < N; ++i) {
    for (int j = 0; j < N; ++j) Rg(i * kStokes, j * kStokes) = 2 * A * g.w[j] * g.mu[j];
    rg_sun(i * kStokes) = A * g.mu0 / M_PI;
  }
  const MatrixXd I = MatrixXd::Identity(n, n);
  const VectorXd D = Eigen::PartialPivLU<MatrixXd>(I - l.Rs * Rg).solve(l.t_sun + l.Rs * rg_sun * l.e_sun());
  const VectorXd U = Rg * D + rg_sun * l.e_sun();  // leaving the ground, at the nodes
  e.down_nodes = D;
  e.up_nodes = l.r_sun + l.Ts() * U;
  e.down_views = l.tu_sun + l.Rsu * U;
  // Leaving the ground in the views' directions: the same isotropic radiance U(I).
  VectorXd Uv = VectorXd::Zero(nu * kStokes);
  for (int u = 0; u < nu; ++u) Uv(u * kStokes) = U(0);
  e.up_views = l.ru_sun + l.Tsu * U + l.e_view().cwiseProduct(Uv);
  return e;
}

Geometry make_geometry(const VectorRtSettings& s, double mu0, const std::vector<double>& view_mu) {
  check_vector_rt(s);
  if (!(mu0 > 0 && mu0 <= 1))
    throw std::invalid_argument(fmt::format("vector-rt sky: the sun's cos zenith {} is outside (0, 1]", mu0));
  for (double m : view_mu)
    if (!(m > 0 && m <= 1))
      throw std::invalid_argument(fmt::format("vector-rt sky: a view's cos zenith {} is outside (0, 1]", m));
  Geometry g;
  // Gauss–Legendre in x = √μ: near the horizon the field changes over δμ ~ τ (the slant paths),
  // which Gauss in μ itself resolves only with many streams (table errors 3e-3 against 5e-6 at
  // 32 streams, τ = 0.02; docs/validation.md).
  const QuadratureRule q = gauss_legendre_01(s.streams / 2);
  for (std::size_t j = 0; j < q.x.size(); ++j) {
    g.mu.push_back(q.x[j] * q.x[j]);
    g.w.push_back(q.w[j] * 2 * q.x[j]);
  }
  g.view_mu = view_mu, g.mu0 = mu0;
  return g;
}

// The first `terms` Fourier terms (the fluxes need m = 0 alone).
std::vector<Emerging> solve(const VectorRtSettings& s, const Geometry& g, int terms = kRayleighTerms) {
  int doublings = 0;
  while (s.tau_rayleigh / std::ldexp(1.0, doublings) > kStartDepth) ++doublings;
  std::vector<Layer> L = thin_layers(g, std::ldexp(s.tau_rayleigh, -doublings), s.depolarization);
  std::vector<Emerging> out;
  for (int m = 0; m < terms; ++m) {
    Layer l = std::move(L[m]);
    for (int k = 0; k < doublings; ++k) l = doubled(l);
    out.push_back(with_ground(l, g, s.ground_albedo, m == 0));
  }
  return out;
}

// The solver's frame → polrig's: the view v = −k has the same e_θ and the opposite e_φ, so U and V
// change sign; φ(view) − φ(sun) equals the light's relative azimuth.
Eigen::Vector4d to_view_frame(const VectorXd& x, int u) {
  return {x(u * kStokes), x(u * kStokes + 1), -x(u * kStokes + 2), 0};
}

Eigen::Vector4d fourier_sum(const std::vector<std::vector<Eigen::Vector4d>>& c, std::size_t u, double phi) {
  Eigen::Vector4d out = Eigen::Vector4d::Zero();
  for (std::size_t m = 0; m < c.size(); ++m) {
    const double cm = std::cos(m * phi), sm = std::sin(m * phi);
    out += Eigen::Vector4d(cm, cm, sm, sm).cwiseProduct(c[m][u]);
  }
  return out;
}

}  // namespace

void check_vector_rt(const VectorRtSettings& s) {
  if (!(s.tau_rayleigh > 0 && s.tau_rayleigh <= 100))
    throw std::invalid_argument(fmt::format("vector-rt sky: tau_rayleigh {} is outside (0, 100]", s.tau_rayleigh));
  if (!(s.depolarization >= 0 && s.depolarization < 0.5))
    throw std::invalid_argument(fmt::format("vector-rt sky: depolarization {} is outside [0, 0.5)", s.depolarization));
  if (!(s.ground_albedo >= 0 && s.ground_albedo <= 1))
    throw std::invalid_argument(fmt::format("vector-rt sky: ground_albedo {} is outside [0, 1]", s.ground_albedo));
  if (s.streams < 4 || s.streams > 128 || s.streams % 2 != 0)
    throw std::invalid_argument(fmt::format("vector-rt sky: streams {} is not an even number in [4, 128]", s.streams));
}

Eigen::Vector4d DiffuseField::down_at(std::size_t u, double phi) const { return fourier_sum(down, u, phi); }
Eigen::Vector4d DiffuseField::up_at(std::size_t u, double phi) const { return fourier_sum(up, u, phi); }

DiffuseField solve_vector_rt(const VectorRtSettings& s, double mu0, const std::vector<double>& view_mu) {
  const Geometry g = make_geometry(s, mu0, view_mu);
  const std::vector<Emerging> e = solve(s, g);
  DiffuseField f;
  f.mu = view_mu;
  f.down.resize(e.size()), f.up.resize(e.size());
  for (std::size_t m = 0; m < e.size(); ++m)
    for (int u = 0; u < static_cast<int>(view_mu.size()); ++u) {
      f.down[m].push_back(to_view_frame(e[m].down_views, u));
      f.up[m].push_back(to_view_frame(e[m].up_views, u));
    }
  return f;
}

DiffuseFluxes vector_rt_fluxes(const VectorRtSettings& s, double mu0) {
  const Geometry g = make_geometry(s, mu0, {});
  const Emerging e = solve(s, g, 1).front();
  DiffuseFluxes f;
  for (std::size_t j = 0; j < g.mu.size(); ++j) {
    const double weight = 2 * M_PI * g.w[j] * g.mu[j];
    f.up_top += weight * e.up_nodes(static_cast<Eigen::Index>(j) * kStokes);
    f.down_diffuse_bottom += weight * e.down_nodes(static_cast<Eigen::Index>(j) * kStokes);
  }
  f.down_direct_bottom = mu0 * std::exp(-s.tau_rayleigh / mu0);
  return f;
}

double rayleigh_optical_depth_bodhaine(double wavelength_nm, double pressure_hPa, double rho) {
  if (!(wavelength_nm >= 250 && wavelength_nm <= 4000))
    throw std::invalid_argument(fmt::format("Rayleigh optical depth: wavelength {} nm is outside [250, 4000] nm", wavelength_nm));
  if (!(pressure_hPa >= 1 && pressure_hPa <= 1100))
    throw std::invalid_argument(fmt::format("Rayleigh optical depth: pressure {} hPa is outside [1, 1100] hPa", pressure_hPa));
  if (!(rho >= 0 && rho < 0.5))
    throw std::invalid_argument(fmt::format("Rayleigh optical depth: depolarization {} is outside [0, 0.5)", rho));
  constexpr double kCo2 = 360e-6;                    // volume fraction
  constexpr double kNs = 2.546899e19;                // molecules cm⁻³ at 288.15 K, 1013.25 hPa
  constexpr double kAvogadro = 6.0221367e23, kGravity = 980.616;  // mol⁻¹, cm s⁻²
  const double lambda_um = wavelength_nm * 1e-3, inv2 = 1 / (lambda_um * lambda_um);
  const double n300_minus_1 = (8060.51 + 2480990 / (132.274 - inv2) + 17455.7 / (39.32957 - inv2)) * 1e-8;
  const double n = 1 + n300_minus_1 * (1 + 0.54 * (kCo2 - 0.0003));
  const double lambda_cm = lambda_um * 1e-4, n2 = n * n;
  const double king = (6 + 3 * rho) / (6 - 7 * rho);
  const double sigma = 24 * std::pow(M_PI, 3) * (n2 - 1) * (n2 - 1) /
                       (std::pow(lambda_cm, 4) * kNs * kNs * (n2 + 2) * (n2 + 2)) * king;  // cm²
  const double m_air = 15.0556 * kCo2 + 28.9595;                                       // g mol⁻¹
  return sigma * pressure_hPa * 1e3 * kAvogadro / (m_air * kGravity);
}

}  // namespace polrig
