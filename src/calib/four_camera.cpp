#include "polrig/calib/four_camera.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <Eigen/Dense>
#include <Eigen/SVD>
#include <fmt/format.h>
#include <unsupported/Eigen/LevenbergMarquardt>

#include "polrig/units.h"

namespace polrig {

namespace {

// How well the polarized stops' table angles separate the analyzers' axes from the DoP: σ_min/σ_max of
// the design [1, cos 2θ_R, sin 2θ_R]. Each camera sees 1 + d·cos 2(β − a_j) with β = ψ_0 + s_R·θ_R; with
// only two polarizer orientations (stops 90° apart: 2θ_R on one line) it gives one number per camera,
// d·cos 2(ψ_0 − a_j), for the fit's unknowns ε_2..ε_4, ψ_0 and d_0: five unknowns from four numbers.
// Three orientations or more (not all near one line through 2θ) give the three per camera the fit needs.
double table_design_ratio(const std::vector<double>& theta_R_deg) {
  Eigen::MatrixXd A(static_cast<Eigen::Index>(theta_R_deg.size()), 3);
  for (Eigen::Index m = 0; m < A.rows(); ++m) {
    const double t = 2 * deg2rad(theta_R_deg[static_cast<std::size_t>(m)]);
    A.row(m) << 1.0, std::cos(t), std::sin(t);
  }
  const Eigen::VectorXd s = Eigen::JacobiSVD<Eigen::MatrixXd>(A).singularValues();
  return s(2) / s(0);
}
// [C] Below this the stops' orientations are too close to two (a full turn in equal steps: 1/√2; stops
// at 0°, 90° and 5°: 0.06).
constexpr double kMinTableDesignRatio = 0.05;

// An axial difference in radians, wrapped into [−π/2, π/2).
double wrap90_rad(double d) {
  d = std::fmod(d, kPi);
  if (d < -0.5 * kPi) d += kPi;
  if (d >= 0.5 * kPi) d -= kPi;
  return d;
}

template <class T>
void check_frames(const FourCameraFrames<T>& s, std::size_t n, const char* what) {
  for (std::size_t j = 0; j < 4; ++j)
    if (s.f[j].size() != n)
      throw std::invalid_argument(fmt::format("{} stop {}: camera {}'s frame has {} pixels (expected {})", what, s.stop,
                                              j + 1, s.f[j].size(), n));
  if (!std::isfinite(s.theta_R_deg))
    throw std::invalid_argument(fmt::format("{} stop {}: table angle {} is not finite", what, s.stop, s.theta_R_deg));
}

// Eqs. 3–5 at one pixel for axes a (rad), with ∂φ/∂a_j and ∂d/∂a_j (docs/physics.md §16.1).
struct PixelFusion {
  double phi = 0, dop = 0;  // φ̂ (rad, (−π/2, π/2]), d̂
  std::array<double, 4> dphi{}, ddop{};
};
PixelFusion fuse_with_derivatives(const std::array<double, 4>& a, const std::array<double, 4>& F) {
  Eigen::Matrix<double, 4, 3> D;
  for (int j = 0; j < 4; ++j) D.row(j) << std::cos(2 * a[j]), std::sin(2 * a[j]), 1.0;
  const Eigen::Vector4d f(F[0], F[1], F[2], F[3]);
  const Eigen::Matrix3d Ginv = (D.transpose() * D).inverse();
  const Eigen::Vector3d x = Ginv * (D.transpose() * f);
  const Eigen::Vector4d r = f - D * x;
  PixelFusion p;
  const double p2 = x(0) * x(0) + x(1) * x(1), pn = std::sqrt(p2);
  p.phi = 0.5 * std::atan2(x(1), x(0));
  p.dop = pn / x(2);
  for (int j = 0; j < 4; ++j) {
    const Eigen::Vector3d g(-2 * std::sin(2 * a[j]), 2 * std::cos(2 * a[j]), 0.0);
    const Eigen::Vector3d dx = Ginv * (g * r(j) - D.row(j).transpose() * g.dot(x));
    p.dphi[j] = 0.5 * (x(0) * dx(1) - x(1) * dx(0)) / p2;
    p.ddop[j] = (x(0) * dx(0) + x(1) * dx(1)) / (pn * x(2)) - p.dop * dx(2) / x(2);
  }
  return p;
}

// The port polarizer's AoP along view v at β (rad) and dφ/dβ: arg(M·(cos β, sin β)),
// M = I₂ − (v_x, v_y)(v_x, v_y)ᵀ/(1 + v_z) (dofp_projected_aop_deg's).
void projected(const Vec3& v, double beta, bool on, double& phi, double& dphi) {
  if (!on) {
    phi = beta, dphi = 1;
    return;
  }
  const double g = 1.0 / (1.0 + v[2]);
  const double m11 = 1 - g * v[0] * v[0], m12 = -g * v[0] * v[1], m22 = 1 - g * v[1] * v[1];
  const double c = std::cos(beta), s = std::sin(beta);
  const double qx = m11 * c + m12 * s, qy = m12 * c + m22 * s;
  const double dqx = -m11 * s + m12 * c, dqy = -m12 * s + m22 * c;
  phi = std::atan2(qy, qx);
  dphi = (qx * dqy - qy * dqx) / (qx * qx + qy * qy);
}

std::array<double, 4> axes_rad(const PolarizerSamples& s, std::size_t i, const Eigen::Matrix<double, 5, 1>& x) {
  std::array<double, 4> a{};
  for (std::size_t j = 0; j < 4; ++j)
    a[j] = deg2rad(s.nominal_deg[j] + s.delta_deg[i][j]) + (j == 0 ? 0.0 : x(static_cast<Eigen::Index>(j - 1)));
  return a;
}

// Residuals and (when J is not null) the Jacobian at x.
void polarizer_model(const PolarizerSamples& s, const Eigen::Matrix<double, 5, 1>& x, const PolarizerOptions& o,
                     Eigen::VectorXd& r, Eigen::MatrixXd* J) {
  const std::size_t P = s.pixels(), M = s.theta_R_deg.size();
  r.resize(static_cast<Eigen::Index>(2 * P * M));
  if (J) J->setZero(static_cast<Eigen::Index>(2 * P * M), 5);
  const double w = o.dop_weight;
  for (std::size_t i = 0; i < P; ++i) {
    const std::array<double, 4> a = axes_rad(s, i, x);
    for (std::size_t m = 0; m < M; ++m) {
      const PixelFusion p = fuse_with_derivatives(a, s.F[m * P + i]);
      double phi_m = 0, dphi_m = 0;
      projected(s.views[i], x(3) + o.table_sense * deg2rad(s.theta_R_deg[m]), o.view_projection, phi_m, dphi_m);
      const Eigen::Index row = static_cast<Eigen::Index>(2 * (m * P + i));
      r(row) = wrap90_rad(p.phi - phi_m);
      r(row + 1) = w > 0 ? w * (p.dop - x(4)) : 0.0;
      if (J) {
        for (int j = 1; j < 4; ++j) {
          (*J)(row, j - 1) = p.dphi[static_cast<std::size_t>(j)];
          (*J)(row + 1, j - 1) = w * p.ddop[static_cast<std::size_t>(j)];
        }
        (*J)(row, 3) = -dphi_m;
        (*J)(row + 1, 4) = -w;
      }
    }
  }
}

// Eigen's LM over the first `n` unknowns of x (4 without the DoP residual: d_0 stays).
struct PolarizerFunctor : Eigen::DenseFunctor<double> {
  PolarizerFunctor(const PolarizerSamples& s, const PolarizerOptions& o, const Eigen::Matrix<double, 5, 1>& x0, int n)
      : Eigen::DenseFunctor<double>(n, static_cast<int>(2 * s.pixels() * s.theta_R_deg.size())),
        samples(s), options(o), base(x0) {}
  Eigen::Matrix<double, 5, 1> full(const InputType& x) const {
    Eigen::Matrix<double, 5, 1> v = base;
    v.head(x.size()) = x;
    return v;
  }
  int operator()(const InputType& x, ValueType& r) const {
    polarizer_model(samples, full(x), options, r, nullptr);
    return 0;
  }
  int df(const InputType& x, JacobianType& J) const {
    Eigen::VectorXd r;
    Eigen::MatrixXd Jf;
    polarizer_model(samples, full(x), options, r, &Jf);
    J = Jf.leftCols(x.size());
    return 0;
  }
  const PolarizerSamples& samples;
  const PolarizerOptions& options;
  Eigen::Matrix<double, 5, 1> base;
};

}  // namespace

PixelWindow centred_window(int width, int height, double cx, double cy, int half, int stride) {
  if (half < 0 || stride < 1)
    throw std::invalid_argument(fmt::format("a window's half size ({}) must be ≥ 0 and its stride ({}) ≥ 1", half, stride));
  if (!(std::isfinite(cx) && std::isfinite(cy) && cx >= 0 && cy >= 0 && cx < width && cy < height))
    throw std::invalid_argument(
        fmt::format("the window's centre ({}, {}) px lies outside the {} × {} px image", cx, cy, width, height));
  const int c = static_cast<int>(std::floor(cx)), rr = static_cast<int>(std::floor(cy));
  PixelWindow w;
  w.stride = stride;
  w.col0 = std::max(0, c - half), w.col1 = std::min(width, c + half + 1);
  w.row0 = std::max(0, rr - half), w.row1 = std::min(height, rr + half + 1);
  return w;
}

bool FourCameraRadiometry::usable() const {
  return std::all_of(camera.begin(), camera.end(), [](const CameraRadiometry& c) { return c.usable(); });
}

template <class T>
RadiometricLevel radiometric_level(std::span<const T> frame, int width, const PixelWindow& w,
                                   const FourCameraFrames<T>& stop, const RadiometricOptions& o) {
  RadiometricLevel l;
  l.stop = stop.stop;
  l.level = stop.level;
  l.intensity = stop.level * o.intensity_per_level;
  double sum = 0;
  for (int row = w.row0; row < w.row1; row += w.stride)
    for (int col = w.col0; col < w.col1; col += w.stride) {
      const double v = static_cast<double>(frame[static_cast<std::size_t>(row) * static_cast<std::size_t>(width) +
                                                 static_cast<std::size_t>(col)]);
      if (!std::isfinite(v))
        throw std::invalid_argument(fmt::format("level stop {}: pixel ({}, {}) is not finite", stop.stop, col, row));
      if (v <= 0 || v >= o.saturation_DN) ++l.clipped;
      sum += v;
      ++l.pixels;
    }
  l.mean_DN = sum / static_cast<double>(l.pixels);
  double ss = 0;
  for (int row = w.row0; row < w.row1; row += w.stride)
    for (int col = w.col0; col < w.col1; col += w.stride) {
      const double v = static_cast<double>(frame[static_cast<std::size_t>(row) * static_cast<std::size_t>(width) +
                                                 static_cast<std::size_t>(col)]) - l.mean_DN;
      ss += v * v;
    }
  l.sd_DN = l.pixels > 1 ? std::sqrt(ss / static_cast<double>(l.pixels - 1)) : 0.0;
  l.used = l.clipped == 0;
  return l;
}

CameraRadiometry fit_radiometry(std::vector<RadiometricLevel> levels, const PixelWindow& window) {
  CameraRadiometry c;
  c.window = window;
  c.levels = std::move(levels);
  std::vector<const RadiometricLevel*> used;
  for (const RadiometricLevel& l : c.levels)
    if (l.used) used.push_back(&l);
  c.levels_used = static_cast<int>(used.size());
  const double n = static_cast<double>(used.size());
  double xm = 0, ym = 0;
  for (const RadiometricLevel* l : used) xm += l->intensity, ym += l->mean_DN;
  if (used.empty()) {
    c.message = c.levels.empty() ? "no unpolarized level" : "every level clips (a pixel at 0 or at the ADC's top)";
    return c;
  }
  xm /= n, ym /= n;
  double sxx = 0;
  for (const RadiometricLevel* l : used) sxx += (l->intensity - xm) * (l->intensity - xm);
  c.rank = sxx > 0 ? 2 : 1;
  if (c.rank < 2) {
    c.message = fmt::format("{} usable level(s), all at intensity {}: K and b need two distinct levels", used.size(), xm);
    return c;
  }
  double sxy = 0;
  for (const RadiometricLevel* l : used) sxy += (l->intensity - xm) * (l->mean_DN - ym);
  c.K = sxy / sxx;
  c.b = ym - c.K * xm;
  double vK = 0, vb = 0, rss = 0;
  for (const RadiometricLevel* l : used) {
    const double ci = (l->intensity - xm) / sxx, var = l->sd_DN * l->sd_DN / static_cast<double>(l->pixels);
    vK += ci * ci * var;
    vb += (1.0 / n - xm * ci) * (1.0 / n - xm * ci) * var;
    const double e = l->mean_DN - (c.K * l->intensity + c.b);
    rss += e * e;
  }
  c.K_se = std::sqrt(vK), c.b_se = std::sqrt(vb);
  c.residual_rms_DN = std::sqrt(rss / n);
  if (!(c.K > 0)) c.message = fmt::format("K = {:.6g} DN per unit intensity: the signal does not grow with the level", c.K);
  return c;
}

template <class T>
FourCameraRadiometry calibrate_four_camera_radiometry(const std::array<CameraGeometry, kFourCameras>& geometry,
                                                      int width, int height,
                                                      std::span<const FourCameraFrames<T>> levels,
                                                      const RadiometricOptions& options) {
  if (!(options.intensity_per_level > 0 && std::isfinite(options.intensity_per_level)))
    throw std::invalid_argument(
        fmt::format("the sphere's intensity per level must be finite and > 0, got {}", options.intensity_per_level));
  if (levels.empty()) throw std::invalid_argument("no unpolarized stop: the radiometric calibration needs the sphere's levels");
  const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  for (const FourCameraFrames<T>& s : levels) {
    check_frames(s, n, "unpolarized");
    if (!(std::isfinite(s.level) && s.level >= 0))
      throw std::invalid_argument(fmt::format("unpolarized stop {}: level {} (expected a finite level ≥ 0)", s.stop, s.level));
  }
  FourCameraRadiometry out;
  out.options = options;
  for (std::size_t j = 0; j < 4; ++j) {
    const PixelWindow w = centred_window(width, height, geometry[j].cx, geometry[j].cy, options.window_half_px);
    std::vector<RadiometricLevel> rows;
    for (const FourCameraFrames<T>& s : levels) rows.push_back(radiometric_level<T>(s.f[j], width, w, s, options));
    out.camera[j] = fit_radiometry(std::move(rows), w);
  }
  return out;
}

template <class T>
PolarizerSamples polarizer_samples(const FourCameraModel& model, const PerCamera& nominal_deg,
                                   std::span<const FourCameraFrames<T>> stops, const PolarizerOptions& options,
                                   const Progress& progress) {
  if (stops.empty()) throw std::invalid_argument("no polarized stop: the polarizer-angle calibration needs the table's turn");
  for (std::size_t j = 0; j < 4; ++j)
    if (!(model.K[j] > 0 && std::isfinite(model.K[j]) && std::isfinite(model.b[j])))
      throw std::invalid_argument(fmt::format("camera {}: K = {}, b = {} cannot correct a frame", j + 1, model.K[j], model.b[j]));
  // The fusion of the geometry with K = 1, b = 0: fuse_at is linear in the frames, so camera j's
  // sample s_j follows from its frame alone among zero frames, x = s_j·w_j, with w_j (column j of
  // (DᵀD)⁻¹Dᵀ) from a frame of ones: s_j = x·w_j/|w_j|² — the fusion's own sampling, reused.
  FourCameraModel unit = model;
  unit.K = {1, 1, 1, 1}, unit.b = {0, 0, 0, 0}, unit.axis_deg = nominal_deg;
  const FourCameraFusion fusion(unit);
  const VirtualCamera g = fusion.grid();
  const std::size_t n = static_cast<std::size_t>(g.width) * static_cast<std::size_t>(g.height);
  PolarizerSamples s;
  s.nominal_deg = nominal_deg;
  s.window = centred_window(g.width, g.height, g.cx, g.cy, options.window_half_px, options.stride);
  const std::vector<T> zeros(n, T(0)), ones(n, T(1));
  const auto with = [&](std::size_t j, std::span<const T> f) {
    std::array<std::span<const T>, kFourCameras> frames{zeros, zeros, zeros, zeros};
    frames[j] = f;
    return frames;
  };
  std::vector<std::size_t> index;
  std::vector<std::array<Eigen::Vector3d, 4>> columns;
  for (int row = s.window.row0; row < s.window.row1; row += s.window.stride)
    for (int col = s.window.col0; col < s.window.col1; col += s.window.stride) {
      const std::size_t i = static_cast<std::size_t>(row) * static_cast<std::size_t>(g.width) + static_cast<std::size_t>(col);
      std::array<Eigen::Vector3d, 4> w;
      PerCamera delta{};
      for (std::size_t j = 0; j < 4; ++j) {
        FusedStokes x;
        if (!fusion.fuse_at<T>(with(j, ones), i, x))
          throw std::invalid_argument(fmt::format("virtual pixel ({}, {}) of the polarizer window is not seen by every "
                                                  "camera: the geometry does not overlap there",
                                                  col, row));
        w[j] = {x.S1, x.S2, x.S0};
        delta[j] = j == 0 ? 0.0 : fusion.frame_offset_deg(static_cast<int>(j), i);
      }
      index.push_back(i);
      columns.push_back(w);
      s.views.push_back(vec3::unit({(col + 0.5 - g.cx) / g.f_c, (row + 0.5 - g.cy) / g.f_c, 1.0}));
      s.delta_deg.push_back(delta);
    }
  progress.begin("calibrate four-camera: polarized stops", static_cast<long long>(stops.size()));
  for (const FourCameraFrames<T>& st : stops) {
    check_frames(st, n, "polarized");
    s.stops.push_back(st.stop);
    s.theta_R_deg.push_back(st.theta_R_deg);
    for (std::size_t k = 0; k < index.size(); ++k) {
      std::array<double, 4> F{};
      for (std::size_t j = 0; j < 4; ++j) {
        FusedStokes x;
        fusion.fuse_at<T>(with(j, st.f[j]), index[k], x);
        const Eigen::Vector3d& w = columns[k][j];
        const double sample = (x.S1 * w(0) + x.S2 * w(1) + x.S0 * w(2)) / w.squaredNorm();
        F[j] = (sample - model.b[j]) / model.K[j];
        if (!std::isfinite(F[j]))
          throw std::invalid_argument(fmt::format("polarized stop {}: camera {} is not finite near the principal point",
                                                  st.stop, j + 1));
      }
      s.F.push_back(F);
    }
    progress.advance();
  }
  progress.finish();
  return s;
}

Eigen::VectorXd polarizer_residuals(const PolarizerSamples& samples, const Eigen::Matrix<double, 5, 1>& x,
                                    const PolarizerOptions& options) {
  Eigen::VectorXd r;
  polarizer_model(samples, x, options, r, nullptr);
  return r;
}

Eigen::MatrixXd polarizer_jacobian(const PolarizerSamples& samples, const Eigen::Matrix<double, 5, 1>& x,
                                   const PolarizerOptions& options) {
  Eigen::VectorXd r;
  Eigen::MatrixXd J;
  polarizer_model(samples, x, options, r, &J);
  return J;
}

PolarizerFit fit_polarizer_angles(const PolarizerSamples& s, const PolarizerOptions& o) {
  if (!(o.table_sense == 1.0 || o.table_sense == -1.0))
    throw std::invalid_argument(fmt::format("table sense {} (expected +1 or −1)", o.table_sense));
  if (!(o.min_singular_ratio > 0 && o.min_singular_ratio < 1))
    throw std::invalid_argument(fmt::format("minimum singular ratio {} (expected (0, 1))", o.min_singular_ratio));
  if (!(o.dop_weight >= 0 && std::isfinite(o.dop_weight)))
    throw std::invalid_argument(fmt::format("DoP weight {} (expected a finite weight ≥ 0)", o.dop_weight));
  if (!(o.fit.max_iterations > 0 && o.fit.max_evaluations > 0 && o.fit.function_tolerance >= 0 &&
        o.fit.parameter_tolerance >= 0 && o.fit.gradient_tolerance >= 0))
    throw std::invalid_argument("the polarizer fit's limits must be positive and its tolerances ≥ 0");
  const std::size_t P = s.pixels(), M = s.theta_R_deg.size();
  if (s.delta_deg.size() != P || s.F.size() != P * M)
    throw std::invalid_argument("polarizer samples: views, offsets and values disagree in size");
  PolarizerFit fit;
  const bool with_dop = o.dop_weight > 0;
  const int unknowns = with_dop ? 5 : 4;
  fit.unknowns = unknowns;
  fit.summary.observations = static_cast<int>(P * M);
  if (M < 3 || P == 0) {
    fit.summary.termination = FitTermination::TooFewObservations;
    fit.summary.message = fmt::format("{} polarized stop(s): the angles need at least 3 table angles", M);
    return fit;
  }
  if (const double ratio = table_design_ratio(s.theta_R_deg); !(ratio >= kMinTableDesignRatio)) {
    fit.summary.termination = FitTermination::RankDeficient;
    fit.summary.message = fmt::format(
        "the polarized stops turn the polarizer through too few orientations to separate the analyzers' axes from the "
        "DoP (σ_min/σ_max of [1, cos 2θ_R, sin 2θ_R] = {:.2g}, needs ≥ {}; stops 90° apart give two orientations, "
        "0): turn the table in steps that are not a multiple of 90°, e.g. 30°",
        ratio, kMinTableDesignRatio);
    return fit;
  }
  // The start: ε = 0, ψ_0 the circular mean of φ̂ − s_R·θ_R, d_0 the mean d̂ with the nominal axes.
  Eigen::Matrix<double, 5, 1> x0 = Eigen::Matrix<double, 5, 1>::Zero();
  {
    double c = 0, sn = 0, d = 0;
    for (std::size_t i = 0; i < P; ++i) {
      const std::array<double, 4> a = axes_rad(s, i, x0);
      for (std::size_t m = 0; m < M; ++m) {
        const PixelFusion p = fuse_with_derivatives(a, s.F[m * P + i]);
        const double t = 2 * (p.phi - o.table_sense * deg2rad(s.theta_R_deg[m]));
        c += std::cos(t), sn += std::sin(t), d += p.dop;
      }
    }
    x0(3) = 0.5 * std::atan2(sn, c);
    x0(4) = with_dop ? d / static_cast<double>(P * M) : 0.0;
  }
  for (std::size_t k = 0; k < P * M; ++k)
    for (double F : s.F[k])
      if (!std::isfinite(F)) throw std::invalid_argument("polarizer samples: a value is not finite");

  PolarizerFunctor f(s, o, x0, unknowns);
  Eigen::LevenbergMarquardt<PolarizerFunctor> lm(f);
  lm.setXtol(o.fit.parameter_tolerance);
  lm.setFtol(o.fit.function_tolerance);
  lm.setGtol(o.fit.gradient_tolerance);
  lm.setMaxfev(o.fit.max_evaluations);
  Eigen::VectorXd x = x0.head(unknowns);
  using S = Eigen::LevenbergMarquardtSpace::Status;
  S status = lm.minimizeInit(x);
  fit.summary.cost_unit = "rad^2 (the AoP residuals in rad, the DoP residuals times dop_weight)";
  fit.summary.initial_cost = 0.5 * lm.fvec().squaredNorm();
  if (status == S::NotStarted) {
    status = S::Running;
    while (status == S::Running && lm.njev() < o.fit.max_iterations) status = lm.minimizeOneStep(x);
  }
  const SolverOutcome outcome = levenberg_marquardt_outcome(static_cast<int>(status));
  fit.summary.solver_status = outcome.name;
  fit.summary.iterations = static_cast<int>(lm.njev());
  fit.summary.evaluations = static_cast<int>(lm.nfev());
  const Eigen::Matrix<double, 5, 1> xf = f.full(x);
  Eigen::VectorXd r;
  Eigen::MatrixXd Jf;
  polarizer_model(s, xf, o, r, &Jf);
  fit.summary.final_cost = 0.5 * r.squaredNorm();
  double aop_ss = 0, dop_ss = 0;
  for (Eigen::Index k = 0; k < r.size(); k += 2) aop_ss += r(k) * r(k), dop_ss += r(k + 1) * r(k + 1);
  const double N = static_cast<double>(P * M);
  fit.residual_rms_deg = rad2deg(std::sqrt(aop_ss / N));
  fit.dop_residual_rms = with_dop ? std::sqrt(dop_ss / N) / o.dop_weight : std::numeric_limits<double>::quiet_NaN();
  for (std::size_t j = 1; j < 4; ++j) fit.eps_deg[j] = rad2deg(xf(static_cast<Eigen::Index>(j - 1)));
  fit.psi0_deg = wrap_axis_deg(rad2deg(xf(3)));
  fit.dop = with_dop ? xf(4) : std::numeric_limits<double>::quiet_NaN();

  // Identifiability and standard errors: the column-scaled Jacobian's SVD (as fit_eq15).
  const Eigen::MatrixXd J = Jf.leftCols(unknowns);
  const Eigen::VectorXd norms = J.colwise().norm().transpose();
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(J * norms.cwiseMax(1e-300).cwiseInverse().asDiagonal(), Eigen::ComputeThinV);
  const Eigen::VectorXd sigma = svd.singularValues();
  fit.singular_ratio = sigma(sigma.size() - 1) / sigma(0);
  fit.rank = 0;
  for (Eigen::Index k = 0; k < sigma.size(); ++k) fit.rank += sigma(k) >= o.min_singular_ratio * sigma(0) ? 1 : 0;
  const double dof = (with_dop ? 2.0 : 1.0) * N - unknowns;  // the AoP residuals, and the DoP's when weighted
  if (dof > 0 && fit.rank == unknowns) {
    const Eigen::MatrixXd V = svd.matrixV();
    const Eigen::VectorXd inv_s2 = sigma.cwiseAbs2().cwiseInverse();
    const double s2 = r.squaredNorm() / dof;
    std::array<double, 5> se{};
    for (int c = 0; c < unknowns; ++c) se[static_cast<std::size_t>(c)] = std::sqrt(s2 * (V.row(c).cwiseAbs2() * inv_s2)(0)) / norms(c);
    for (std::size_t j = 1; j < 4; ++j) fit.eps_se_deg[j] = rad2deg(se[j - 1]);
    fit.psi0_se_deg = rad2deg(se[3]);
    fit.dop_se = with_dop ? se[4] : std::numeric_limits<double>::quiet_NaN();
  }

  // polarizer.csv's rows: before (nominal axes, ψ_0 refitted by one Gauss–Newton step) and after.
  {
    Eigen::Matrix<double, 5, 1> xb = xf;
    xb.head(3).setZero();
    Eigen::VectorXd rb;
    Eigen::MatrixXd Jb;
    polarizer_model(s, xb, o, rb, &Jb);
    double num = 0, den = 0;
    for (Eigen::Index k = 0; k < rb.size(); k += 2) num += Jb(k, 3) * rb(k), den += Jb(k, 3) * Jb(k, 3);
    xb(3) -= num / den;
    polarizer_model(s, xb, o, rb, nullptr);
    double ss = 0;
    for (Eigen::Index k = 0; k < rb.size(); k += 2) ss += rb(k) * rb(k);
    fit.residual_rms_before_deg = rad2deg(std::sqrt(ss / N));
    for (std::size_t m = 0; m < M; ++m) {
      PolarizerStopRow row;
      row.stop = s.stops.empty() ? static_cast<int>(m) : s.stops[m];
      row.theta_R_deg = s.theta_R_deg[m];
      double cb = 0, sb = 0, ca = 0, sa = 0;
      for (std::size_t i = 0; i < P; ++i) {
        const PixelFusion pb = fuse_with_derivatives(axes_rad(s, i, xb), s.F[m * P + i]);
        const PixelFusion pa = fuse_with_derivatives(axes_rad(s, i, xf), s.F[m * P + i]);
        cb += std::cos(2 * pb.phi), sb += std::sin(2 * pb.phi), ca += std::cos(2 * pa.phi), sa += std::sin(2 * pa.phi);
        row.dop_before += pb.dop, row.dop_after += pa.dop;
        const Eigen::Index k = static_cast<Eigen::Index>(2 * (m * P + i));
        row.residual_before_deg += rad2deg(rb(k)), row.residual_after_deg += rad2deg(r(k));
      }
      const double Pn = static_cast<double>(P);
      row.aop_before_deg = wrap_axis_deg(rad2deg(0.5 * std::atan2(sb, cb)));
      row.aop_after_deg = wrap_axis_deg(rad2deg(0.5 * std::atan2(sa, ca)));
      row.dop_before /= Pn, row.dop_after /= Pn, row.residual_before_deg /= Pn, row.residual_after_deg /= Pn;
      fit.stops.push_back(row);
    }
  }

  const auto stop = [&](FitTermination t, std::string message) {
    fit.summary.termination = t;
    fit.summary.message = std::move(message);
    return fit;
  };
  if (!r.allFinite() || !xf.head(unknowns).allFinite())
    return stop(FitTermination::OutsideDomain, "the fit ended where the fused AoP or DoP is undefined (no polarization)");
  if (outcome.termination != FitTermination::Converged)
    return stop(outcome.termination, fmt::format("{} ({} iterations, {} evaluations allowed; solver status {})",
                                                 outcome.message, o.fit.max_iterations, o.fit.max_evaluations,
                                                 outcome.name));
  if (fit.rank < unknowns) {
    static const char* const names[5] = {"eps_2", "eps_3", "eps_4", "psi_0", "d_0"};
    Eigen::Index worst = 0;
    svd.matrixV().col(sigma.size() - 1).cwiseAbs().maxCoeff(&worst);
    return stop(FitTermination::RankDeficient,
                fmt::format("the data cannot determine the axes (rank {} of {}, σ_min/σ_max = {:.1e}); {} is the least "
                            "determined{}",
                            fit.rank, unknowns, fit.singular_ratio, names[worst],
                            with_dop ? ": turn the table over more angles" : ": the AoP alone sees two of the axes' "
                                                                              "four combinations (use the DoP residual)"));
  }
  return stop(FitTermination::Converged, outcome.message);
}

template <class T>
FourCameraCalibration calibrate_four_camera(const std::array<CameraGeometry, kFourCameras>& geometry, int width,
                                            int height, std::span<const FourCameraFrames<T>> levels,
                                            std::span<const FourCameraFrames<T>> polarized,
                                            const FourCameraCalibrationOptions& options, const Progress& progress) {
  FourCameraCalibration c;
  c.options = options;
  c.radiometry = calibrate_four_camera_radiometry<T>(geometry, width, height, levels, options.radiometric);
  for (std::size_t j = 0; j < 4; ++j)
    if (!c.radiometry.camera[j].usable())
      throw CalibrationError(fmt::format("camera {}: the radiometric fit is not usable: {}", j + 1,
                                         c.radiometry.camera[j].message));
  if (polarized.empty())
    throw CalibrationError("no polarized stop: the polarizer-angle calibration needs the polarized source turned by the table");
  c.model.width = width, c.model.height = height;
  c.model.camera = geometry;
  for (std::size_t j = 0; j < 4; ++j) {
    c.model.K[j] = c.radiometry.camera[j].K;
    c.model.b[j] = c.radiometry.camera[j].b;
  }
  const PolarizerSamples samples = polarizer_samples<T>(c.model, options.nominal_deg, polarized, options.polarizer, progress);
  c.polarizer = fit_polarizer_angles(samples, options.polarizer);
  for (std::size_t j = 0; j < 4; ++j) c.model.axis_deg[j] = options.nominal_deg[j] + c.polarizer.eps_deg[j];
  return c;
}

#define POLRIG_FOUR_CAMERA_CALIBRATION(T)                                                                          \
  template RadiometricLevel radiometric_level<T>(std::span<const T>, int, const PixelWindow&,                      \
                                                 const FourCameraFrames<T>&, const RadiometricOptions&);           \
  template FourCameraRadiometry calibrate_four_camera_radiometry<T>(                                               \
      const std::array<CameraGeometry, kFourCameras>&, int, int, std::span<const FourCameraFrames<T>>,             \
      const RadiometricOptions&);                                                                                  \
  template PolarizerSamples polarizer_samples<T>(const FourCameraModel&, const PerCamera&,                         \
                                                 std::span<const FourCameraFrames<T>>, const PolarizerOptions&,    \
                                                 const Progress&);                                                 \
  template FourCameraCalibration calibrate_four_camera<T>(                                                         \
      const std::array<CameraGeometry, kFourCameras>&, int, int, std::span<const FourCameraFrames<T>>,             \
      std::span<const FourCameraFrames<T>>, const FourCameraCalibrationOptions&, const Progress&);
POLRIG_FOUR_CAMERA_CALIBRATION(double)
POLRIG_FOUR_CAMERA_CALIBRATION(std::uint16_t)
#undef POLRIG_FOUR_CAMERA_CALIBRATION

}  // namespace polrig
