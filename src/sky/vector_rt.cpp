// Adding–doubling for the polarized Rayleigh sky (spec skies.md §2; docs/physics.md §21).
//
// Per Fourier term m, a layer is described by radiance-to-radiance operators on the quadrature
// streams (μ_j, w_j: Gauss–Legendre in √μ on (0, 1] in each hemisphere, `streams`/2 of them), each a
// block of Stokes components: R (lit from above, leaving the top), T (lit from above, leaving the
// bottom, the direct e^{−δ/μ} on its diagonal), R* and T* (lit from below). Columns of the
// collimated sun and rows of the asked views (zero quadrature weight) ride along. A layer of
// δ = τ/2ⁿ ≤ 1e-5 starts as single and double scattering with every leg's decay exact (its error
// O(δ²) relative, 2e-8 in the flux budget; single scattering alone needed δ ~ 1e-10, 32 doublings
// instead of 15 at τ = 0.25) and is doubled n times (van de Hulst's adding equations for two identical layers, one
// factorisation each by the layer's mirror symmetry); the ground is added at the end. With an
// aerosol (physics §24) the layer's phase matrix is Rayleigh's and the aerosol's δ-M truncation
// mixed, the terms run to m = streams/2 − 1 with all four Stokes components, and the views'
// once-scattered light is taken out for SingleScatteringSky's exact one.
#include "polrig/sky/vector_rt.h"

#include "polrig/quadrature.h"
#include "polrig/sky/phase_matrix.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>

namespace polrig {

using Eigen::MatrixXd;
using Eigen::VectorXd;

namespace {

constexpr int kRayleighTerms = 3;     // m = 0, 1, 2: Rayleigh's phase matrix has no others
constexpr int kRayleighAzimuths = 6;  // > 2·(highest m): the azimuth sums below are exact
constexpr double kStartDepth = 1e-5;  // the first layer's δ is at most this (its O(δ²) error)

// The mixed layer's ϖP = R·P_R + A·P_a, with R = τ_R/τ and A = ϖ_aτ_a/τ (δ-M's or the real
// layer's τ, ϖ_a and P_a).
ScatteringElements mixed(const ScatteringElements& r, double R, const ScatteringElements& a, double A) {
  return {R * r.a1 + A * a.a1, R * r.a2 + A * a.a2, R * r.a3 + A * a.a3,
          R * r.a4 + A * a.a4, R * r.b1 + A * a.b1, R * r.b2 + A * a.b2};
}

// The one homogeneous layer the solver sees: Rayleigh alone (exactly three Fourier terms, V
// decoupled: I, Q, U), or Rayleigh and an aerosol after δ-M (terms m ≤ L = streams/2 − 1, V coupled
// to U by b2: all four).
struct Medium {
  double tau = 0;              // the solved layer's optical depth (δ-M scaled)
  double rho = 0;              // Rayleigh's depolarization
  int terms = kRayleighTerms;  // Fourier terms m = 0 … terms − 1
  int azimuths = kRayleighAzimuths;
  bool aerosol = false;
  double rayleigh_share = 1, aerosol_share = 0;  // τ_R/τ', ϖ'_a·τ'_a/τ'
  PhaseExpansion truncated;                      // the aerosol's δ-M phase matrix
  // ϖ'P'(cos Θ): the layer's phase matrix times its single-scattering albedo.
  ScatteringElements omega_P(double x) const {
    const ScatteringElements r = rayleigh_elements(x, rho);
    if (!aerosol) return r;
    return mixed(r, rayleigh_share, truncated.at(x), aerosol_share);
  }
};

// The δ-M expansion of the aerosol at the settings' streams, and the lowest value of its a1 over
// the scattering angle (negative: too few streams for this phase matrix).
// The order L of the truncated expansion: the quadrature (Gauss in √μ, N = streams/2 nodes per
// hemisphere) integrates polynomials in μ exactly only to degree N − 1, and the m = 0 kernel is
// one of degree L in μ', so L = N − 1 keeps the layer's scattering exactly conservative.
int aerosol_order(int streams) { return streams / 2 - 1; }

DeltaM aerosol_delta_m(const VectorRtSettings& s) {
  const int L = aerosol_order(s.streams);
  return delta_m(expand(*s.aerosol.phase, L + 1), L);
}

double lowest_a1(const PhaseExpansion& e, double* at_deg) {
  double lowest = 1e300;
  for (int i = 0; i <= 1800; ++i) {
    const double a1 = e.at(std::cos(i * 0.1 * M_PI / 180)).a1;
    if (a1 < lowest) lowest = a1, *at_deg = i * 0.1;
  }
  return lowest;
}

Medium make_medium(const VectorRtSettings& s) {
  Medium md;
  md.rho = s.depolarization;
  md.tau = s.tau_rayleigh;
  if (s.aerosol.tau == 0) return md;
  const DeltaM dm = aerosol_delta_m(s);
  const double w = s.aerosol.ssa, f = dm.f;
  const double tau_a = (1 - w * f) * s.aerosol.tau, ssa_a = (1 - f) * w / (1 - w * f);
  md.aerosol = true;
  md.truncated = dm.truncated;
  md.tau = s.tau_rayleigh + tau_a;
  md.rayleigh_share = s.tau_rayleigh / md.tau;
  md.aerosol_share = ssa_a * tau_a / md.tau;
  md.terms = aerosol_order(s.streams) + 1;
  md.azimuths = 2 * md.terms;  // > 2L: Z·cos mφ is a trigonometric polynomial of degree ≤ 2L
  return md;
}

// The Stokes components term m carries: at m = 0 U and V decouple from I and Q (their sin 0
// vanishes).
int stokes_in_term(int m, int ns) { return m == 0 ? 2 : ns; }

template <int NS>
using Block = Eigen::Matrix<double, NS, NS>;

// The m-th Fourier kernel of the phase matrix between two cosines (signed: > 0 upward), the
// factor 1/4π of the scattering integral and ϖ included:
//   K^m = (1/4π)∫₀^{2π} ϖZ(μ, φ; μ', 0)∘W_m(φ) dφ,
// W_m = cos mφ on the (I, Q)×(I, Q) and (U, V)×(U, V) blocks, −sin mφ on (I, Q)×(U, V) and
// +sin mφ on (U, V)×(I, Q): with I(φ) = Σ_m Φ_m(φ)c_m, Φ_m = diag(cos, cos, sin, sin)(mφ),
// (1/4π)∫∫Z·I dφ' dμ' = Σ_m Φ_m(φ)∫K^m(μ, μ')c_m(μ')dμ'. Kept for the first NS components.
template <int NS>
struct Kernels {
  std::vector<Block<NS>> K;
};

template <int NS>
Block<NS> azimuth_weights(double c, double s) {
  Block<NS> W;
  for (int i = 0; i < NS; ++i)
    for (int j = 0; j < NS; ++j) W(i, j) = (i < 2) == (j < 2) ? c : (i < 2 ? -s : s);
  return W;
}

template <int NS>
Kernels<NS> fourier_kernels(const Medium& md, double mu_out, double mu_in) {
  Kernels<NS> out;
  out.K.assign(static_cast<std::size_t>(md.terms), Block<NS>::Zero());
  const Direction in = direction(mu_in, 0);
  const int A = md.azimuths;
  for (int k = 0; k < A; ++k) {
    // A grid shifted by half a step never meets the forward or backward direction exactly.
    const double phi = (k + 0.5) * 2 * M_PI / A;
    const Direction o = direction(mu_out, phi);
    const Block<NS> Z = phase_matrix(in, o, md.omega_P(vec3::dot(in.k, o.k))).template topLeftCorner<NS, NS>();
    for (int m = 0; m < md.terms; ++m)
      out.K[static_cast<std::size_t>(m)] +=
          Z.cwiseProduct(azimuth_weights<NS>(std::cos(m * phi), std::sin(m * phi))) * (2 * M_PI / A / (4 * M_PI));
  }
  return out;
}

// A plane-parallel layer is its own mirror image in its middle plane: the mirror takes a downward
// direction to an upward one and reverses the sense of U and V (Hovenier 1969). So the kernel from
// up to up is Δ·(down to down)·Δ, R* = ΔRΔ and T* = ΔTΔ with Δ = diag(1, 1, −1, −1) per stream.
template <int NS>
Block<NS> mirrored(const Block<NS>& K) {
  Block<NS> M = K;
  for (int i = 0; i < NS; ++i)
    for (int j = 0; j < NS; ++j)
      if ((i < 2) != (j < 2)) M(i, j) *= -1;
  return M;
}
VectorXd mirror_signs(Eigen::Index size, int ns) {
  VectorXd d = VectorXd::Ones(size);
  for (Eigen::Index k = 0; k < size; ++k)
    if (k % ns >= 2) d(k) = -1;
  return d;
}
MatrixXd mirrored(const MatrixXd& M, int ns) {
  if (ns < 3) return M;
  return mirror_signs(M.rows(), ns).asDiagonal() * M * mirror_signs(M.cols(), ns).asDiagonal();
}

// expm1(x)/x, 1 at x = 0.
double phi1(double x) { return std::abs(x) < 1e-8 ? 1 + x / 2 : std::expm1(x) / x; }

// The path integrals of light scattered once or twice in a layer of thickness δ whose legs decay
// at the rates x (the sum of 1/μ over the directions that cross each stretch of the layer). Once:
// ∫₀^δ e^{−x₀t − x₁(δ−t)}dt; twice: ∫∫_{0<r<s<δ} e^{−x₀r − x₁(s−r) − x₂(δ−s)} dr ds. Each is the
// divided difference f[x₀, …] of f(x) = e^{−δx} (Hermite–Genocchi), evaluated after a shift to the
// smallest rate so that no exponential grows: by its series where the spread is small, by
// differences of φ₁ otherwise.
double once_scattered_path(double delta, double x0, double x1) {
  return delta * std::exp(-std::min(x0, x1) * delta) * phi1(-std::abs(x1 - x0) * delta);
}

double twice_scattered_path(double delta, double x0, double x1, double x2) {
  if (x0 > x1) std::swap(x0, x1);
  if (x1 > x2) std::swap(x1, x2);
  if (x0 > x1) std::swap(x0, x1);
  const double u1 = (x1 - x0) * delta, u2 = (x2 - x0) * delta;
  double h;  // h[0, u1, u2] of h(u) = e^{−u}
  if (u2 < 0.25) {
    // Σ_k (−1)^k/(k + 2)!·Σ_{i+j=k} u1^i u2^j
    h = 0;
    double factorial = 2, sum = 1, u1_power = 1;
    for (int k = 0; k < 24; ++k) {
      const double term = ((k % 2) ? -sum : sum) / factorial;
      h += term;
      if (std::abs(term) < 1e-18 * h) break;
      u1_power *= u1;
      sum = sum * u2 + u1_power;
      factorial *= k + 3;
    }
  } else {
    const double h01 = -phi1(-u1), h12 = -std::exp(-u1) * phi1(-(u2 - u1));
    h = (h12 - h01) / u2;
  }
  return delta * delta * std::exp(-x0 * delta) * h;
}

// One Fourier term of a layer (see the top of the file), `ns` Stokes components per stream.
// R* and T* are the mirror images of R and T. The transmissions are kept as their departures
// from the identity (T = E + T_minus_E, e = 1 + e_minus_1): a first layer as thin as δ ~ 1e-4
// would otherwise lose the digits of what it scatters to 1 − δ/μ.
struct Layer {
  int ns = 3;
  MatrixXd R, T_minus_E;    // node → node
  VectorXd r_sun, t_sun;    // diffuse response at the nodes to the collimated sun
  double e_sun_minus_1 = 0; // the sun beam's direct transmission, less 1
  MatrixXd Ru, Tu;          // node → view, diffuse only
  VectorXd ru_sun, tu_sun;  // sun → view, diffuse
  VectorXd e_view_minus_1;  // each view's direct transmission, less 1, per Stokes row
  MatrixXd T() const { return T_minus_E + MatrixXd::Identity(R.rows(), R.cols()); }
  MatrixXd Rs() const { return mirrored(R, ns); }
  MatrixXd Ts() const { return mirrored(T(), ns); }
  MatrixXd Rsu() const { return mirrored(Ru, ns); }
  MatrixXd Tsu() const { return mirrored(Tu, ns); }
  double e_sun() const { return 1 + e_sun_minus_1; }
  VectorXd e_view() const { return e_view_minus_1.array() + 1; }
};

struct Geometry {
  std::vector<double> mu, w;  // quadrature on (0, 1]
  std::vector<double> view_mu;
  double mu0 = 1;
  double sun_air_mass = 0;  // pseudo-spherical: the beam's air mass; 0: plane-parallel, 1/μ₀
  // The beam's decay rate per unit optical depth, and its optical path through a depth δ.
  double sun_rate() const { return sun_air_mass > 0 ? sun_air_mass : 1 / mu0; }
  double sun_path(double delta) const { return sun_air_mass > 0 ? delta * sun_air_mass : delta / mu0; }
};

// The kernels the thin layer needs, every term at once: outgoing directions are the nodes, then
// the views; incoming ones the nodes, then the sun. `same` goes from a downward direction into a
// downward one, `across` from a downward one into an upward one; the other two are mirrored.
template <int NS>
struct KernelTable {
  int cols = 0;
  std::vector<Kernels<NS>> same, across, same_mirrored, across_mirrored;
  const Block<NS>& s(int o, int i, int m) const { return same[o * cols + i].K[m]; }
  const Block<NS>& a(int o, int i, int m) const { return across[o * cols + i].K[m]; }
  const Block<NS>& s_mirrored(int o, int i, int m) const { return same_mirrored[o * cols + i].K[m]; }
  const Block<NS>& a_mirrored(int o, int i, int m) const { return across_mirrored[o * cols + i].K[m]; }
};

template <int NS>
KernelTable<NS> kernel_table(const Geometry& g, const Medium& md) {
  const int N = static_cast<int>(g.mu.size());
  std::vector<double> out = g.mu, in = g.mu;
  out.insert(out.end(), g.view_mu.begin(), g.view_mu.end());
  in.push_back(g.mu0);
  KernelTable<NS> t;
  t.cols = N + 1;
  for (double mo : out)
    for (double mi : in) {
      t.same.push_back(fourier_kernels<NS>(md, -mo, -mi));
      t.across.push_back(fourier_kernels<NS>(md, mo, -mi));
      Kernels<NS> sm = t.same.back(), am = t.across.back();
      for (int m = 0; m < md.terms; ++m) sm.K[m] = mirrored<NS>(sm.K[m]), am.K[m] = mirrored<NS>(am.K[m]);
      t.same_mirrored.push_back(sm), t.across_mirrored.push_back(am);
    }
  return t;
}

// Light entering the top of the thin layer δ downward in direction `in` (decay rate a: 1/μ_in, or
// the sun's air mass),
// leaving in the outgoing direction `o` (rate c = 1/μ_o): the reflected (up, at the top) and
// transmitted (down, at the bottom, diffuse) responses of every term to first and second order of
// scattering (ϖ in the kernels). The second order sums over the nodes k (rate b) of the
// intermediate leg, down then up; each leg's decay is exact, so grazing streams with δ/μ ≫ 1 stay
// right. The error is O(δ³) per layer, O(δ²) relative after the doublings.
template <int NS>
struct Scattered {
  std::vector<Block<NS>> reflected, transmitted;
};

template <int NS>
Scattered<NS> thin_response(const KernelTable<NS>& t, const Geometry& g, int terms, int o, double mu_o, int in,
                            double a, double delta) {
  const int N = static_cast<int>(g.mu.size());
  const double c = 1 / mu_o;
  const double once_reflected = once_scattered_path(delta, a + c, 0) / mu_o;
  const double once_transmitted = once_scattered_path(delta, a, c) / mu_o;
  Scattered<NS> x;
  x.reflected.resize(static_cast<std::size_t>(terms)), x.transmitted.resize(static_cast<std::size_t>(terms));
  for (int m = 0; m < terms; ++m) {
    x.reflected[m] = t.a(o, in, m) * once_reflected;
    x.transmitted[m] = t.s(o, in, m) * once_transmitted;
  }
  for (int k = 0; k < N; ++k) {
    const double b = 1 / g.mu[k], s_k = g.w[k] / (mu_o * g.mu[k]);
    const double r_down = s_k * twice_scattered_path(delta, a + c, b + c, 0);
    const double r_up = s_k * twice_scattered_path(delta, a + c, a + b, 0);
    const double t_down = s_k * twice_scattered_path(delta, a, b, c);
    const double t_up = s_k * twice_scattered_path(delta, a, a + b + c, c);
    for (int m = 0; m < terms; ++m) {
      const Block<NS>& down_from_in = t.s(k, in, m);
      const Block<NS>& up_from_in = t.a(k, in, m);
      x.reflected[m].noalias() += t.a(o, k, m) * (r_down * down_from_in);
      x.reflected[m].noalias() += t.s_mirrored(o, k, m) * (r_up * up_from_in);
      x.transmitted[m].noalias() += t.s(o, k, m) * (t_down * down_from_in);
      x.transmitted[m].noalias() += t.a_mirrored(o, k, m) * (t_up * up_from_in);
    }
  }
  return x;
}

// The thin layer δ for every Fourier term.
template <int NS>
std::vector<Layer> thin_layers(const Geometry& g, double delta, const Medium& md) {
  const int N = static_cast<int>(g.mu.size()), nu = static_cast<int>(g.view_mu.size());
  const KernelTable<NS> table = kernel_table<NS>(g, md);
  std::vector<Layer> L(static_cast<std::size_t>(md.terms));
  for (int m = 0; m < md.terms; ++m) {
    Layer& l = L[m];
    const int ns = l.ns = stokes_in_term(m, NS), n = N * ns, nv = nu * ns;
    l.R = l.T_minus_E = MatrixXd::Zero(n, n);
    l.r_sun = l.t_sun = VectorXd::Zero(n);
    l.Ru = l.Tu = MatrixXd::Zero(nv, n);
    l.ru_sun = l.tu_sun = VectorXd::Zero(nv);
    l.e_sun_minus_1 = std::expm1(-g.sun_path(delta));
    l.e_view_minus_1.resize(nv);
  }
  // A node column carries its quadrature weight w_j (K already holds the azimuth integral); the
  // sun's column the collimated beam's (2 − δ_m0)/2π from the Fourier series of its source.
  auto fill = [&](int o, double mu_o, MatrixXd Layer::*R, MatrixXd Layer::*T, VectorXd Layer::*r_sun,
                  VectorXd Layer::*t_sun, int row) {
    for (int j = 0; j <= N; ++j) {
      const bool sun = j == N;
      const Scattered<NS> x = thin_response<NS>(table, g, md.terms, o, mu_o, j, sun ? g.sun_rate() : 1 / g.mu[j], delta);
      for (int m = 0; m < md.terms; ++m) {
        Layer& l = L[m];
        const int ns = l.ns;
        if (sun) {
          const double sun_weight = (m == 0 ? 1.0 : 2.0) / (2 * M_PI);
          (l.*r_sun).segment(row * ns, ns) = x.reflected[m].col(0).head(ns) * sun_weight;
          (l.*t_sun).segment(row * ns, ns) = x.transmitted[m].col(0).head(ns) * sun_weight;
        } else {
          (l.*R).block(row * ns, j * ns, ns, ns) = x.reflected[m].topLeftCorner(ns, ns) * g.w[j];
          (l.*T).block(row * ns, j * ns, ns, ns) = x.transmitted[m].topLeftCorner(ns, ns) * g.w[j];
        }
      }
    }
  };
  for (int i = 0; i < N; ++i) {
    fill(i, g.mu[i], &Layer::R, &Layer::T_minus_E, &Layer::r_sun, &Layer::t_sun, i);
    for (Layer& l : L) l.T_minus_E.diagonal().segment(i * l.ns, l.ns).array() += std::expm1(-delta / g.mu[i]);
  }
  for (int u = 0; u < nu; ++u) {
    fill(N + u, g.view_mu[u], &Layer::Ru, &Layer::Tu, &Layer::ru_sun, &Layer::tu_sun, u);
    for (Layer& l : L) l.e_view_minus_1.segment(u * l.ns, l.ns).setConstant(std::expm1(-delta / g.view_mu[u]));
  }
  return L;
}

// Two identical layers a (above) and b (below) as one (van de Hulst 1980; Hansen & Travis 1974
// Eqs. 3.41–3.48 with the sun's and the views' columns and rows). By the mirror symmetry the
// interface's response to light from below is the mirror image of its response from above, so one
// factorisation serves both.
Layer doubled(const Layer& l) {
  const auto n = l.R.rows();
  const MatrixXd I = MatrixXd::Identity(n, n);
  const MatrixXd T = l.T(), Rs = l.Rs(), Ts = l.Ts();
  const MatrixXd RsR = Rs * l.R;
  const Eigen::PartialPivLU<MatrixXd> A(I - RsR);  // (E − R*_a R_b): lit from above
  const double e = l.e_sun();
  Layer o;
  o.ns = l.ns;
  // Lit from above: D = (E − R*R)⁻¹T down and U up at the interface; (E − R*R)⁻¹ = E + (E − R*R)⁻¹R*R
  // keeps D − T = X to its own digits.
  const MatrixXd X = A.solve(RsR * T);
  const MatrixXd D = T + X, U = l.R * D;
  o.R = l.R + Ts * U;
  o.T_minus_E = l.T_minus_E * D + l.T_minus_E + X;  // T·D − E = (T − E)·D + D − E
  // The sun: its direct beam reaches b after a's e.
  const VectorXd d_sun = A.solve(l.t_sun + Rs * (l.r_sun * e));
  const VectorXd u_sun = l.R * d_sun + l.r_sun * e;
  o.r_sun = l.r_sun + Ts * u_sun;
  o.t_sun = T * d_sun + l.t_sun * e;
  o.e_sun_minus_1 = l.e_sun_minus_1 * (2 + l.e_sun_minus_1);
  // The views: their radiance at the interface, then through a (up) or b (down).
  const VectorXd ev = l.e_view();
  const auto Ev = ev.asDiagonal();
  const MatrixXd Rsu = l.Rsu(), Tsu = l.Tsu();
  const MatrixXd Du = l.Tu + Rsu * U, Uu = l.Ru * D;
  o.Ru = l.Ru + Tsu * U + Ev * Uu;
  o.Tu = l.Tu * D + Ev * Du;
  const VectorXd Dus = l.tu_sun + Rsu * u_sun, Uus = l.Ru * d_sun + l.ru_sun * e;
  o.ru_sun = l.ru_sun + Tsu * u_sun + Ev * Uus;
  o.tu_sun = l.Tu * d_sun + Ev * Dus + l.tu_sun * e;
  o.e_view_minus_1 = l.e_view_minus_1.cwiseProduct(l.e_view_minus_1) + 2 * l.e_view_minus_1;  // e² − 1
  return o;
}

// The layer's diffuse field with a Lambertian ground of albedo A under it (m = 0 only: the ground
// reflects isotropically, L = (A/π)·(downward flux)). Returns the views' down and up coefficients
// and the nodes' (for fluxes).
struct Emerging {
  int ns = 3;
  VectorXd down_nodes, up_nodes, down_views, up_views;
};

Emerging with_ground(const Layer& l, const Geometry& g, double A, bool m0) {
  const auto n = l.R.rows();
  const int N = static_cast<int>(g.mu.size()), nu = static_cast<int>(g.view_mu.size()), ns = l.ns;
  Emerging e;
  e.ns = ns;
  if (!m0 || A == 0) {
    e.down_nodes = l.t_sun, e.up_nodes = l.r_sun;
    e.down_views = l.tu_sun, e.up_views = l.ru_sun;
    return e;
  }
  // The ground's reflection of node radiances (flux 2π Σ w_j μ_j I_j) and of the direct beam.
  MatrixXd Rg = MatrixXd::Zero(n, n);
  VectorXd rg_sun = VectorXd::Zero(n);
  for (int i = 0; i < N; ++i) {
    for (int j = 0; j < N; ++j) Rg(i * ns, j * ns) = 2 * A * g.w[j] * g.mu[j];
    rg_sun(i * ns) = A * g.mu0 / M_PI;
  }
  const MatrixXd I = MatrixXd::Identity(n, n), Rs = l.Rs();
  const VectorXd D = Eigen::PartialPivLU<MatrixXd>(I - Rs * Rg).solve(l.t_sun + Rs * rg_sun * l.e_sun());
  const VectorXd U = Rg * D + rg_sun * l.e_sun();  // leaving the ground, at the nodes
  e.down_nodes = D;
  e.up_nodes = l.r_sun + l.Ts() * U;
  e.down_views = l.tu_sun + l.Rsu() * U;
  // Leaving the ground in the views' directions: the same isotropic radiance U(I).
  VectorXd Uv = VectorXd::Zero(nu * ns);
  for (int u = 0; u < nu; ++u) Uv(u * ns) = U(0);
  e.up_views = l.ru_sun + l.Tsu() * U + l.e_view().cwiseProduct(Uv);
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
  if (s.pseudo_spherical) g.sun_air_mass = chapman_air_mass(mu0);
  return g;
}

// The first `terms` Fourier terms of the medium (the fluxes need m = 0 alone).
std::vector<Emerging> solve(const VectorRtSettings& s, const Geometry& g, Medium md, int terms) {
  md.terms = std::min(md.terms, terms);
  int doublings = 0;
  while (md.tau / std::ldexp(1.0, doublings) > kStartDepth) ++doublings;
  const double delta = std::ldexp(md.tau, -doublings);
  std::vector<Layer> L = md.aerosol ? thin_layers<4>(g, delta, md) : thin_layers<3>(g, delta, md);
  std::vector<Emerging> out;
  for (int m = 0; m < md.terms; ++m) {
    Layer l = std::move(L[m]);
    for (int k = 0; k < doublings; ++k) l = doubled(l);
    out.push_back(with_ground(l, g, s.ground_albedo, m == 0));
  }
  return out;
}

// The solver's frame → polrig's: the view v = −k has the same e_θ and the opposite e_φ, so U and V
// change sign; φ(view) − φ(sun) equals the light's relative azimuth.
Eigen::Vector4d to_view_frame(const VectorXd& x, int u, int ns) {
  return {x(u * ns), x(u * ns + 1), ns > 2 ? -x(u * ns + 2) : 0.0, ns > 3 ? -x(u * ns + 3) : 0.0};
}

Eigen::Vector4d fourier_sum(const std::vector<std::vector<Eigen::Vector4d>>& c, std::size_t u, double phi) {
  Eigen::Vector4d out = Eigen::Vector4d::Zero();
  for (std::size_t m = 0; m < c.size(); ++m) {
    const double cm = std::cos(m * phi), sm = std::sin(m * phi);
    out += Eigen::Vector4d(cm, cm, sm, sm).cwiseProduct(c[m][u]);
  }
  return out;
}

// The single-scattering correction (Nakajima & Tanaka 1988): the δ-M layer's once-scattered sky at
// the views, the sun's column of each term's kernel through the whole layer,
// ∫₀^τ' e^{−t/μ₀ − (τ'−t)/μ} dt/μ, is taken out of `down`; SingleScatteringSky puts the exact one back.
void remove_truncated_single(const Medium& md, const Geometry& g, std::vector<Emerging>& e) {
  for (std::size_t u = 0; u < g.view_mu.size(); ++u) {
    const double mu = g.view_mu[u];
    const Kernels<4> K = fourier_kernels<4>(md, -mu, -g.mu0);
    const double path = once_scattered_path(md.tau, g.sun_rate(), 1 / mu) / mu;
    for (std::size_t m = 0; m < e.size(); ++m) {
      const int ns = e[m].ns;
      const double sun_weight = (m == 0 ? 1.0 : 2.0) / (2 * M_PI);
      e[m].down_views.segment(static_cast<Eigen::Index>(u) * ns, ns) -= K.K[m].col(0).head(ns) * (sun_weight * path);
    }
  }
}

}  // namespace

void check_vector_rt(const VectorRtSettings& s) {
  if (!(s.tau_rayleigh >= 0 && s.tau_rayleigh <= 100) || (s.tau_rayleigh == 0 && !(s.aerosol.tau > 0)))
    throw std::invalid_argument(fmt::format("vector-rt sky: tau_rayleigh {} is outside (0, 100] (0 only with an aerosol)",
                                            s.tau_rayleigh));
  if (!(s.depolarization >= 0 && s.depolarization < 0.5))
    throw std::invalid_argument(fmt::format("vector-rt sky: depolarization {} is outside [0, 0.5)", s.depolarization));
  if (!(s.ground_albedo >= 0 && s.ground_albedo <= 1))
    throw std::invalid_argument(fmt::format("vector-rt sky: ground_albedo {} is outside [0, 1]", s.ground_albedo));
  if (s.streams < 4 || s.streams > 128 || s.streams % 2 != 0)
    throw std::invalid_argument(fmt::format("vector-rt sky: streams {} is not an even number in [4, 128]", s.streams));
  const AerosolSettings& a = s.aerosol;
  if (!(a.tau >= 0 && a.tau <= 100))
    throw std::invalid_argument(fmt::format("vector-rt sky: the aerosol's tau {} is outside [0, 100]", a.tau));
  if (!(a.ssa > 0 && a.ssa <= 1))
    throw std::invalid_argument(fmt::format("vector-rt sky: the aerosol's ssa {} is outside (0, 1]", a.ssa));
  if (a.tau == 0) return;
  if (!a.phase) throw std::invalid_argument("vector-rt sky: an aerosol of tau > 0 needs its phase matrix");
  double at_deg = 0;
  const double lowest = lowest_a1(aerosol_delta_m(s).truncated, &at_deg);
  if (lowest < 0)
    throw std::invalid_argument(fmt::format(
        "vector-rt sky: streams {} are too few for the aerosol's phase matrix ({}): truncated at l = {} by δ-M "
        "its phase function is {:.3g} at {:.1f} degrees, not a phase function; give more streams",
        s.streams, a.phase->source, aerosol_order(s.streams), lowest, at_deg));
}

SingleScatteringSky::SingleScatteringSky(const VectorRtSettings& s) : settings_(s) {
  check_vector_rt(s);
  extinction_tau_ = make_medium(s).tau;
}

double SingleScatteringSky::sun_air_mass(double mu0) const {
  return settings_.pseudo_spherical ? chapman_air_mass(mu0) : 1 / mu0;
}

Eigen::Vector4d SingleScatteringSky::down(double mu0, double mu, double phi) const {
  return down(mu0, sun_air_mass(mu0), mu, phi);
}

Eigen::Vector4d SingleScatteringSky::down(double mu0, double air_mass, double mu, double phi) const {
  const VectorRtSettings& s = settings_;
  const double tau = s.tau_rayleigh + s.aerosol.tau;
  const Direction in = direction(-mu0, 0), out = direction(-mu, phi);
  const double x = vec3::dot(in.k, out.k);
  ScatteringElements P = rayleigh_elements(x, s.depolarization);
  if (s.aerosol.tau > 0) P = mixed(P, s.tau_rayleigh / tau, s.aerosol.phase->at(x), s.aerosol.ssa * s.aerosol.tau / tau);
  const Eigen::Vector4d light =
      phase_matrix(in, out, P).col(0) * (tau / extinction_tau_ * once_scattered_path(extinction_tau_, air_mass, 1 / mu) /
                                         (4 * M_PI * mu));
  return {light(0), light(1), -light(2), -light(3)};  // the view's frame (to_view_frame)
}

Eigen::Vector4d DiffuseField::down_at(std::size_t u, double phi) const {
  Eigen::Vector4d out = fourier_sum(down, u, phi);
  if (single) out += single->down(mu0, mu[u], phi);
  return out;
}
Eigen::Vector4d DiffuseField::up_at(std::size_t u, double phi) const { return fourier_sum(up, u, phi); }

DiffuseField solve_vector_rt(const VectorRtSettings& s, double mu0, const std::vector<double>& view_mu) {
  const Geometry g = make_geometry(s, mu0, view_mu);
  const Medium md = make_medium(s);
  std::vector<Emerging> e = solve(s, g, md, md.terms);
  if (md.aerosol) remove_truncated_single(md, g, e);  // the single-scattering correction
  DiffuseField f;
  f.mu = view_mu;
  f.mu0 = mu0;
  f.down.resize(e.size()), f.up.resize(e.size());
  for (std::size_t m = 0; m < e.size(); ++m)
    for (int u = 0; u < static_cast<int>(view_mu.size()); ++u) {
      f.down[m].push_back(to_view_frame(e[m].down_views, u, e[m].ns));
      f.up[m].push_back(to_view_frame(e[m].up_views, u, e[m].ns));
    }
  if (md.aerosol) f.single = std::make_shared<const SingleScatteringSky>(s);
  return f;
}

double min_sun_elevation_deg(const VectorRtSettings& s) { return s.pseudo_spherical ? 1.0 : 2.0; }

double chapman_air_mass(double mu0) {
  if (!(mu0 >= 0 && mu0 <= 1))
    throw std::invalid_argument(fmt::format("chapman_air_mass: cos zenith {} is outside [0, 1]", mu0));
  constexpr double R = 6371, H = 8;  // km
  constexpr int kIntervals = 4000;   // Simpson on [0, 7]: e^{−49} is far below the rule's error
  constexpr double kXMax = 7;
  // h = H x²: ds = (R + h)dh/√((R + h)² − R² sin²θ₀), and dh = 2Hx dx.
  const auto f = [&](double x) {
    const double r = R + H * x * x;
    const double root = std::sqrt(R * R * mu0 * mu0 + 2 * R * H * x * x + H * H * x * x * x * x);
    return x == 0 ? (mu0 > 0 ? 0.0 : 2 * R / std::sqrt(2 * R * H)) : std::exp(-x * x) * 2 * x * r / root;
  };
  const double h = kXMax / kIntervals;
  double sum = f(0) + f(kXMax);
  for (int i = 1; i < kIntervals; ++i) sum += (i % 2 ? 4 : 2) * f(i * h);
  return sum * h / 3;
}

std::string atmosphere_text(const VectorRtSettings& s) {
  std::string text = fmt::format("tau {:.4g}, albedo {:.3g}", s.tau_rayleigh, s.ground_albedo);
  if (s.aerosol.tau > 0) text += fmt::format(", aerosol tau {:.4g}, ssa {:.3g}", s.aerosol.tau, s.aerosol.ssa);
  return text;
}

DiffuseFluxes vector_rt_fluxes(const VectorRtSettings& s, double mu0) {
  const Geometry g = make_geometry(s, mu0, {});
  const Medium md = make_medium(s);
  const Emerging e = solve(s, g, md, 1).front();
  DiffuseFluxes f;
  for (std::size_t j = 0; j < g.mu.size(); ++j) {
    const double weight = 2 * M_PI * g.w[j] * g.mu[j];
    f.up_top += weight * e.up_nodes(static_cast<Eigen::Index>(j) * e.ns);
    f.down_diffuse_bottom += weight * e.down_nodes(static_cast<Eigen::Index>(j) * e.ns);
  }
  f.down_direct_bottom = mu0 * std::exp(-g.sun_path(md.tau));
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
