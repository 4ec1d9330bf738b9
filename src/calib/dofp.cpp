#include "polrig/calib/dofp.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstring>
#include <numbers>
#include <optional>
#include <stdexcept>

#include <Eigen/Dense>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "dofp_lanes.h"
#include "polrig/units.h"

namespace polrig {

namespace {

using Vec8 = Eigen::Matrix<double, 8, 1>;
using Mat8 = Eigen::Matrix<double, 8, 8>;

// Into (−90°, 90°] (the spec's wrap90).
double wrap90_deg(double deg) {
  double w = std::fmod(deg, 180.0);
  if (w <= -90.0) w += 180.0;
  if (w > 90.0) w -= 180.0;
  return w;
}

void check_frame(std::span<const double> frame, std::size_t pixels, std::size_t width,
                 const std::string& what) {
  if (frame.size() != pixels)
    throw std::invalid_argument(
        fmt::format("{}: the frame has {} values, the camera {} pixels", what, frame.size(), pixels));
  for (std::size_t i = 0; i < frame.size(); ++i)
    if (!std::isfinite(frame[i]))
      throw std::invalid_argument(fmt::format("{}: the pixel at column {}, row {} is {}", what,
                                              i % width, i / width, frame[i]));
}

void check_size(int width, int height) {
  if (width <= 0 || height <= 0 || width % 2 != 0 || height % 2 != 0)
    throw std::invalid_argument(fmt::format(
        "DoFP calibration: the frame is {} × {} pixels; both must be positive and even "
        "(whole 2 × 2 cells)", width, height));
}

// Checks every frame of a list in parallel; the lowest failing index is reported, so the message
// does not depend on the thread schedule.
template <class Item>
void check_frames(std::span<const Item> items, std::size_t pixels, std::size_t width,
                  const char* kind) {
  std::vector<std::string> errors(items.size());
  tbb::parallel_for(std::size_t{0}, items.size(), [&](std::size_t i) {
    try {
      check_frame(items[i].frame, pixels, width, fmt::format("{} {}", kind, i));
    } catch (const std::invalid_argument& e) {
      errors[i] = e.what();
    }
  });
  for (const std::string& e : errors)
    if (!e.empty()) throw std::invalid_argument("DoFP calibration: " + e);
}

// ---- The cell model of step 2 (Eqs. 20–22) and its derivatives ----
// x = [ε2, ε3, ε4, k2, k3, k4, ψ0, d0]; pixel j = 0..3 (TL, TR, BL, BR) with k_0 = 1, ε_0 = 0.
struct CellModel {
  Eigen::Matrix<double, 3, 4> P;                    // R⁻¹Ãᵀ (Eq. 21): Q̃ = P·F̃
  std::array<Eigen::Matrix<double, 3, 4>, 6> dP;    // its derivatives by x_0..x_5
  double c2psi = 1, s2psi = 0;                      // cos, sin of −2ψ0
  double d0 = 0, w = 0;                             // the DoP unknown and its residual's weight
  Eigen::Vector4d n;                                // unit normal of Ã's columns in pixel space
  std::array<Eigen::Vector4d, 6> dn;                // its derivatives by x_0..x_5
  double we = 0;                                    // weight of the fit residual
};

// n_i = (−1)^i·det(Ã without row i): orthogonal to Ã's three columns (the 4-D cross product).
Eigen::Vector4d cofactor_normal(const Eigen::Matrix<double, 4, 3>& A) {
  Eigen::Vector4d n;
  for (int i = 0; i < 4; ++i) {
    Eigen::Matrix3d M;
    for (int r = 0, k = 0; r < 4; ++r)
      if (r != i) M.row(k++) = A.row(r);
    n[i] = (i % 2 ? -1.0 : 1.0) * M.determinant();
  }
  return n;
}

// False when ÃᵀÃ is singular (k so small that the four analyzers do not span the Stokes plane).
bool make_cell_model(const Vec8& x, const std::array<double, 4>& alpha_rad, double dop_weight,
                     double fit_weight, bool derivatives, CellModel& m) {
  Eigen::Matrix<double, 4, 3> A;
  std::array<double, 4> c{}, s{}, k{};
  for (int j = 0; j < 4; ++j) {
    const double eps = j == 0 ? 0.0 : x[j - 1];
    k[j] = j == 0 ? 1.0 : x[j + 2];
    c[j] = std::cos(2.0 * (alpha_rad[j] - eps));
    s[j] = std::sin(2.0 * (alpha_rad[j] - eps));
    A.row(j) << k[j] * c[j], k[j] * s[j], 1.0;
  }
  if (!A.allFinite()) return false;
  const Eigen::Matrix3d R = A.transpose() * A;
  Eigen::Matrix3d Rinv;
  bool invertible = false;
  double det = 0;
  R.computeInverseAndDetWithCheck(Rinv, det, invertible, 1e-12 * R.squaredNorm() * R.norm());
  if (!invertible || !(det > 0)) return false;
  m.P = Rinv * A.transpose();
  m.c2psi = std::cos(-2.0 * x[6]);
  m.s2psi = std::sin(-2.0 * x[6]);
  m.d0 = x[7];
  m.w = dop_weight;
  m.we = fit_weight;
  const Eigen::Vector4d n = cofactor_normal(A);
  const double nn = n.norm();
  if (!(nn > 0)) return false;
  m.n = n / nn;
  if (!derivatives) return true;
  for (int p = 0; p < 6; ++p) {
    const int j = p % 3 + 1;
    Eigen::Vector3d u;  // ∂(row j of Ã)/∂x_p
    if (p < 3)
      u << 2.0 * k[j] * s[j], -2.0 * k[j] * c[j], 0.0;  // by ε_j
    else
      u << c[j], s[j], 0.0;                              // by k_j
    const Eigen::Vector3d v = A.row(j).transpose();
    const Eigen::Matrix3d dR = u * v.transpose() + v * u.transpose();
    Eigen::Matrix<double, 3, 4> dAt = Eigen::Matrix<double, 3, 4>::Zero();
    dAt.col(j) = u;
    // ∂(R⁻¹Ãᵀ) = R⁻¹(∂Ãᵀ − ∂R·R⁻¹Ãᵀ)
    m.dP[p] = Rinv * (dAt - dR * m.P);
    // The cofactors are linear in row j: ∂n = the cofactors with row j replaced by u (n_j keeps
    // no row j); then ∂(n/|n|) = (∂n − n̂·(n̂·∂n))/|n|.
    Eigen::Matrix<double, 4, 3> Au = A;
    Au.row(j) = u.transpose();
    Eigen::Vector4d dn = cofactor_normal(Au);
    dn[j] = 0.0;
    m.dn[p] = (dn - m.n * m.n.dot(dn)) / nn;
  }
  return true;
}

// Sums over the observations of one block (4 F̃ values each, and cos, sin of −2·s_R·θ_R).
struct Sums {
  Mat8 JtJ = Mat8::Zero();  // upper triangle
  Vec8 Jtr = Vec8::Zero();
  double cost = 0;     // Σ r² over both kinds of residual
  double aop_ss = 0;   // Σ r² of the AoP residuals (rad²)
  long long bad = -1;  // first observation whose AoP or DoP is undefined, −1 if none
  void add(const Sums& o) {
    JtJ += o.JtJ;
    Jtr += o.Jtr;
    cost += o.cost;
    aop_ss += o.aop_ss;
    if (bad < 0) bad = o.bad;
  }
};

inline double dot4(const double* a, const double* f) {
  return a[0] * f[0] + a[1] * f[1] + a[2] * f[2] + a[3] * f[3];
}

// Per observation two residuals:
//   AoP (H17 Eq. 24, well-posed form): r = wrap90(φ̃ − ψ0 − s_R·θ_R)
//       = ½·arg[(q̃1 + i q̃2)·e^{−2i s_R θ_R}·e^{−2iψ0}] ∈ (−π/2, π/2],
//       ∂r/∂x_p = (q̃1·∂q̃2 − q̃2·∂q̃1) / (2(q̃1² + q̃2²)) (Appendix A's ∂φ̃/∂Q̃), ∂r/∂ψ0 = −1;
//   DoP [C]: r_d = w·(d̃ − d0), d̃ = √(q̃1² + q̃2²)/q̃3 (Eq. 22),
//       ∂d̃/∂x_p = (q̃1·∂q̃1 + q̃2·∂q̃2)/(|q̃|·q̃3) − |q̃|·∂q̃3/q̃3², ∂r_d/∂d0 = −w;
//   Eq. 21's fit [C]: r_e = w_e·n̂ᵀF̃/q̃3, the part of the four pixels that Ã cannot explain (n̂ ⊥
//       Ã's columns), relative to the intensity; ∂r_e = w_e·(∂n̂ᵀF̃/q̃3 − n̂ᵀF̃·∂q̃3/q̃3²).
// With w = w_e = 0 only the AoP residual counts (H17's cost).
template <bool kJacobian>
void accumulate(const CellModel& m, const double* F, const double* rot, std::size_t n, Sums& out,
                double* residuals = nullptr, double* jacobian_rows = nullptr) {
  // Row-major copies of P and dP for dot4.
  double P[3][4], dP[6][3][4];
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 4; ++b) {
      P[a][b] = m.P(a, b);
      if constexpr (kJacobian)
        for (int p = 0; p < 6; ++p) dP[p][a][b] = m.dP[p](a, b);
    }
  const bool dop = m.w != 0.0, fitres = m.we != 0.0;
  // Local accumulators (the compiler keeps them out of memory; `out` may alias nothing, but it
  // cannot know).
  double jtj[6][6] = {}, j6[6] = {}, j7[6] = {}, jtr[8] = {};
  double j66 = 0, j77 = 0, cost = 0, aop_ss = 0;
  long long bad = -1;
  double nv[4], dnv[6][4];
  for (int b = 0; b < 4; ++b) {
    nv[b] = m.n[b];
    if constexpr (kJacobian)
      for (int p = 0; p < 6; ++p) dnv[p][b] = m.dn[p][b];
  }
  for (std::size_t i = 0; i < n; ++i) {
    const double* f = F + 4 * i;
    const double q1 = dot4(P[0], f), q2 = dot4(P[1], f), q3 = dot4(P[2], f);
    const double s = q1 * q1 + q2 * q2;
    if (!(s > 0) || ((dop || fitres) && !(q3 > 0))) {
      if (bad < 0) bad = static_cast<long long>(i);
      continue;
    }
    const double cr = rot[3 * i] * m.c2psi - rot[3 * i + 1] * m.s2psi;
    const double sr = rot[3 * i] * m.s2psi + rot[3 * i + 1] * m.c2psi;
    const double ww = rot[3 * i + 2];  // the observation's weight
    const double r0 = 0.5 * std::atan2(q1 * sr + q2 * cr, q1 * cr - q2 * sr);
    const double r = ww * r0;
    const double a = std::sqrt(s);
    const double rd = dop ? ww * m.w * (a / q3 - m.d0) : 0.0;
    const double nf = fitres ? dot4(nv, f) : 0.0;
    const double re = fitres ? ww * m.we * nf / q3 : 0.0;
    aop_ss += r0 * r0;
    cost += r * r + rd * rd + re * re;
    if (residuals) {
      residuals[3 * i] = r;
      residuals[3 * i + 1] = rd;
      residuals[3 * i + 2] = re;
    }
    if constexpr (kJacobian) {
      double g[6], h[6], e[6];
      const double inv = 0.5 / s, ia = 1.0 / (a * q3), iq = a / (q3 * q3), i3 = 1.0 / q3;
      for (int p = 0; p < 6; ++p) {
        const double dq1 = dot4(dP[p][0], f), dq2 = dot4(dP[p][1], f);
        const double dq3 = dot4(dP[p][2], f);
        g[p] = ww * (q1 * dq2 - q2 * dq1) * inv;
        h[p] = dop ? ww * m.w * ((q1 * dq1 + q2 * dq2) * ia - iq * dq3) : 0.0;
        e[p] = fitres ? ww * m.we * (dot4(dnv[p], f) - nf * dq3 * i3) * i3 : 0.0;
      }
      // JᵀJ's upper triangle: rows g = [g, −ww, 0], h = [h, 0, −ww·w] and e = [e, 0, 0].
      const double g6 = -ww, h7 = -ww * m.w;
      for (int p = 0; p < 6; ++p) {
        for (int q = p; q < 6; ++q) jtj[p][q] += g[p] * g[q] + h[p] * h[q] + e[p] * e[q];
        j6[p] += g[p] * g6;
        j7[p] += h[p] * h7;
        jtr[p] += g[p] * r + h[p] * rd + e[p] * re;
      }
      j66 += g6 * g6;
      j77 += h7 * h7;
      jtr[6] += g6 * r;
      jtr[7] += h7 * rd;
      if (jacobian_rows) {
        double* row = jacobian_rows + 24 * i;
        for (int p = 0; p < 6; ++p) {
          row[p] = g[p];
          row[8 + p] = h[p];
          row[16 + p] = e[p];
        }
        row[6] = g6;
        row[7] = 0.0;
        row[14] = 0.0;
        row[15] = h7;
        row[22] = row[23] = 0.0;
      }
    }
  }
  out.cost += cost;
  out.aop_ss += aop_ss;
  if (out.bad < 0) out.bad = bad;
  if constexpr (kJacobian) {
    for (int p = 0; p < 6; ++p) {
      for (int q = p; q < 6; ++q) out.JtJ(p, q) += jtj[p][q];
      out.JtJ(p, 6) += j6[p];
      out.JtJ(p, 7) += j7[p];
    }
    out.JtJ(6, 6) += j66;
    out.JtJ(7, 7) += j77;
    for (int p = 0; p < 8; ++p) out.Jtr[p] += jtr[p];
  }
}

// The vectorised pass (src/calib/dofp_lanes.*): accumulate's sums with the observations in
// lanes of 8 (structure of arrays), so that each operation works on 8 observations at once:
// every q̃ and ∂q̃ is a linear form of F̃; per lane block the 28 forms (q̃1..3, n̂ᵀF̃,
// 6 × ∂q̃1..3, 6 × ∂n̂ᵀF̃), the residuals and the Jacobian's rows stay in registers or L1, and
// JᵀJ, Jᵀr are summed per lane and reduced once at the end in lane order. Only atan2 stays
// scalar. The cell's observations are padded to whole blocks with copies of the first one at
// weight 0 (their terms are exact zeros). When an observation's AoP or DoP is undefined the
// scalar loop runs instead (it names the first such observation and skips them, as before).
// The sums differ from accumulate's by rounding only (the order of the additions), and the
// SSE2 and AVX2 variants give the same bits; a test checks both.
constexpr int kLanes = dofp_lanes::kLanes;

// The per-stop constants padded to whole lane blocks: cos, sin of −2·s_R·θ_R,m, the stop's
// weight (0 in the padding) and 1 for a real observation (0 in the padding).
struct StopArrays {
  std::size_t n = 0, padded = 0;
  std::vector<double> c, s, w, real;
  explicit StopArrays(const std::vector<double>& rot) {
    n = rot.size() / 3;
    padded = (n + kLanes - 1) / kLanes * kLanes;
    c.assign(padded, 1.0);
    s.assign(padded, 0.0);
    w.assign(padded, 0.0);
    real.assign(padded, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
      c[i] = rot[3 * i];
      s[i] = rot[3 * i + 1];
      w[i] = rot[3 * i + 2];
      real[i] = 1.0;
    }
  }
};

// One thread's work space: the cell's F̃ by pixel, each padded to st.padded.
struct SoaScratch {
  std::vector<double> F;
};

enum class LanePath { Scalar, Sse2, Avx2 };

bool cpu_has_avx2() {
#if defined(__x86_64__) || defined(__i386__)
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
#else
  return false;
#endif
}

template <bool kJacobian>
void accumulate_soa(const CellModel& m, const double* F, const StopArrays& st, const double* rot,
                    SoaScratch& sc, Sums& out,
                    LanePath path = cpu_has_avx2() ? LanePath::Avx2 : LanePath::Sse2) {
  const std::size_t n = st.n, np = st.padded;
  if (path == LanePath::Scalar || n == 0) {
    accumulate<kJacobian>(m, F, rot, n, out);
    return;
  }
  double L[4][28] = {};
  for (int j = 0; j < 4; ++j) {
    for (int a = 0; a < 3; ++a) L[j][a] = m.P(a, j);
    L[j][3] = m.n[j];
    if constexpr (kJacobian)
      for (int p = 0; p < 6; ++p) {
        for (int a = 0; a < 3; ++a) L[j][4 + 3 * p + a] = m.dP[p](a, j);
        L[j][22 + p] = m.dn[p][j];
      }
  }
  sc.F.resize(4 * np);
  for (std::size_t i = 0; i < np; ++i)
    for (int j = 0; j < 4; ++j) sc.F[j * np + i] = F[4 * (i < n ? i : 0) + j];
  dofp_lanes::Input in;
  in.L = &L[0][0];
  in.F = sc.F.data();
  in.c = st.c.data();
  in.s = st.s.data();
  in.w = st.w.data();
  in.real = st.real.data();
  in.padded = np;
  in.c2psi = m.c2psi;
  in.s2psi = m.s2psi;
  in.dop_weight = m.w;
  in.fit_weight = m.we;
  in.d0 = m.d0;
  in.jacobian = kJacobian;
  dofp_lanes::Output o;
  const bool ok = path == LanePath::Avx2 ? dofp_lanes::sums_avx2(in, o) : dofp_lanes::sums_sse2(in, o);
  if (!ok) {
    accumulate<kJacobian>(m, F, rot, n, out);
    return;
  }
  out.cost += o.cost;
  out.aop_ss += o.aop_ss;
  if constexpr (kJacobian) {
    for (int p = 0; p < 8; ++p) {
      for (int q = p; q < 8; ++q) out.JtJ(p, q) += o.JtJ[p][q];
      out.Jtr[p] += o.Jtr[p];
    }
  }
}

// Circular mean ½·arg Σ e^{2i(φ̃_m − s_R θ_R,m)} and mean DoP at x (ψ0, d0 ignored): the start.
void start_sums(const CellModel& m, const double* F, const double* rot, std::size_t n, double& re,
                double& im, double& dsum, long long& dn) {
  for (std::size_t i = 0; i < n; ++i) {
    const double* f = F + 4 * i;
    const double q1 = m.P(0, 0) * f[0] + m.P(0, 1) * f[1] + m.P(0, 2) * f[2] + m.P(0, 3) * f[3];
    const double q2 = m.P(1, 0) * f[0] + m.P(1, 1) * f[1] + m.P(1, 2) * f[2] + m.P(1, 3) * f[3];
    const double q3 = m.P(2, 0) * f[0] + m.P(2, 1) * f[1] + m.P(2, 2) * f[2] + m.P(2, 3) * f[3];
    const double a = std::hypot(q1, q2);
    if (!(a > 0)) continue;
    re += (q1 * rot[3 * i] - q2 * rot[3 * i + 1]) / a;
    im += (q1 * rot[3 * i + 1] + q2 * rot[3 * i]) / a;
    if (q3 > 0) {
      dsum += a / q3;
      ++dn;
    }
  }
}

// The view's projection (options.view_projection; docs/physics.md §14): the cell sees the port
// polarizer's axis (cos β, sin β) as u = M·(cos β, sin β), M = I₂ − (v_x, v_y)(v_x, v_y)ᵀ/(1 + v_z)
// (symmetric; det M = v_z), so φ = arg u and dφ/dβ = det M/|u|² (u × ∂u/∂β = det M).
struct ViewProjection {
  double m11 = 1, m12 = 0, m22 = 1, det = 1;
};
ViewProjection view_projection_of(const Vec3& v) {
  const double g = 1.0 / (1.0 + v[2]);
  ViewProjection p;
  p.m11 = 1.0 - g * v[0] * v[0];
  p.m12 = -g * v[0] * v[1];
  p.m22 = 1.0 - g * v[1] * v[1];
  p.det = p.m11 * p.m22 - p.m12 * p.m12;
  return p;
}

// s_R·θ_R,m in radians per stop.
std::vector<double> table_turns_rad(std::span<const DofpPolarizedStop> stops, double sense) {
  std::vector<double> t(stops.size());
  for (std::size_t m = 0; m < stops.size(); ++m) t[m] = sense * deg2rad(stops[m].theta_R_deg);
  return t;
}

// ---- The closed-form start of step 2 [C] ----
// With a uniform source of DoP d at AoP φ_m = ψ0 + s_R·θ_R,m and intensity c·I_m (c unknown,
// common to the four pixels), Eqs. 20–21 give per pixel j
//   F̃_j,m = c·I_m·(1 + k_j·d·cos(A_j − 2β_m)),   A_j = 2(α_j − ε_j − ψ0),   β_m = s_R·θ_R,m,
// linear in [c, c·k_j·d·cos A_j, c·k_j·d·sin A_j] on the rows I_m·[1, cos 2β_m, sin 2β_m]. Per
// pixel a linear least squares gives z_j = k_j·d·e^{iA_j} (coefficients 2 + i3 over 1), and with
// the gauge k_1 = 1, ε_1 = 0 (Eq. 25):
//   d0 = |z_1|,  k_j = |z_j|/|z_1|,  ψ0 = ½·arg(z̄_1·e^{2iα_1}),  ε_j = −½·arg(z_j·z̄_1·e^{−2i(α_j − α_1)}),
// exact on noise-free data of the model, so that LM needs about two passes instead of about six.
// The normal matrix depends on the stops only: its inverse is made once.
struct ClosedFormStart {
  bool ok = false;                   // false: the rows do not determine the three coefficients
  Eigen::Matrix3d Ninv;              // (ΣDᵀD)⁻¹ over the rows D_m = I_m·[1, cos 2β_m, sin 2β_m]
  std::vector<double> row;           // per stop: I_m·[1, cos 2β_m, sin 2β_m]
  ClosedFormStart(std::span<const DofpPolarizedStop> stops, const std::vector<double>& rot) {
    double top = 0;
    for (const DofpPolarizedStop& s : stops) top = std::max(top, s.intensity);
    if (!(top > 0) || !std::isfinite(top)) return;
    row.resize(3 * stops.size());
    Eigen::Matrix3d N = Eigen::Matrix3d::Zero();
    for (std::size_t m = 0; m < stops.size(); ++m) {
      const double I = std::max(stops[m].intensity, 0.0) / top;
      const Eigen::Vector3d d(I, I * rot[3 * m], -I * rot[3 * m + 1]);  // rot: cos, sin of −2β
      for (int a = 0; a < 3; ++a) row[3 * m + a] = d[a];
      N += d * d.transpose();
    }
    // Well-conditioned when the stops' angles spread over the half turn: the scaled normal
    // matrix's smallest eigenvalue is then a fair fraction of its largest (1/2 for even spread).
    const Eigen::Vector3d sc = N.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
    const Eigen::Matrix3d S = sc.asDiagonal() * N * sc.asDiagonal();
    const Eigen::Vector3d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(S).eigenvalues();
    if (!(ev[0] > 1e-6 * ev[2])) return;
    Ninv = N.inverse();
    ok = Ninv.allFinite();
  }
  // Adds one cell's right-hand sides Σ_m D_m·F̃_j,m (g[j], pixel j) over its n observations.
  void add(const double* F, std::size_t n, Eigen::Matrix<double, 3, 4>& g) const {
    for (std::size_t m = 0; m < n; ++m)
      for (int j = 0; j < 4; ++j)
        for (int a = 0; a < 3; ++a) g(a, j) += row[3 * m + a] * F[4 * m + j];
  }
  // The start from the summed right-hand sides; false (use the nominal start) when a pixel's
  // modulation or intensity is not positive, or an ε is 22.5° or more: the pixel's axis would be
  // nearer another of the mosaic's nominal axes than its own (a mislabelled mosaic or the wrong
  // table sense, which a fit from the nominal start must report instead of fitting).
  bool start(const Eigen::Matrix<double, 3, 4>& g, const std::array<double, 4>& alpha, Vec8& x) const {
    if (!ok) return false;
    const Eigen::Matrix<double, 3, 4> coef = Ninv * g;
    std::array<std::complex<double>, 4> z;
    for (int j = 0; j < 4; ++j) {
      if (!(coef(0, j) > 0)) return false;
      z[j] = std::complex<double>(coef(1, j), coef(2, j)) / coef(0, j);
      if (!(std::abs(z[j]) > 0) || !std::isfinite(std::abs(z[j]))) return false;
    }
    const double d = std::abs(z[0]);
    x[6] = 0.5 * std::arg(std::conj(z[0]) * std::polar(1.0, 2.0 * alpha[0]));
    x[7] = d;
    for (int j = 1; j < 4; ++j) {
      const double eps =
          -0.5 * std::arg(z[j] * std::conj(z[0]) * std::polar(1.0, -2.0 * (alpha[j] - alpha[0])));
      if (!(std::abs(eps) < std::numbers::pi / 8)) return false;
      x[j - 1] = eps;
      x[j + 2] = std::abs(z[j]) / d;
    }
    return x.allFinite();
  }
};

const char* const kUnknownNames[8] = {"eps2", "eps3", "eps4", "k2", "k3", "k4", "psi0", "d0"};
// With the view's projection ψ_0 is held and x_6 is ε_1, the four analyzers' common rotation
// (x_0..2 then are ε_2..4 − ε_1).
const char* const kProjectedUnknownNames[8] = {"eps2-eps1", "eps3-eps1", "eps4-eps1", "k2", "k3", "k4",
                                               "eps1", "d0"};

// Rank of J from JᵀJ scaled to unit diagonal, over the first `n` unknowns; `weakest` names the
// unknown with the largest share in the least determined direction.
int jacobian_rank(const Mat8& JtJ_upper, int n, double min_ratio, int& weakest) {
  const Mat8 full = JtJ_upper.selfadjointView<Eigen::Upper>();
  Eigen::MatrixXd S = full.topLeftCorner(n, n);
  Eigen::VectorXd d(n);
  for (int i = 0; i < n; ++i) d[i] = S(i, i) > 0 ? 1.0 / std::sqrt(S(i, i)) : 0.0;
  S = d.asDiagonal() * S * d.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(S);
  const Eigen::VectorXd lambda = es.eigenvalues().cwiseMax(0.0);  // ascending
  const double top = lambda[n - 1];
  int rank = 0;
  for (int i = 0; i < n; ++i)
    if (top > 0 && std::sqrt(lambda[i] / top) > min_ratio) ++rank;
  es.eigenvectors().col(0).cwiseAbs().maxCoeff(&weakest);
  for (int i = 0; i < n; ++i)
    if (d[i] == 0) weakest = i;
  return rank;
}

// Levenberg–Marquardt (Eqs. 28–29 damped: (JᵀJ + λ·diag JᵀJ)·Δ = −Jᵀr; λ ÷ 10 after a step that
// lowers the cost, × 10 and retry after one that does not); stopping rule of spec §2.4 [C]:
// |Δx| < step_tolerance on an accepted step, or max_iterations. `eval(x, jac, sums)` returns the
// sums over every observation of the fit.
// The start is `closed` (ClosedFormStart) when there is one and the model is defined there,
// else `nominal()`: ε = 0, k = 1 and start_sums's ψ0, d0.
template <class Eval, class Nominal>
DofpCellFit levenberg_marquardt(Eval&& eval, const std::optional<Vec8>& closed, Nominal&& nominal,
                                long long n, const DofpStep2Options& o,
                                const char* const* names = kUnknownNames, double residual_ulps = 0) {
  DofpCellFit fit;
  fit.observations = static_cast<int>(n);
  const bool dop = o.dop_weight != 0.0;
  const int unknowns = dop ? 8 : 7;
  const long long residuals = n * (1 + dop + (o.fit_weight != 0.0));
  if (residuals < unknowns) {
    fit.termination = FitTermination::TooFewObservations;
    fit.message = fmt::format("{} observations for {} unknowns", n, unknowns);
    return fit;
  }
  Vec8 x;
  Sums acc;
  bool started = false;
  if (closed) {
    x = *closed;
    if (!dop) x[7] = 0.0;
    started = eval(x, true, acc) && acc.bad < 0;
  }
  if (!started) {
    x = nominal();
    if (!dop) x[7] = 0.0;
    acc = Sums{};
  }
  if (!started && (!eval(x, true, acc) || acc.bad >= 0)) {
    fit.termination = FitTermination::OutsideDomain;
    fit.message = acc.bad >= 0 ? fmt::format("the AoP or DoP is undefined at observation {} "
                                             "(no polarized signal)", acc.bad)
                               : "the start is outside the model";
    return fit;
  }
  const double scale = static_cast<double>(n);
  fit.initial_rms_deg = rad2deg(std::sqrt(acc.aop_ss / scale));
  double cost = acc.cost, aop_ss = acc.aop_ss;
  const auto set_result = [&](const Vec8& at) {
    for (int j = 1; j < 4; ++j) {
      fit.eps_deg[j] = rad2deg(at[j - 1]);
      fit.k[j] = at[j + 2];
    }
    fit.psi0_deg = wrap90_deg(rad2deg(at[6]));
    fit.dop = dop ? at[7] : std::numeric_limits<double>::quiet_NaN();
    fit.final_rms_deg = rad2deg(std::sqrt(aop_ss / scale));
  };
  double lambda = 1e-3;
  bool converged = false;
  for (int it = 1; it <= o.max_iterations && !converged; ++it) {
    Mat8 JtJ = acc.JtJ.selfadjointView<Eigen::Upper>();
    if (!dop) {  // d0 is not an unknown: keep it where it is
      JtJ.row(7).setZero();
      JtJ.col(7).setZero();
      JtJ(7, 7) = 1.0;
    }
    Vec8 grad = acc.Jtr;
    if (!dop) grad[7] = 0;
    bool accepted = false;
    Vec8 step = Vec8::Zero(), xn;
    Sums trial;
    // The decrease the model predicts for the first trial step, −gᵀΔ − ½ΔᵀJᵀJΔ: a step that is
    // rejected although the model promises more than rounding — 1e-10 of the cost (≈ 1e-13 for
    // ~10³ residuals), or, at an exact fit, the cost of residuals of a few ulps of 1 rad each
    // (3n·(4·2⁻⁵²)²) — is a stall, not the cost's floor.
    double predicted = std::numeric_limits<double>::infinity();
    // With residual_ulps > 0 also the cost's own rounding, 2·√(cost·3n)·δ for residuals each off
    // by δ = residual_ulps·ε_double (the projected model's longer arithmetic per stop).
    const double rounding = 1e-10 * cost + 3.0 * scale * std::pow(4.0 * std::numeric_limits<double>::epsilon(), 2) +
                            2.0 * std::sqrt(cost * 3.0 * scale) * residual_ulps * std::numeric_limits<double>::epsilon();
    bool at_floor = false;
    for (int h = 0; h <= o.max_halvings; ++h) {
      Mat8 Aug = JtJ;
      for (int p = 0; p < 8; ++p) Aug(p, p) += lambda * std::max(JtJ(p, p), 1e-12);
      step = -Aug.ldlt().solve(grad);
      if (!step.allFinite()) {
        lambda *= 10;
        continue;
      }
      if (!std::isfinite(predicted)) predicted = -grad.dot(step) - 0.5 * step.dot(JtJ * step);
      // A step below the tolerance that promises no more than rounding ends the fit whether or
      // not it would lower the cost (both end as converged below): x moves by < step_tolerance
      // if it is taken, so it is not evaluated, which saves each cell's last pass.
      if (step.norm() < o.step_tolerance && predicted <= rounding) {
        at_floor = true;
        break;
      }
      xn = x + step;
      trial = Sums{};
      // The trial pass sums the Jacobian too: an accepted step (the usual case) needs no
      // second pass over the observations.
      if (eval(xn, true, trial) && trial.bad < 0 && trial.cost <= cost) {
        accepted = true;
        break;
      }
      if (step.norm() < o.step_tolerance) break;  // at the cost's floor
      lambda *= 10;
    }
    if (!accepted) {
      if (at_floor || (step.allFinite() && step.norm() < o.step_tolerance && predicted <= rounding)) {
        converged = true;
        break;
      }
      fit.termination = FitTermination::NoConvergence;
      fit.message = fmt::format("no step lowered the cost after {} tries (the model promised {:.3g} of {:.3g})",
                                o.max_halvings + 1, predicted, cost);
      fit.iterations = it - 1;
      set_result(x);
      return fit;
    }
    x = xn;
    cost = trial.cost;
    aop_ss = trial.aop_ss;
    lambda = std::max(lambda / 10, 1e-12);
    fit.iterations = it;
    if (step.norm() < o.step_tolerance) converged = true;
    acc = trial;
  }
  set_result(x);
  int weakest = 0;
  fit.rank = jacobian_rank(acc.JtJ, unknowns, o.min_singular_ratio, weakest);
  if (fit.rank < unknowns) {
    fit.termination = FitTermination::RankDeficient;
    fit.message = fmt::format("the data determine {} of the {} unknowns (least: {})", fit.rank,
                              unknowns, names[weakest]);
    return fit;
  }
  if (!converged) {
    fit.termination = FitTermination::NoConvergence;
    fit.message = fmt::format("|dx| still >= {:g} after {} iterations", o.step_tolerance,
                              o.max_iterations);
    return fit;
  }
  for (int j = 1; j < 4; ++j)
    if (!(fit.k[j] > 0)) {
      fit.termination = FitTermination::OutsideDomain;
      fit.message = fmt::format("k{} = {:.6g} is not positive", j + 1, fit.k[j]);
      return fit;
    }
  fit.termination = FitTermination::Converged;
  return fit;
}

Vec8 ideal_x() {
  Vec8 x;
  x << 0, 0, 0, 1, 1, 1, 0, 0;
  return x;
}

Vec8 nominal_start(double psi0, double d0) {
  Vec8 x;
  x << 0, 0, 0, 1, 1, 1, psi0, d0;
  return x;
}

std::array<double, 4> alpha_rad_of(const DofpStep2Options& o) {
  std::array<double, 4> a{};
  for (int j = 0; j < 4; ++j) a[j] = deg2rad(o.mosaic_deg[j]);
  return a;
}

void check_step2_options(const DofpStep2Options& o) {
  if (o.table_sense != 1.0 && o.table_sense != -1.0)
    throw std::invalid_argument(
        fmt::format("DoFP step 2: table_sense is {}; it must be +1 or -1", o.table_sense));
  if (o.max_iterations <= 0 || o.max_halvings < 0 || !(o.step_tolerance > 0) ||
      !(o.min_singular_ratio > 0 && o.min_singular_ratio < 1) ||
      !(std::isfinite(o.dop_weight) && o.dop_weight >= 0) ||
      !(std::isfinite(o.fit_weight) && o.fit_weight >= 0))
    throw std::invalid_argument("DoFP step 2: max_iterations must be > 0, max_halvings >= 0, "
                                "step_tolerance > 0, 0 < min_singular_ratio < 1, dop_weight >= 0 and fit_weight >= 0");
  for (double a : o.mosaic_deg)
    if (!std::isfinite(a))
      throw std::invalid_argument("DoFP step 2: the mosaic angles must be finite");
  if (o.view_projection &&
      (!(std::isfinite(o.focal_px) && o.focal_px > 0) || std::isinf(o.principal_x_px) || std::isinf(o.principal_y_px)))
    throw std::invalid_argument(fmt::format(
        "DoFP step 2: the view's projection needs a finite focal length > 0 px and a finite principal "
        "point (or NaN: the image centre); got f_c = {} px, ({}, {}) px",
        o.focal_px, o.principal_x_px, o.principal_y_px));
}

// Per stop: cos and sin of −2·s_R·θ_R,m, and the weight of its residuals (I_m/I_max, or 1).
std::vector<double> table_rotations(std::span<const DofpPolarizedStop> stops, double sense,
                                    bool weight_by_intensity) {
  double top = 0;
  for (const DofpPolarizedStop& s : stops) top = std::max(top, s.intensity);
  std::vector<double> rot(3 * stops.size());
  for (std::size_t m = 0; m < stops.size(); ++m) {
    const double a = -2.0 * sense * deg2rad(stops[m].theta_R_deg);
    rot[3 * m] = std::cos(a);
    rot[3 * m + 1] = std::sin(a);
    rot[3 * m + 2] = weight_by_intensity && top > 0 ? stops[m].intensity / top : 1.0;
  }
  return rot;
}

// The first pixel of a cell that step 1 left undetermined, or −1.
long long undetermined_pixel(const DofpStep1& s1, int cx, int cy) {
  for (int j = 0; j < 4; ++j) {
    const long long p = static_cast<long long>(2 * cy + j / 2) * s1.width + 2 * cx + j % 2;
    if (s1.rank[p] < 2) return p;
  }
  return -1;
}

// F̃ = (f − b)/K of one cell row: out[(cx·M + m)·4 + j].
void gather_cell_row(const DofpStep1& s1, std::span<const DofpPolarizedStop> stops, int cy,
                     std::vector<double>& out) {
  const std::size_t M = stops.size();
  const int W = s1.width, cells_x = W / 2;
  out.resize(static_cast<std::size_t>(cells_x) * M * 4);
  const std::size_t r0 = static_cast<std::size_t>(2 * cy) * W, r1 = r0 + W;
  for (std::size_t m = 0; m < M; ++m) {
    const double* f = stops[m].frame.data();
    for (int cx = 0; cx < cells_x; ++cx) {
      const std::size_t p[4] = {r0 + 2 * cx, r0 + 2 * cx + 1, r1 + 2 * cx, r1 + 2 * cx + 1};
      double* o = &out[(static_cast<std::size_t>(cx) * M + m) * 4];
      for (int j = 0; j < 4; ++j)
        o[j] = s1.rank[p[j]] == 2 ? (f[p[j]] - s1.b[p[j]]) / s1.K[p[j]] : 0.0;
    }
  }
}


// ---- The view's projection with one ψ_0 for the image (options.view_projection; physics §14) ----
// Each pixel j of a cell sees the port polarizer along its own view: φ_j,m = arg(M_j·(cos β_m,
// sin β_m)), β_m = ψ_0 + s_R·θ_R,m. With ψ_0 held, the cell's unknowns are x = [ε2 − ε1, ε3 − ε1,
// ε4 − ε1, k2, k3, k4, ε1, d0]: pixel j's term cos(2φ_j,m − 2(α_j − ε_j)) is Eq. 17's with the TL
// pixel's AoP φ_1,m and the relative error ε_j − ε_1 + (φ_j,m − φ_1,m), so stop m has its own Ã
// (CellModel) and the AoP residual is ½·arg[(q̃1 + i q̃2)·e^{−2iε1}·e^{−2iφ_1,m}] (accumulate's
// with x_6 = ε1 and the rotation e^{−2iφ_1,m}).
using PixelProjections = std::array<ViewProjection, 4>;
// The rounding of a projected residual, in ulps of 1 rad, for the stopping rule: each stop builds
// its own model (Ã_m, R⁻¹, the views' angles), so a few hundred operations stand between the frames
// and r_m; 128 ulps (3e-14 rad) is far below any noise and far above what ends a well-posed fit.
constexpr double kProjectedResidualUlps = 128;

PixelProjections cell_pixel_projections(int width, int height, const DofpStep2Options& o, int cx, int cy) {
  PixelProjections p;
  for (int j = 0; j < 4; ++j)
    p[j] = view_projection_of(dofp_pixel_view(width, height, o, 2 * cx + j % 2, 2 * cy + j / 2));
  return p;
}

// φ = arg(M·(cos β, sin β)) and dφ/dβ = det M/|u|².
double projected_angle(const ViewProjection& M, double beta, double* dphi_dbeta = nullptr) {
  const double cb = std::cos(beta), sb = std::sin(beta);
  const double u1 = M.m11 * cb + M.m12 * sb, u2 = M.m12 * cb + M.m22 * sb;
  if (dphi_dbeta) *dphi_dbeta = M.det / (u1 * u1 + u2 * u2);
  return std::atan2(u2, u1);
}

// Per stop of one cell at ψ_0: TL's rotation (cos 2φ_1,m, sin(−2φ_1,m), the stop's weight), the
// other pixels' φ_j,m − φ_1,m (wrapped into (−π/2, π/2]) and every pixel's dφ_j,m/dψ_0.
struct ProjectedStops {
  std::vector<double> rot, shift, dphi;  // 3, 3 and 4 per stop
};

double wrap_half_pi(double a) { return std::remainder(a, std::numbers::pi); }

void project_stops(const PixelProjections& M, const std::vector<double>& turns, const std::vector<double>& rot,
                   double psi0, ProjectedStops& ps) {
  const std::size_t n = turns.size();
  ps.rot.resize(3 * n), ps.shift.resize(3 * n), ps.dphi.resize(4 * n);
  for (std::size_t m = 0; m < n; ++m) {
    double phi[4];
    for (int j = 0; j < 4; ++j) phi[j] = projected_angle(M[j], psi0 + turns[m], &ps.dphi[4 * m + j]);
    ps.rot[3 * m] = std::cos(2.0 * phi[0]);
    ps.rot[3 * m + 1] = -std::sin(2.0 * phi[0]);
    ps.rot[3 * m + 2] = rot[3 * m + 2];
    for (int j = 1; j < 4; ++j) ps.shift[3 * m + j - 1] = wrap_half_pi(phi[j] - phi[0]);
  }
}

// accumulate's sums over a cell's stops with each stop's own model (x shifted by its pixels' views);
// residuals and Jacobian rows as accumulate's. False where the model is singular.
template <bool kJacobian>
bool accumulate_projected(const Vec8& x, const std::array<double, 4>& alpha, const DofpStep2Options& o,
                          const double* F, const ProjectedStops& ps, std::size_t n, Sums& out,
                          double* residuals = nullptr, double* jacobian_rows = nullptr) {
  CellModel model;
  for (std::size_t m = 0; m < n; ++m) {
    Vec8 xm = x;
    for (int p = 0; p < 3; ++p) xm[p] += ps.shift[3 * m + p];
    if (!make_cell_model(xm, alpha, o.dop_weight, o.fit_weight, kJacobian, model)) return false;
    const long long bad_before = out.bad;
    accumulate<kJacobian>(model, F + 4 * m, &ps.rot[3 * m], 1, out, residuals ? residuals + 3 * m : nullptr,
                          jacobian_rows ? jacobian_rows + 24 * m : nullptr);
    if (bad_before < 0 && out.bad >= 0) out.bad = static_cast<long long>(m);
  }
  return true;
}

// ψ_0's share of one fit at x: J_xᵀJ_x (8 × 8), J_xᵀJ_ψ, J_xᵀr, J_ψᵀJ_ψ, J_ψᵀr and Σr². ψ_0 moves
// TL's rotation (∂r/∂ψ_0 = ∂r/∂ε1·dφ_1/dψ_0) and each pixel's shift (∂r/∂x_p·(dφ_{p+1} − dφ_1)/dψ_0).
struct Psi0Share {
  Mat8 H = Mat8::Zero();
  Vec8 b = Vec8::Zero(), gx = Vec8::Zero();
  double c = 0, gpsi = 0, cost = 0;
  void add(const Psi0Share& o) {
    H += o.H, b += o.b, gx += o.gx;
    c += o.c, gpsi += o.gpsi, cost += o.cost;
  }
};

// ∂r/∂ψ_0 of one residual row (accumulate's 8 columns) at a stop with every pixel's dφ/dψ_0.
double psi0_column(const double* row, const double* dphi) {
  double j = row[6] * dphi[0];
  for (int p = 0; p < 3; ++p) j += row[p] * (dphi[p + 1] - dphi[0]);
  return j;
}

bool psi0_share(const Vec8& x, const std::array<double, 4>& alpha, const DofpStep2Options& o, const double* F,
                const ProjectedStops& ps, std::size_t n, Psi0Share& s) {
  std::vector<double> r(3 * n, 0.0), J(24 * n, 0.0);
  Sums sums;
  if (!accumulate_projected<true>(x, alpha, o, F, ps, n, sums, r.data(), J.data()) || sums.bad >= 0) return false;
  for (std::size_t m = 0; m < n; ++m) {
    const double* d = &ps.dphi[4 * m];
    for (int k = 0; k < 3; ++k) {
      const Eigen::Map<const Vec8> row(&J[24 * m + 8 * k]);
      const double ri = r[3 * m + k];
      const double jpsi = psi0_column(&J[24 * m + 8 * k], d);
      s.H += row * row.transpose();
      s.b += row * jpsi;
      s.gx += row * ri;
      s.c += jpsi * jpsi;
      s.gpsi += jpsi * ri;
      s.cost += ri * ri;
    }
  }
  return true;
}

// The share reduced over the fit's own unknowns (d0 only with the DoP residual): one term of ψ_0's
// Gauss–Newton equation (Schur complement).
void reduce_psi0_share(const Psi0Share& s, bool dop, DofpPsi0Pass& pass) {
  const int n = dop ? 8 : 7;
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(s.H.topLeftCorner(n, n));
  const Eigen::VectorXd hb = ldlt.solve(s.b.head(n)), hg = ldlt.solve(s.gx.head(n));
  pass.gradient += s.gpsi - s.b.head(n).dot(hg);
  pass.curvature += s.c - s.b.head(n).dot(hb);
  pass.raw_curvature += s.c;
  pass.cost += s.cost;
  pass.fits += 1;
}

// A fit made with ψ_0 held (x_6 = ε1) in the absolute gauge: ε_1 = x_6, ε_j = (ε_j − ε_1) + ε_1.
void to_absolute_gauge(DofpCellFit& fit, double psi0_deg) {
  const double eps1 = fit.psi0_deg;  // levenberg_marquardt's x_6, wrapped into (−90°, 90°]
  fit.eps_deg[0] = eps1;
  for (int j = 1; j < 4; ++j) fit.eps_deg[j] += eps1;
  fit.psi0_deg = wrap90_deg(psi0_deg);
}

// What every projected fit of one step 2 shares.
struct ProjectedContext {
  const DofpStep2Options& o;
  std::array<double, 4> alpha;
  const std::vector<double>& turns;  // s_R·θ_R,m (rad)
  const std::vector<double>& rot;    // table_rotations (their weights)
  const ClosedFormStart& cf;
};

// One cell fitted with ψ_0 (rad) held; its share of ψ_0's equation added to `pass` when usable.
// A usable fit made at another ψ_0 (its psi0_deg) as a start at psi0: the same analyzers, ε_1 turned
// by the change of ψ_0 (near the axis they trade one for one).
std::optional<Vec8> start_from(const DofpCellFit* f, double psi0) {
  if (!f || !f->usable()) return std::nullopt;
  Vec8 x;
  x << deg2rad(f->eps_deg[1] - f->eps_deg[0]), deg2rad(f->eps_deg[2] - f->eps_deg[0]),
      deg2rad(f->eps_deg[3] - f->eps_deg[0]), f->k[1], f->k[2], f->k[3],
      wrap_half_pi(deg2rad(f->eps_deg[0] + f->psi0_deg) - psi0), std::isnan(f->dop) ? 0.0 : f->dop;
  return x;
}

DofpCellFit fit_projected_cell(const ProjectedContext& ctx, const PixelProjections& views, const double* F,
                               double psi0, const DofpCellFit* warm, DofpPsi0Pass& pass) {
  const std::size_t n = ctx.turns.size();
  ProjectedStops ps;
  project_stops(views, ctx.turns, ctx.rot, psi0, ps);
  const auto eval = [&](const Vec8& x, bool jac, Sums& sums) {
    return jac ? accumulate_projected<true>(x, ctx.alpha, ctx.o, F, ps, n, sums)
               : accumulate_projected<false>(x, ctx.alpha, ctx.o, F, ps, n, sums);
  };
  std::optional<Vec8> closed = start_from(warm, psi0);
  if (!closed && ctx.cf.ok) {
    Eigen::Matrix<double, 3, 4> g = Eigen::Matrix<double, 3, 4>::Zero();
    ctx.cf.add(F, n, g);
    if (Vec8 x; ctx.cf.start(g, ctx.alpha, x)) {
      x[6] = wrap_half_pi(x[6] - psi0);  // H17's gauge: its ψ_0 is ψ_0 + ε1 (near the axis)
      closed = x;
    }
  }
  const auto nominal = [&] {
    double re = 0, im = 0, dsum = 0;
    long long dn = 0;
    CellModel model;
    if (make_cell_model(ideal_x(), ctx.alpha, ctx.o.dop_weight, ctx.o.fit_weight, false, model))
      start_sums(model, F, ps.rot.data(), n, re, im, dsum, dn);
    return nominal_start(0.5 * std::atan2(im, re), dn > 0 ? dsum / dn : 0.0);
  };
  DofpCellFit fit = levenberg_marquardt(eval, closed, nominal, static_cast<long long>(n), ctx.o,
                                        kProjectedUnknownNames, kProjectedResidualUlps);
  Vec8 x;
  x << deg2rad(fit.eps_deg[1]), deg2rad(fit.eps_deg[2]), deg2rad(fit.eps_deg[3]), fit.k[1], fit.k[2], fit.k[3],
      deg2rad(fit.psi0_deg), std::isnan(fit.dop) ? 0.0 : fit.dop;
  to_absolute_gauge(fit, rad2deg(psi0));
  if (Psi0Share s; fit.usable() && psi0_share(x, ctx.alpha, ctx.o, F, ps, n, s))
    reduce_psi0_share(s, ctx.o.dop_weight != 0.0, pass);
  return fit;
}


// Table 1 with the view's projection: a cell's port-plane angle β̃ from its four values F̃. Its
// model depends on β itself (the pixels' shifts φ_j − φ_1), so from the shifts 0: the TL view's
// AoP φ̃_1 = φ̃ − ε1, β̃ = arg(M_1⁻¹·(cos φ̃_1, sin φ̃_1)) (M⁻¹ ∝ adj M), the shifts at β̃, again until
// β̃ moves by < 1e-13 rad (each step shrinks the error by |d(φ_j − φ_1)/dβ|, ~1e-3 for H17's
// pixels) or 50 steps. False where the AoP is undefined.
struct ProjectedCell {
  Vec8 x;       // [ε2 − ε1, ε3 − ε1, ε4 − ε1, k2, k3, k4, ·, ·]
  double eps1;  // rad
  PixelProjections views;
};

bool port_angle(const ProjectedCell& c, const std::array<double, 4>& alpha, const double* F, double& beta) {
  double shift[3] = {0, 0, 0};
  beta = std::numeric_limits<double>::quiet_NaN();
  CellModel m;
  for (int it = 0; it < 50; ++it) {
    Vec8 x = c.x;
    for (int p = 0; p < 3; ++p) x[p] += shift[p];
    if (!make_cell_model(x, alpha, 0.0, 0.0, false, m)) return false;
    const double q1 = m.P(0, 0) * F[0] + m.P(0, 1) * F[1] + m.P(0, 2) * F[2] + m.P(0, 3) * F[3];
    const double q2 = m.P(1, 0) * F[0] + m.P(1, 1) * F[1] + m.P(1, 2) * F[2] + m.P(1, 3) * F[3];
    if (!(q1 * q1 + q2 * q2 > 0)) return false;
    const double phi1 = 0.5 * std::atan2(q2, q1) - c.eps1, cp = std::cos(phi1), sp = std::sin(phi1);
    const ViewProjection& M = c.views[0];
    const double b = std::atan2(-M.m12 * cp + M.m11 * sp, M.m22 * cp - M.m12 * sp);
    const bool settled = std::abs(wrap_half_pi(b - beta)) < 1e-13;
    beta = b;
    if (settled) break;
    const double phi0 = projected_angle(c.views[0], beta);
    for (int j = 1; j < 4; ++j) shift[j - 1] = wrap_half_pi(projected_angle(c.views[j], beta) - phi0);
  }
  return true;
}

// A cell with a pixel step 1 left undetermined: its fit says so (true), and is not run.
bool undetermined_cell_fit(const DofpStep1& s1, int cx, int cy, std::size_t stops, DofpCellFit& fit) {
  const long long p = undetermined_pixel(s1, cx, cy);
  if (p < 0) return false;
  fit.termination = FitTermination::RankDeficient;
  fit.observations = static_cast<int>(stops);
  fit.message = fmt::format("step 1 left pixel (column {}, row {}) undetermined (rank {})", p % s1.width,
                            p / s1.width, int{s1.rank[p]});
  return true;
}

// One pass of the per-cell projected fit at ψ_0 (rad): every cell of `out`, the sums in row order.
// Each usable fit of `starts` (the previous pass's, at its own ψ_0) starts its cell's fit.
std::vector<DofpPsi0Pass> projected_cells_pass(const DofpStep1& s1, std::span<const DofpPolarizedStop> stops,
                                               const ProjectedContext& ctx, double psi0,
                                               std::span<const DofpCellFit> starts, DofpStep2& out,
                                               const Progress& progress) {
  const int cells_x = out.cells_x, cells_y = out.cells_y;
  const std::size_t M = stops.size();
  std::vector<DofpPsi0Pass> rows(static_cast<std::size_t>(cells_y));
  progress.begin(fmt::format("calibrate dofp: step 2 cells at psi0 = {:.9g} deg", rad2deg(psi0)),
                 static_cast<long long>(out.cells.size()));
  tbb::parallel_for(tbb::blocked_range<int>(0, cells_y, 1), [&](const tbb::blocked_range<int>& r) {
    std::vector<double> F;
    for (int cy = r.begin(); cy < r.end(); ++cy) {
      gather_cell_row(s1, stops, cy, F);
      for (int cx = 0; cx < cells_x; ++cx) {
        const std::size_t c = static_cast<std::size_t>(cy) * cells_x + cx;
        DofpCellFit fit;
        if (!undetermined_cell_fit(s1, cx, cy, M, fit))
          fit = fit_projected_cell(ctx, cell_pixel_projections(s1.width, s1.height, ctx.o, cx, cy),
                                   &F[static_cast<std::size_t>(cx) * M * 4], psi0,
                                   c < starts.size() ? &starts[c] : nullptr, rows[static_cast<std::size_t>(cy)]);
        out.cells[c] = std::move(fit);
      }
      progress.advance(cells_x);
    }
  });
  progress.finish();
  return rows;
}

// The global projected fit at ψ_0 (rad): one set for every cell `ok` marks (F: gather_cell_row's
// rows), its share of ψ_0's equation reduced once over the set's unknowns.
DofpCellFit projected_global_fit(const DofpStep1& s1, const std::vector<std::vector<double>>& F,
                                 const std::vector<std::uint8_t>& ok, long long used, const ProjectedContext& ctx,
                                 double psi0, DofpPsi0Pass& pass) {
  const int cells_x = s1.width / 2, cells_y = s1.height / 2;
  const std::size_t M = ctx.turns.size();
  const auto cell_data = [&](int cx, int cy, ProjectedStops& ps) -> const double* {
    if (!ok[static_cast<std::size_t>(cy) * cells_x + cx]) return nullptr;
    project_stops(cell_pixel_projections(s1.width, s1.height, ctx.o, cx, cy), ctx.turns, ctx.rot, psi0, ps);
    return &F[static_cast<std::size_t>(cy)][static_cast<std::size_t>(cx) * M * 4];
  };
  // Sums of `each(cy, cx, Fc, ps, acc)` over the cells, by rows in parallel, added in row order.
  const auto over_cells = [&](auto each, auto& total) {
    using Acc = std::decay_t<decltype(total)>;
    std::vector<Acc> rows(static_cast<std::size_t>(cells_y));
    std::vector<std::uint8_t> fine(static_cast<std::size_t>(cells_y), 1);
    tbb::parallel_for(0, cells_y, [&](int cy) {
      ProjectedStops ps;
      for (int cx = 0; cx < cells_x; ++cx)
        if (const double* Fc = cell_data(cx, cy, ps); Fc && !each(Fc, ps, rows[static_cast<std::size_t>(cy)]))
          fine[static_cast<std::size_t>(cy)] = 0;
    });
    for (const Acc& a : rows) total.add(a);
    return std::all_of(fine.begin(), fine.end(), [](std::uint8_t f) { return f != 0; });
  };
  const auto eval = [&](const Vec8& x, bool jac, Sums& total) {
    return over_cells([&](const double* Fc, const ProjectedStops& ps, Sums& acc) {
      return jac ? accumulate_projected<true>(x, ctx.alpha, ctx.o, Fc, ps, M, acc)
                 : accumulate_projected<false>(x, ctx.alpha, ctx.o, Fc, ps, M, acc);
    }, total);
  };
  std::optional<Vec8> closed;
  if (ctx.cf.ok) {  // the pooled right-hand sides of every cell used, in row order
    Eigen::Matrix<double, 3, 4> g = Eigen::Matrix<double, 3, 4>::Zero();
    for (int cy = 0; cy < cells_y; ++cy)
      for (int cx = 0; cx < cells_x; ++cx)
        if (ok[static_cast<std::size_t>(cy) * cells_x + cx])
          ctx.cf.add(&F[static_cast<std::size_t>(cy)][static_cast<std::size_t>(cx) * M * 4], M, g);
    if (Vec8 x; ctx.cf.start(g, ctx.alpha, x)) {
      x[6] = wrap_half_pi(x[6] - psi0);
      closed = x;
    }
  }
  const auto nominal = [&] {
    struct Start {
      double re = 0, im = 0, dsum = 0;
      long long dn = 0;
      void add(const Start& o) { re += o.re, im += o.im, dsum += o.dsum, dn += o.dn; }
    } st;
    CellModel model;
    if (make_cell_model(ideal_x(), ctx.alpha, ctx.o.dop_weight, ctx.o.fit_weight, false, model))
      over_cells([&](const double* Fc, const ProjectedStops& ps, Start& a) {
        start_sums(model, Fc, ps.rot.data(), M, a.re, a.im, a.dsum, a.dn);
        return true;
      }, st);
    return nominal_start(0.5 * std::atan2(st.im, st.re), st.dn > 0 ? st.dsum / st.dn : 0.0);
  };
  DofpCellFit fit = levenberg_marquardt(eval, closed, nominal, used * static_cast<long long>(M), ctx.o,
                                        kProjectedUnknownNames, kProjectedResidualUlps);
  if (used == 0) fit.message = "step 1 left every cell undetermined";
  Vec8 x;
  x << deg2rad(fit.eps_deg[1]), deg2rad(fit.eps_deg[2]), deg2rad(fit.eps_deg[3]), fit.k[1], fit.k[2], fit.k[3],
      deg2rad(fit.psi0_deg), std::isnan(fit.dop) ? 0.0 : fit.dop;
  to_absolute_gauge(fit, rad2deg(psi0));
  Psi0Share share;
  if (fit.usable() && over_cells([&](const double* Fc, const ProjectedStops& ps, Psi0Share& acc) {
        return psi0_share(x, ctx.alpha, ctx.o, Fc, ps, M, acc);
      }, share))
    reduce_psi0_share(share, ctx.o.dop_weight != 0.0, pass);
  return fit;
}


// Step 2 with the view's projection: every cell (or the one global set) fitted at ψ_0, ψ_0 itself
// fitted for the whole image by dofp_fit_psi0 unless options.psi0_deg holds it.
DofpStep2 projected_step2(const DofpStep1& s1, std::span<const DofpPolarizedStop> stops, const DofpStep2Options& o,
                          const std::vector<double>& rot, const ClosedFormStart& cf, const Progress& progress,
                          DofpStep2& out) {
  const std::vector<double> turns = table_turns_rad(stops, o.table_sense);
  const ProjectedContext ctx{o, alpha_rad_of(o), turns, rot, cf};
  const int cells_x = out.cells_x, cells_y = out.cells_y;
  std::function<DofpPsi0Pass(double)> pass;
  std::vector<std::vector<double>> F;
  std::vector<std::uint8_t> ok;
  long long used = 0;
  std::vector<DofpCellFit> previous(o.start_cells.begin(), o.start_cells.end());
  if (o.scope == DofpStep2Scope::PerCell) {
    out.cells.resize(static_cast<std::size_t>(cells_x) * cells_y);
    pass = [&](double psi0_deg) {
      out.psi0_rows = projected_cells_pass(s1, stops, ctx, deg2rad(psi0_deg), previous, out, progress);
      previous = out.cells;  // the next pass starts where this one ended
      return dofp_sum(out.psi0_rows);
    };
  } else {
    F.resize(static_cast<std::size_t>(cells_y));
    ok.resize(static_cast<std::size_t>(cells_x) * cells_y);
    tbb::parallel_for(0, cells_y, [&](int cy) {
      gather_cell_row(s1, stops, cy, F[static_cast<std::size_t>(cy)]);
      for (int cx = 0; cx < cells_x; ++cx)
        ok[static_cast<std::size_t>(cy) * cells_x + cx] = undetermined_pixel(s1, cx, cy) < 0;
    });
    for (std::uint8_t v : ok) used += v;
    pass = [&](double psi0_deg) {
      out.psi0_rows.assign(1, DofpPsi0Pass{});
      out.cells.assign(1, projected_global_fit(s1, F, ok, used, ctx, deg2rad(psi0_deg), out.psi0_rows[0]));
      return out.psi0_rows[0];
    };
  }
  const auto run = [&](double psi0_deg) { return out.psi0_pass = pass(psi0_deg); };
  if (std::isfinite(o.psi0_deg)) {
    out.psi0_deg = o.psi0_deg;
    run(o.psi0_deg);
    out.psi0_fit.message = "psi0 held (one pass of the fit)";
  } else {
    out.psi0_fit = dofp_fit_psi0(run, dofp_psi0_start_deg(dofp_psi0_start_rows(s1, stops, o)), o, out.psi0_deg);
  }
  for (const DofpCellFit& c : out.cells) out.usable_cells += c.usable();
  return out;
}

}  // namespace

std::string dofp_scope_name(DofpStep2Scope s) {
  return s == DofpStep2Scope::PerCell ? "per-cell" : "global";
}

DofpStep2Scope parse_dofp_scope(const std::string& name) {
  if (name == "per-cell") return DofpStep2Scope::PerCell;
  if (name == "global") return DofpStep2Scope::Global;
  throw std::invalid_argument(
      fmt::format("DoFP step 2 scope '{}': expected per-cell or global", name));
}

// ---------------------------------------------------------------- step 1 (Eq. 19)
DofpStep1 calibrate_dofp_step1(int width, int height, std::span<const DofpUnpolarizedLevel> levels,
                               const DofpStep1Options& options) {
  check_size(width, height);
  if (levels.size() > 65535)
    throw std::invalid_argument("DoFP step 1: more than 65535 levels");
  if (std::isnan(options.saturation_DN))
    throw std::invalid_argument("DoFP step 1: the saturation level is NaN");
  for (std::size_t i = 0; i < levels.size(); ++i)
    if (!std::isfinite(levels[i].intensity) || levels[i].intensity < 0)
      throw std::invalid_argument(fmt::format(
          "DoFP step 1: level {} has intensity {}; it must be finite and >= 0", i,
          levels[i].intensity));
  const std::size_t N = static_cast<std::size_t>(width) * height;
  check_frames(levels, N, static_cast<std::size_t>(width), "unpolarized level");

  DofpStep1 s;
  s.width = width;
  s.height = height;
  s.K.assign(N, 0.0);
  s.b.assign(N, 0.0);
  s.residual_rms_DN.assign(N, 0.0);
  s.rank.assign(N, 0);
  s.levels_used.assign(N, 0);
  const double sat = options.saturation_DN;
  tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
    std::vector<double> sx(width), sy(width), xmin(width), xmax(width), sxx(width), sxy(width);
    std::vector<int> n(width);
    for (int row = rows.begin(); row < rows.end(); ++row) {
      const std::size_t base = static_cast<std::size_t>(row) * width;
      std::fill(sx.begin(), sx.end(), 0.0);
      std::fill(sy.begin(), sy.end(), 0.0);
      std::fill(sxx.begin(), sxx.end(), 0.0);
      std::fill(sxy.begin(), sxy.end(), 0.0);
      std::fill(n.begin(), n.end(), 0);
      std::fill(xmin.begin(), xmin.end(), std::numeric_limits<double>::infinity());
      std::fill(xmax.begin(), xmax.end(), -std::numeric_limits<double>::infinity());
      for (const DofpUnpolarizedLevel& L : levels) {
        const double x = 0.5 * L.intensity;  // I_j = I/2 behind the analyzer (spec §2.4)
        const double* f = L.frame.data() + base;
        for (int c = 0; c < width; ++c) {
          if (!(f[c] < sat)) continue;
          sx[c] += x;
          sy[c] += f[c];
          ++n[c];
          xmin[c] = std::min(xmin[c], x);
          xmax[c] = std::max(xmax[c], x);
        }
      }
      for (int c = 0; c < width; ++c)
        if (n[c] > 0) {
          sx[c] /= n[c];  // now the means x̄, ȳ
          sy[c] /= n[c];
        }
      // Centred sums: K = Σ(x − x̄)(f − f̄)/Σ(x − x̄)², b = f̄ − K·x̄.
      for (const DofpUnpolarizedLevel& L : levels) {
        const double x = 0.5 * L.intensity;
        const double* f = L.frame.data() + base;
        for (int c = 0; c < width; ++c) {
          if (!(f[c] < sat)) continue;
          const double dx = x - sx[c];
          sxx[c] += dx * dx;
          sxy[c] += dx * (f[c] - sy[c]);
        }
      }
      for (int c = 0; c < width; ++c) {
        const std::size_t p = base + c;
        s.levels_used[p] = static_cast<std::uint16_t>(n[c]);
        s.rank[p] = n[c] == 0 ? 0 : (xmax[c] > xmin[c] && sxx[c] > 0 ? 2 : 1);
        if (s.rank[p] < 2) continue;
        s.K[p] = sxy[c] / sxx[c];
        s.b[p] = sy[c] - s.K[p] * sx[c];
      }
      std::fill(sxx.begin(), sxx.end(), 0.0);  // now Σ residual²
      for (const DofpUnpolarizedLevel& L : levels) {
        const double x = 0.5 * L.intensity;
        const double* f = L.frame.data() + base;
        for (int c = 0; c < width; ++c) {
          if (!(f[c] < sat) || s.rank[base + c] < 2) continue;
          const double r = s.K[base + c] * x + s.b[base + c] - f[c];
          sxx[c] += r * r;
        }
      }
      for (int c = 0; c < width; ++c)
        if (s.rank[base + c] == 2) s.residual_rms_DN[base + c] = std::sqrt(sxx[c] / n[c]);
    }
  });
  for (std::uint8_t r : s.rank) s.rank_deficient_pixels += r < 2;
  return s;
}

// ---------------------------------------------------------------- step 2 (Eqs. 20–29)
DofpStep2 calibrate_dofp_step2(const DofpStep1& s1, std::span<const DofpPolarizedStop> stops,
                               const DofpStep2Options& o, const Progress& progress) {
  check_step2_options(o);
  check_size(s1.width, s1.height);
  const std::size_t N = static_cast<std::size_t>(s1.width) * s1.height;
  if (s1.K.size() != N || s1.b.size() != N || s1.rank.size() != N)
    throw std::invalid_argument("DoFP step 2: step 1's maps do not match its frame size");
  if (stops.empty()) throw std::invalid_argument("DoFP step 2: no polarized stop");
  for (std::size_t m = 0; m < stops.size(); ++m)
    if (!std::isfinite(stops[m].theta_R_deg) || !std::isfinite(stops[m].intensity))
      throw std::invalid_argument(
          fmt::format("DoFP step 2: stop {} has a non-finite table angle or intensity", m));
  check_frames(stops, N, static_cast<std::size_t>(s1.width), "polarized stop");

  const std::array<double, 4> alpha = alpha_rad_of(o);
  const std::vector<double> rot = table_rotations(stops, o.table_sense, o.weight_by_intensity);
  const StopArrays st(rot);
  const ClosedFormStart cf(stops, rot);
  const std::size_t M = stops.size();
  DofpStep2 out;
  out.scope = o.scope;
  out.cells_x = s1.width / 2;
  out.cells_y = s1.height / 2;
  const int cells_x = out.cells_x, cells_y = out.cells_y;
  if (o.view_projection) return projected_step2(s1, stops, o, rot, cf, progress, out);

  if (o.scope == DofpStep2Scope::PerCell) {
    out.cells.resize(static_cast<std::size_t>(cells_x) * cells_y);
    progress.begin("calibrate dofp: step 2 cells", static_cast<long long>(out.cells.size()));
    tbb::parallel_for(tbb::blocked_range<int>(0, cells_y, 1), [&](const tbb::blocked_range<int>& r) {
      std::vector<double> F;
      SoaScratch sc;
      for (int cy = r.begin(); cy < r.end(); ++cy) {
        gather_cell_row(s1, stops, cy, F);
        for (int cx = 0; cx < cells_x; ++cx) {
          DofpCellFit& fit = out.cells[static_cast<std::size_t>(cy) * cells_x + cx];
          if (undetermined_cell_fit(s1, cx, cy, M, fit)) continue;
          const double* Fc = &F[static_cast<std::size_t>(cx) * M * 4];
          CellModel model;
          const auto eval = [&](const Vec8& x, bool jac, Sums& sums) {
            if (!make_cell_model(x, alpha, o.dop_weight, o.fit_weight, jac, model)) return false;
            if (jac)
              accumulate_soa<true>(model, Fc, st, rot.data(), sc, sums);
            else
              accumulate_soa<false>(model, Fc, st, rot.data(), sc, sums);
            return true;
          };
          std::optional<Vec8> closed;
          if (cf.ok) {
            Eigen::Matrix<double, 3, 4> g = Eigen::Matrix<double, 3, 4>::Zero();
            cf.add(Fc, M, g);
            if (Vec8 x; cf.start(g, alpha, x)) closed = x;
          }
          const auto nominal = [&] {
            double re = 0, im = 0, dsum = 0;
            long long dn = 0;
            if (make_cell_model(ideal_x(), alpha, o.dop_weight, o.fit_weight, false, model))
              start_sums(model, Fc, rot.data(), M, re, im, dsum, dn);
            return nominal_start(0.5 * std::atan2(im, re), dn > 0 ? dsum / dn : 0.0);
          };
          fit = levenberg_marquardt(eval, closed, nominal, static_cast<long long>(M), o);
        }
        progress.advance(cells_x);
      }
    });
    progress.finish();
  } else {
    // One set for the whole array: the sums over cell rows, added in row order (deterministic).
    std::vector<std::vector<double>> F(cells_y);
    std::vector<std::uint8_t> ok(static_cast<std::size_t>(cells_x) * cells_y);
    long long used = 0;
    tbb::parallel_for(0, cells_y, [&](int cy) {
      gather_cell_row(s1, stops, cy, F[cy]);
      for (int cx = 0; cx < cells_x; ++cx)
        ok[static_cast<std::size_t>(cy) * cells_x + cx] = undetermined_pixel(s1, cx, cy) < 0;
    });
    for (std::uint8_t v : ok) used += v;
    const auto eval = [&](const Vec8& x, bool jac, Sums& total) {
      CellModel model;
      if (!make_cell_model(x, alpha, o.dop_weight, o.fit_weight, jac, model)) return false;
      std::vector<Sums> rows(cells_y);
      tbb::parallel_for(0, cells_y, [&](int cy) {
        SoaScratch sc;
        for (int cx = 0; cx < cells_x; ++cx) {
          if (!ok[static_cast<std::size_t>(cy) * cells_x + cx]) continue;
          const double* Fc = &F[cy][static_cast<std::size_t>(cx) * M * 4];
          if (jac)
            accumulate_soa<true>(model, Fc, st, rot.data(), sc, rows[cy]);
          else
            accumulate_soa<false>(model, Fc, st, rot.data(), sc, rows[cy]);
        }
      });
      for (const Sums& s : rows) total.add(s);
      return true;
    };
    std::optional<Vec8> closed;
    if (cf.ok) {  // the pooled right-hand sides of every cell used, in row order
      Eigen::Matrix<double, 3, 4> g = Eigen::Matrix<double, 3, 4>::Zero();
      for (int cy = 0; cy < cells_y; ++cy)
        for (int cx = 0; cx < cells_x; ++cx)
          if (ok[static_cast<std::size_t>(cy) * cells_x + cx])
            cf.add(&F[cy][static_cast<std::size_t>(cx) * M * 4], M, g);
      if (Vec8 x; cf.start(g, alpha, x)) closed = x;
    }
    const auto nominal = [&] {
      double re = 0, im = 0, dsum = 0;
      long long dn = 0;
      CellModel model;
      if (make_cell_model(ideal_x(), alpha, o.dop_weight, o.fit_weight, false, model))
        for (int cy = 0; cy < cells_y; ++cy)
          for (int cx = 0; cx < cells_x; ++cx)
            if (ok[static_cast<std::size_t>(cy) * cells_x + cx])
              start_sums(model, &F[cy][static_cast<std::size_t>(cx) * M * 4], rot.data(), M, re,
                         im, dsum, dn);
      return nominal_start(0.5 * std::atan2(im, re), dn > 0 ? dsum / dn : 0.0);
    };
    out.cells.push_back(
        levenberg_marquardt(eval, closed, nominal, used * static_cast<long long>(M), o));
    if (used == 0) out.cells.back().message = "step 1 left every cell undetermined";
  }
  for (const DofpCellFit& c : out.cells) out.usable_cells += c.usable();
  return out;
}

// ---------------------------------------------------------------- Table 1
DofpTable1 dofp_table1(const DofpStep1& s1, const DofpStep2& s2,
                       std::span<const DofpPolarizedStop> stops, const DofpStep2Options& o,
                       double intensity) {
  check_step2_options(o);
  const int cells_x = s2.cells_x, cells_y = s2.cells_y;
  const std::size_t ncells = static_cast<std::size_t>(cells_x) * cells_y;
  if (s2.cells.size() != (s2.scope == DofpStep2Scope::Global ? 1 : ncells) ||
      cells_x * 2 != s1.width || cells_y * 2 != s1.height)
    throw std::invalid_argument("DoFP Table 1: step 1 and step 2 do not match");
  if (!(intensity > 0))
    for (const DofpPolarizedStop& s : stops) intensity = std::max(intensity, s.intensity);
  std::vector<std::size_t> used;
  for (std::size_t m = 0; m < stops.size(); ++m)
    if (stops[m].intensity == intensity) used.push_back(m);
  if (used.size() < 2)
    throw CalibrationError(fmt::format(
        "DoFP Table 1: {} stop(s) at intensity {}; the orientation error needs at least two",
        used.size(), intensity));

  const std::array<double, 4> alpha = alpha_rad_of(o);
  CellModel ideal;
  if (!make_cell_model(ideal_x(), alpha, 0.0, 0.0, false, ideal))
    throw std::invalid_argument("DoFP Table 1: the mosaic's four axes do not span the Stokes plane");
  // The cells used, and each one's fitted projection (rows q̃1, q̃2 of R⁻¹Ãᵀ).
  std::vector<std::size_t> cells;
  std::vector<Eigen::Matrix<double, 2, 4>> fitted;
  for (int cy = 0; cy < cells_y; ++cy)
    for (int cx = 0; cx < cells_x; ++cx) {
      const std::size_t c = static_cast<std::size_t>(cy) * cells_x + cx;
      const DofpCellFit& fit = s2.cells[s2.scope == DofpStep2Scope::Global ? 0 : c];
      if (!fit.usable() || undetermined_pixel(s1, cx, cy) >= 0) continue;
      Vec8 x;
      x << deg2rad(fit.eps_deg[1]), deg2rad(fit.eps_deg[2]), deg2rad(fit.eps_deg[3]), fit.k[1],
          fit.k[2], fit.k[3], 0, 0;
      CellModel m;
      if (!make_cell_model(x, alpha, 0.0, 0.0, false, m)) continue;
      cells.push_back(c);
      fitted.push_back(m.P.topRows<2>());
    }
  if (cells.empty())
    throw CalibrationError("DoFP Table 1: no cell has a usable step 1 and step 2");
  // With the view's projection, each cell's AoP goes back to the port plane before the mean
  // (port_angle): the cell's relative (k, ε), its ε_1 and its pixels' views.
  std::vector<ProjectedCell> back;
  if (o.view_projection)
    for (std::size_t i = 0; i < cells.size(); ++i) {
      const int cx = static_cast<int>(cells[i] % cells_x), cy = static_cast<int>(cells[i] / cells_x);
      const DofpCellFit& fit = s2.cells[s2.scope == DofpStep2Scope::Global ? 0 : cells[i]];
      ProjectedCell pc{Vec8::Zero(), deg2rad(fit.eps_deg[0]), cell_pixel_projections(s1.width, s1.height, o, cx, cy)};
      for (int j = 1; j < 4; ++j) {
        pc.x[j - 1] = deg2rad(fit.eps_deg[j] - fit.eps_deg[0]);
        pc.x[j + 2] = fit.k[j];
      }
      back.push_back(pc);
    }

  // Circular mean per stop and row: ½·arg Σ_cells (q̃1 + i q̃2)/|q̃|.
  std::vector<std::array<double, 3>> orient(used.size());
  tbb::parallel_for(std::size_t{0}, used.size(), [&](std::size_t u) {
    const double* f = stops[used[u]].frame.data();
    std::array<double, 3> re{}, im{};
    for (std::size_t i = 0; i < cells.size(); ++i) {
      const std::size_t c = cells[i];
      const int cx = static_cast<int>(c % cells_x), cy = static_cast<int>(c / cells_x);
      const std::size_t r0 = static_cast<std::size_t>(2 * cy) * s1.width + 2 * cx;
      const std::size_t p[4] = {r0, r0 + 1, r0 + s1.width, r0 + s1.width + 1};
      Eigen::Vector4d raw, F;
      for (int j = 0; j < 4; ++j) {
        raw[j] = f[p[j]];
        F[j] = (f[p[j]] - s1.b[p[j]]) / s1.K[p[j]];
      }
      if (!back.empty()) {
        const ProjectedCell ideal_cell{ideal_x(), 0.0, back[i].views};
        const Eigen::Vector4d* values[3] = {&raw, &F, &F};
        const ProjectedCell* models[3] = {&ideal_cell, &ideal_cell, &back[i]};
        for (int k = 0; k < 3; ++k)
          if (double beta; port_angle(*models[k], alpha, values[k]->data(), beta)) {
            re[k] += std::cos(2.0 * beta);
            im[k] += std::sin(2.0 * beta);
          }
        continue;
      }
      const Eigen::Vector2d q[3] = {ideal.P.topRows<2>() * raw, ideal.P.topRows<2>() * F,
                                    fitted[i] * F};
      for (int k = 0; k < 3; ++k) {
        const double a = q[k].norm();
        if (!(a > 0)) continue;
        re[k] += q[k][0] / a;
        im[k] += q[k][1] / a;
      }
    }
    for (int k = 0; k < 3; ++k) orient[u][k] = rad2deg(0.5 * std::atan2(im[k], re[k]));
  });

  DofpTable1 t;
  t.intensity = intensity;
  t.cells_used = static_cast<long long>(cells.size());
  const char* names[3] = {"raw", "step1", "step2"};
  for (std::size_t u = 1; u < used.size(); ++u)
    t.theta_R_deg.push_back(stops[used[u]].theta_R_deg);
  for (int k = 0; k < 3; ++k) {
    DofpOrientationRow& row = t.rows[k];
    row.name = names[k];
    const double theta0 = stops[used[0]].theta_R_deg;
    for (std::size_t u = 1; u < used.size(); ++u)
      row.error_deg.push_back(wrap90_deg(orient[u][k] - orient[0][k] -
                                         o.table_sense * (stops[used[u]].theta_R_deg - theta0)));
    double sum = 0;
    for (double e : row.error_deg) {
      row.max_deg = std::max(row.max_deg, std::abs(e));
      sum += e;
    }
    const double n = static_cast<double>(row.error_deg.size());
    row.mean_deg = sum / n;
    double ss = 0;
    for (double e : row.error_deg) ss += (e - row.mean_deg) * (e - row.mean_deg);
    row.std_deg = n > 1 ? std::sqrt(ss / (n - 1)) : 0.0;
  }
  return t;
}

DofpCalibration calibrate_dofp(int width, int height, std::span<const DofpUnpolarizedLevel> levels,
                               std::span<const DofpPolarizedStop> stops,
                               const DofpCalibrationOptions& options, const Progress& progress) {
  DofpCalibration c;
  c.options = options;
  c.step1 = calibrate_dofp_step1(width, height, levels, options.step1);
  c.step2 = calibrate_dofp_step2(c.step1, stops, options.step2, progress);
  c.table1 = dofp_table1(c.step1, c.step2, stops, options.step2, options.table1_intensity);
  return c;
}

DofpTruth dofp_parameter_maps(const DofpCalibration& c, std::vector<std::uint8_t>* usable) {
  const DofpStep1& s1 = c.step1;
  const std::size_t N = static_cast<std::size_t>(s1.width) * s1.height;
  DofpTruth t;
  t.width = s1.width;
  t.height = s1.height;
  t.K = s1.K;
  t.b = s1.b;
  t.k.resize(N);
  t.eps_deg.resize(N);
  t.alpha_deg.resize(N);
  if (usable) usable->assign(N, 0);
  const int cells_x = s1.width / 2;
  for (int row = 0; row < s1.height; ++row)
    for (int col = 0; col < s1.width; ++col) {
      const std::size_t p = static_cast<std::size_t>(row) * s1.width + col;
      const int j = (row % 2) * 2 + col % 2;
      const std::size_t cell = static_cast<std::size_t>(row / 2) * cells_x + col / 2;
      const DofpCellFit& fit =
          c.step2.cells[c.step2.scope == DofpStep2Scope::Global ? 0 : cell];
      // A fit that did not converge says where it stopped (cells.csv); the maps keep the ideal
      // k = 1, ε = 0 there, flagged unusable.
      t.k[p] = fit.usable() ? fit.k[j] : 1.0;
      t.eps_deg[p] = fit.usable() ? fit.eps_deg[j] : 0.0;
      t.alpha_deg[p] = c.options.step2.mosaic_deg[j];
      if (usable) (*usable)[p] = fit.usable() && undetermined_pixel(s1, col / 2, row / 2) < 0;
    }
  return t;
}

// ---------------------------------------------------------------- exposed for tests
namespace {
std::vector<double> rotations_of(const std::vector<double>& theta, double sense) {
  std::vector<DofpPolarizedStop> stops(theta.size());
  for (std::size_t m = 0; m < theta.size(); ++m) stops[m].theta_R_deg = theta[m];
  return table_rotations(stops, sense, false);
}

// With the view's projection: a cell's stops at options.psi0_deg, as step 2 takes them.
ProjectedStops projected_stops_of(const std::vector<double>& theta, const DofpStep2Options& o,
                                  const std::array<Vec3, 4>& views) {
  PixelProjections M;
  for (int j = 0; j < 4; ++j) M[j] = view_projection_of(views[j]);
  std::vector<double> turns(theta.size());
  for (std::size_t m = 0; m < theta.size(); ++m) turns[m] = o.table_sense * deg2rad(theta[m]);
  ProjectedStops ps;
  project_stops(M, turns, rotations_of(theta, o.table_sense), deg2rad(o.psi0_deg), ps);
  return ps;
}

}  // namespace

double dofp_projected_aop_deg(const Vec3& view, double psi_deg) {
  const ViewProjection M = view_projection_of(view);
  const double b = deg2rad(psi_deg), cb = std::cos(b), sb = std::sin(b);
  return rad2deg(std::atan2(M.m12 * cb + M.m22 * sb, M.m11 * cb + M.m12 * sb));
}

Vec3 dofp_pixel_view(int width, int height, const DofpStep2Options& o, int col, int row) {
  if (!(std::isfinite(o.focal_px) && o.focal_px > 0))
    throw std::invalid_argument(fmt::format("DoFP: a pixel's view needs a focal length > 0 px, got {}", o.focal_px));
  const double xc = std::isnan(o.principal_x_px) ? 0.5 * width : o.principal_x_px;
  const double yc = std::isnan(o.principal_y_px) ? 0.5 * height : o.principal_y_px;
  return vec3::unit({col + 0.5 - xc, row + 0.5 - yc, o.focal_px});
}

DofpPsi0Pass dofp_sum(std::span<const DofpPsi0Pass> rows) {
  DofpPsi0Pass total;
  for (const DofpPsi0Pass& r : rows) total.add(r);
  return total;
}

double dofp_psi0_start_deg(std::span<const std::array<double, 2>> rows) {
  double re = 0, im = 0;
  for (const std::array<double, 2>& r : rows) re += r[0], im += r[1];
  return rad2deg(0.5 * std::atan2(im, re));
}

std::vector<std::array<double, 2>> dofp_psi0_start_rows(const DofpStep1& s1, std::span<const DofpPolarizedStop> stops,
                                                        const DofpStep2Options& o) {
  const std::vector<double> rot = table_rotations(stops, o.table_sense, o.weight_by_intensity);
  const ClosedFormStart cf(stops, rot);
  const std::array<double, 4> alpha = alpha_rad_of(o);
  const int cells_x = s1.width / 2, cells_y = s1.height / 2;
  const std::size_t M = stops.size();
  std::vector<std::array<double, 2>> rows(static_cast<std::size_t>(cells_y), {0.0, 0.0});
  if (!cf.ok) return rows;
  tbb::parallel_for(0, cells_y, [&](int cy) {
    std::vector<double> F;
    gather_cell_row(s1, stops, cy, F);
    for (int cx = 0; cx < cells_x; ++cx) {
      if (undetermined_pixel(s1, cx, cy) >= 0) continue;
      Eigen::Matrix<double, 3, 4> g = Eigen::Matrix<double, 3, 4>::Zero();
      cf.add(&F[static_cast<std::size_t>(cx) * M * 4], M, g);
      if (Vec8 x; cf.start(g, alpha, x)) {
        rows[static_cast<std::size_t>(cy)][0] += std::cos(2.0 * x[6]);
        rows[static_cast<std::size_t>(cy)][1] += std::sin(2.0 * x[6]);
      }
    }
  });
  return rows;
}

FitSummary dofp_fit_psi0(const std::function<DofpPsi0Pass(double)>& pass, double start_deg,
                         const DofpStep2Options& o, double& psi0_deg) {
  constexpr int kHalvings = 5;  // [C] each try is a pass over every cell
  FitSummary s;
  s.cost_unit = "rad^2";
  s.solver_status = "gauss_newton";
  double psi = deg2rad(start_deg);
  DofpPsi0Pass P = pass(start_deg);
  s.evaluations = 1;
  s.initial_cost = 0.5 * P.cost;
  const auto end = [&](FitTermination t, std::string message) {
    s.termination = t;
    s.message = std::move(message);
  };
  for (int it = 1;; ++it) {
    s.observations = static_cast<int>(P.fits);
    if (P.fits == 0) {
      end(FitTermination::TooFewObservations, fmt::format("no usable fit at psi0 = {:.6g} deg", rad2deg(psi)));
      break;
    }
    if (!(P.curvature > o.min_singular_ratio * o.min_singular_ratio * P.raw_curvature)) {
      end(FitTermination::RankDeficient,
          fmt::format("the views cannot tell psi0 from the analyzers' common rotation eps1 (reduced curvature "
                      "{:.3g} of {:.3g}): the field is too narrow", P.curvature, P.raw_curvature));
      break;
    }
    double step = -P.gradient / P.curvature;
    if (std::abs(step) < o.step_tolerance) {
      end(FitTermination::Converged, "");
      break;
    }
    if (it > o.max_iterations) {
      end(FitTermination::NoConvergence,
          fmt::format("|dpsi0| still >= {:g} after {} iterations", o.step_tolerance, o.max_iterations));
      break;
    }
    bool accepted = false;
    for (int h = 0; h <= kHalvings && !accepted; ++h, step *= 0.5) {
      DofpPsi0Pass T = pass(rad2deg(psi + step));
      ++s.evaluations;
      // Not above the cost but for rounding (1e-12 of it): a last small step must not stall.
      if (T.fits > 0 && T.cost <= P.cost * (1.0 + 1e-12)) {
        psi += step;
        P = T;
        accepted = true;
      }
    }
    s.iterations = it;
    if (!accepted) {
      P = pass(rad2deg(psi));  // the cells at the ψ_0 reported
      ++s.evaluations;
      end(FitTermination::NoConvergence, fmt::format("no step of psi0 lowered the cost after {} tries", kHalvings + 1));
      break;
    }
  }
  s.final_cost = 0.5 * P.cost;
  psi0_deg = wrap90_deg(rad2deg(psi));
  return s;
}

Eigen::VectorXd dofp_cell_residuals(const std::vector<double>& F, const std::vector<double>& theta,
                                    const Eigen::Matrix<double, 8, 1>& x, const DofpStep2Options& o,
                                    const std::array<Vec3, 4>& views) {
  if (F.size() != 4 * theta.size())
    throw std::invalid_argument("dofp_cell_residuals: F needs 4 values per table angle");
  Eigen::VectorXd r = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(3 * theta.size()));
  Sums sums;
  if (o.view_projection) {
    if (!accumulate_projected<false>(x, alpha_rad_of(o), o, F.data(), projected_stops_of(theta, o, views),
                                     theta.size(), sums, r.data()))
      throw std::invalid_argument("dofp_cell_residuals: the model is singular at x");
    return r;
  }
  const std::vector<double> rot = rotations_of(theta, o.table_sense);
  CellModel model;
  if (!make_cell_model(x, alpha_rad_of(o), o.dop_weight, o.fit_weight, false, model))
    throw std::invalid_argument("dofp_cell_residuals: the model is singular at x");
  accumulate<false>(model, F.data(), rot.data(), theta.size(), sums, r.data());
  return r;
}

Eigen::MatrixXd dofp_cell_jacobian(const std::vector<double>& F, const std::vector<double>& theta,
                                   const Eigen::Matrix<double, 8, 1>& x, const DofpStep2Options& o,
                                   const std::array<Vec3, 4>& views) {
  if (F.size() != 4 * theta.size())
    throw std::invalid_argument("dofp_cell_jacobian: F needs 4 values per table angle");
  std::vector<double> rows(24 * theta.size(), 0.0);
  Sums sums;
  ProjectedStops ps;
  if (o.view_projection) {
    ps = projected_stops_of(theta, o, views);
    if (!accumulate_projected<true>(x, alpha_rad_of(o), o, F.data(), ps, theta.size(), sums, nullptr, rows.data()))
      throw std::invalid_argument("dofp_cell_jacobian: the model is singular at x");
  } else {
    const std::vector<double> rot = rotations_of(theta, o.table_sense);
    CellModel model;
    if (!make_cell_model(x, alpha_rad_of(o), o.dop_weight, o.fit_weight, true, model))
      throw std::invalid_argument("dofp_cell_jacobian: the model is singular at x");
    accumulate<true>(model, F.data(), rot.data(), theta.size(), sums, nullptr, rows.data());
  }
  Eigen::MatrixXd J(static_cast<Eigen::Index>(3 * theta.size()), o.view_projection ? 9 : 8);
  for (std::size_t i = 0; i < 3 * theta.size(); ++i) {
    for (int p = 0; p < 8; ++p) J(static_cast<Eigen::Index>(i), p) = rows[8 * i + p];
    if (o.view_projection) J(static_cast<Eigen::Index>(i), 8) = psi0_column(&rows[8 * i], &ps.dphi[4 * (i / 3)]);
  }
  return J;
}

bool dofp_cell_sums(const std::vector<double>& F, const std::vector<double>& theta,
                    const Eigen::Matrix<double, 8, 1>& x, const DofpStep2Options& o,
                    DofpSumsPath path, DofpCellSums& out) {
  if (F.size() != 4 * theta.size())
    throw std::invalid_argument("dofp_cell_sums: F needs 4 values per table angle");
  if (path == DofpSumsPath::LanesAvx2 && !cpu_has_avx2()) return false;
  const std::vector<double> rot = rotations_of(theta, o.table_sense);
  CellModel model;
  if (!make_cell_model(x, alpha_rad_of(o), o.dop_weight, o.fit_weight, true, model))
    throw std::invalid_argument("dofp_cell_sums: the model is singular at x");
  const StopArrays st(rot);
  SoaScratch sc;
  Sums sums;
  accumulate_soa<true>(model, F.data(), st, rot.data(), sc, sums,
                       path == DofpSumsPath::Scalar      ? LanePath::Scalar
                       : path == DofpSumsPath::LanesSse2 ? LanePath::Sse2
                                                         : LanePath::Avx2);
  out.JtJ = sums.JtJ;
  out.Jtr = sums.Jtr;
  out.cost = sums.cost;
  out.aop_ss = sums.aop_ss;
  out.bad = sums.bad;
  return true;
}

}  // namespace polrig
