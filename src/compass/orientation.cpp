#include "polrig/compass/orientation.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>
#include <string>
#include <tuple>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "polrig/compass/heading.h"
#include "polrig/units.h"

namespace polrig {

namespace {

// A point's view geometry without trigonometric calls: cos/sin of α and γ from the offsets.
struct ViewTrig {
  double ca = 1, sa = 0;  // cos α, sin α (α = 0 at the principal point itself)
  double cg = 1, sg = 0;  // cos γ, sin γ
};

ViewTrig view_trig(double x_px, double y_px, const CameraIntrinsics& camera) {
  const double dx = x_px - camera.x_c_px, dy = y_px - camera.y_c_px;
  // sqrt, not hypot: pixel offsets and f_c are far from overflow, and hypot costs several times more
  // in the per-point loop (the benchmark's floor is one cos and one sin per point).
  const double r2 = dx * dx + dy * dy;
  const double r = std::sqrt(r2);
  ViewTrig t;
  if (r > 0) {
    t.ca = dx / r;
    t.sa = dy / r;
  }
  const double inv_len = 1.0 / std::sqrt(r2 + camera.f_c_px * camera.f_c_px);
  t.cg = camera.f_c_px * inv_len;
  t.sg = r * inv_len;
  return t;
}

// Eqs. 6–8 (or the analyzer-in-front projection) from cos/sin of φ_pix.
Vec3 e_vector(double c_pix, double s_pix, const ViewTrig& t, AopConversion conversion) {
  if (conversion == AopConversion::Meridional) {
    // φ = φ_pix − α
    const double c = c_pix * t.ca + s_pix * t.sa, s = s_pix * t.ca - c_pix * t.sa;
    // Ry(γ)·[c, s, 0] = [c·cos γ, s, −c·sin γ]; then Rz(α).
    const double x = c * t.cg, y = s, z = -c * t.sg;
    return {t.ca * x - t.sa * y, t.sa * x + t.ca * y, z};
  }
  const Vec3 v{t.sg * t.ca, t.sg * t.sa, t.cg};
  const double pv = c_pix * v[0] + s_pix * v[1];
  const Vec3 p{c_pix - pv * v[0], s_pix - pv * v[1], -pv * v[2]};
  return vec3::unit(p);  // |p|² = 1 − (p·v)² ≥ cos²γ > 0 for a view in front of the lens
}

void check_lengths(const SkyPoints& p) {
  const std::size_t n = p.aop_deg.size();
  if (p.x_px.size() != n || p.y_px.size() != n)
    throw std::invalid_argument(fmt::format(
        "sky points: x_px ({}), y_px ({}) and aop_deg ({}) must have the same length",
        p.x_px.size(), p.y_px.size(), n));
  if (!p.dop.empty() && p.dop.size() != n)
    throw std::invalid_argument(fmt::format(
        "sky points: dop has {} values for {} points (give none or one per point)", p.dop.size(), n));
}

bool usable(const SkyPoints& p, std::size_t k, const OrientationSettings& s) {
  if (!std::isfinite(p.aop_deg[k]) || !std::isfinite(p.x_px[k]) || !std::isfinite(p.y_px[k]))
    return false;
  if (p.dop.empty()) return true;
  if ((s.dop_weighting || s.correct_noise_bias || s.min_dop > 0) && !std::isfinite(p.dop[k])) return false;
  return !(s.min_dop > 0 && p.dop[k] < s.min_dop);
}

double wrap360(double deg) { return wrap_heading_deg(deg); }

// The half of the meridian `axis_deg` (mod 180°) nearer the prior, or Ambiguous180.
void choose_half(SunAzimuthSolution& r, double axis_deg, std::optional<double> prior_az_deg) {
  r.meridian_deg = wrap_axis_deg(axis_deg);
  if (!prior_az_deg) {
    r.status = SunAzimuthStatus::Ambiguous180;
    r.sun_az_deg = r.meridian_deg;
    return;
  }
  r.status = SunAzimuthStatus::Ok;
  const double a = r.meridian_deg, b = wrap360(r.meridian_deg + 180.0);
  r.sun_az_deg = std::abs(heading_difference_deg(a, *prior_az_deg)) <=
                         std::abs(heading_difference_deg(b, *prior_az_deg))
                     ? a : b;
}

void check_finite_positive(double v, const char* name, bool allow_zero = false) {
  if (!std::isfinite(v) || v < 0 || (!allow_zero && v == 0))
    throw std::invalid_argument(fmt::format("orientation setting {} = {}: must be finite and {}",
                                            name, v, allow_zero ? "≥ 0" : "> 0"));
}

}  // namespace

void check_intrinsics(const CameraIntrinsics& c) {
  if (!std::isfinite(c.f_c_px) || c.f_c_px <= 0)
    throw std::invalid_argument(
        fmt::format("camera f_c = {} px: the focal length must be finite and > 0", c.f_c_px));
  if (!std::isfinite(c.x_c_px) || !std::isfinite(c.y_c_px))
    throw std::invalid_argument(fmt::format(
        "camera principal point ({}, {}) px: must be finite", c.x_c_px, c.y_c_px));
}

void check_orientation_settings(const OrientationSettings& s) {
  check_finite_positive(s.min_dop, "min_dop", true);
  if (s.min_dop > 1) throw std::invalid_argument(fmt::format("orientation setting min_dop = {}: must be in [0, 1]", s.min_dop));
  check_finite_positive(s.horizon_margin_deg, "horizon_margin_deg", true);
  if (s.horizon_margin_deg > 90)
    throw std::invalid_argument(fmt::format(
        "orientation setting horizon_margin_deg = {}: must be in [0°, 90°]", s.horizon_margin_deg));
  check_finite_positive(s.min_relative_gap, "min_relative_gap", true);
  check_finite_positive(s.zenith_radius_px, "zenith_radius_px");
  check_finite_positive(s.line_aop_tolerance_deg, "line_aop_tolerance_deg");
  if (s.line_aop_tolerance_deg >= 45)
    throw std::invalid_argument(fmt::format(
        "orientation setting line_aop_tolerance_deg = {}: must be below 45°", s.line_aop_tolerance_deg));
  check_finite_positive(s.line_min_radius_px, "line_min_radius_px", true);
  check_finite_positive(s.hough_bin_deg, "hough_bin_deg");
  // Below 0.001° (180 000 bins) the bins are far finer than any AoP's noise, and the count of bins
  // would outgrow memory (1e-9° asked for 1.8e11).
  if (s.hough_bin_deg > 30 || s.hough_bin_deg < 1e-3)
    throw std::invalid_argument(fmt::format(
        "orientation setting hough_bin_deg = {}: must be in [0.001°, 30°]", s.hough_bin_deg));
  if (s.prior_sun) {
    const Vec3& p = *s.prior_sun;
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]) || vec3::norm(p) == 0)
      throw std::invalid_argument(fmt::format(
          "orientation setting prior_sun = ({}, {}, {}): must be a finite, non-zero direction",
          p[0], p[1], p[2]));
  }
}

SkyPoints grid_points(int cols, int rows, double element_px, std::vector<double> aop_deg,
                      std::vector<double> dop) {
  if (cols <= 0 || rows <= 0 || !std::isfinite(element_px) || element_px <= 0)
    throw std::invalid_argument(fmt::format(
        "sky grid {} × {} of {} px elements: sizes must be positive", cols, rows, element_px));
  const std::size_t n = static_cast<std::size_t>(cols) * static_cast<std::size_t>(rows);
  if (aop_deg.size() != n)
    throw std::invalid_argument(fmt::format("sky grid {} × {}: aop has {} values, expected {}",
                                            cols, rows, aop_deg.size(), n));
  if (!dop.empty() && dop.size() != n)
    throw std::invalid_argument(fmt::format("sky grid {} × {}: dop has {} values, expected {} or none",
                                            cols, rows, dop.size(), n));
  SkyPoints p;
  p.x_px.resize(n);
  p.y_px.resize(n);
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      const std::size_t k = static_cast<std::size_t>(r) * static_cast<std::size_t>(cols) + static_cast<std::size_t>(c);
      p.x_px[k] = (c + 0.5) * element_px;
      p.y_px[k] = (r + 0.5) * element_px;
    }
  p.aop_deg = std::move(aop_deg);
  p.dop = std::move(dop);
  return p;
}

std::string_view aop_conversion_name(AopConversion c) {
  return c == AopConversion::Meridional ? "meridional" : "analyzer-in-front";
}

std::optional<AopConversion> parse_aop_conversion(std::string_view name) {
  if (name == "meridional") return AopConversion::Meridional;
  if (name == "analyzer-in-front") return AopConversion::AnalyzerInFront;
  return std::nullopt;
}

PointView point_view(double x_px, double y_px, const CameraIntrinsics& camera) {
  const double dx = x_px - camera.x_c_px, dy = y_px - camera.y_c_px;
  return {std::atan(std::hypot(dx, dy) / camera.f_c_px), std::atan2(dy, dx)};
}

Vec3 point_e_vector(double aop_pix_deg, double x_px, double y_px, const CameraIntrinsics& camera,
                    AopConversion conversion) {
  const double phi = deg2rad(aop_pix_deg);
  return e_vector(std::cos(phi), std::sin(phi), view_trig(x_px, y_px, camera), conversion);
}

std::string_view sun_vector_status_name(SunVectorStatus s) {
  switch (s) {
    case SunVectorStatus::Ok: return "ok";
    case SunVectorStatus::NearHorizon: return "near-horizon";
    case SunVectorStatus::TooFewVectors: return "too-few-vectors";
    case SunVectorStatus::Degenerate: return "degenerate";
  }
  return "?";
}

std::string_view sun_root_name(SunRoot r) {
  switch (r) {
    case SunRoot::None: return "none";
    case SunRoot::AboveHorizon: return "above-horizon";
    case SunRoot::Prior: return "prior";
  }
  return "?";
}

std::string_view sun_azimuth_status_name(SunAzimuthStatus s) {
  switch (s) {
    case SunAzimuthStatus::Ok: return "ok";
    case SunAzimuthStatus::Ambiguous180: return "ambiguous-180";
    case SunAzimuthStatus::NoPoints: return "no-points";
  }
  return "?";
}

SunVectorSolution sun_vector_eigen(const SkyPoints& points, const CameraIntrinsics& camera,
                                   const OrientationSettings& settings) {
  check_lengths(points);
  check_intrinsics(camera);
  check_orientation_settings(settings);
  if (settings.correct_noise_bias && points.dop.empty())
    throw std::invalid_argument("orientation setting correct_noise_bias: needs the points' DoP (none given)");
  const bool corrected = settings.correct_noise_bias;
  const bool weighted = settings.dop_weighting && !points.dop.empty();
  // EEᵀ = Σ w·e·eᵀ, its six distinct entries (Eq. 12); with the correction also Σ v·vᵀ (B).
  double xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0, wsum = 0;
  Eigen::Matrix3d vv = Eigen::Matrix3d::Zero();
  int used = 0;
  for (std::size_t k = 0; k < points.aop_deg.size(); ++k) {
    if (!usable(points, k, settings)) continue;
    const double w = corrected ? points.dop[k] * points.dop[k] : weighted ? points.dop[k] : 1.0;
    if (!(w > 0)) continue;
    const double phi = deg2rad(points.aop_deg[k]);
    const ViewTrig view = view_trig(points.x_px[k], points.y_px[k], camera);
    const Vec3 e = e_vector(std::cos(phi), std::sin(phi), view, settings.conversion);
    if (corrected) {
      const Eigen::Vector3d v(view.sg * view.ca, view.sg * view.sa, view.cg);
      vv.noalias() += v * v.transpose();
    }
    xx += w * e[0] * e[0];
    xy += w * e[0] * e[1];
    xz += w * e[0] * e[2];
    yy += w * e[1] * e[1];
    yz += w * e[1] * e[2];
    zz += w * e[2] * e[2];
    wsum += w;
    ++used;
  }
  SunVectorSolution r;
  r.vectors_used = used;
  if (used < 2) {
    r.status = SunVectorStatus::TooFewVectors;
    return r;
  }
  Eigen::Matrix3d m;
  m << xx, xy, xz, xy, yy, yz, xz, yz, zz;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(m);
  const Eigen::Vector3d lambda = solver.eigenvalues();  // rising
  for (int i = 0; i < 3; ++i) r.eigenvalues[static_cast<std::size_t>(i)] = lambda(i);
  const double trace = lambda.sum();
  r.relative_gap = trace > 0 ? (lambda(1) - lambda(0)) / trace : 0.0;
  r.rms_residual = std::sqrt(std::max(lambda(0), 0.0) / wsum);
  if (solver.info() != Eigen::Success || !(r.relative_gap >= settings.min_relative_gap) ||
      r.relative_gap == 0) {
    r.status = SunVectorStatus::Degenerate;
    return r;
  }
  Eigen::Vector3d v = solver.eigenvectors().col(0).normalized();
  if (corrected) {
    // B = Σ (I − v·vᵀ) over the points used: positive definite unless every view is the same.
    const Eigen::Matrix3d B = static_cast<double>(used) * Eigen::Matrix3d::Identity() - vv;
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::Matrix3d> general(m, B);
    if (general.info() != Eigen::Success || !(B.determinant() > 0)) {
      r.status = SunVectorStatus::Degenerate;
      return r;
    }
    v = general.eigenvectors().col(0).normalized();
    r.stokes_noise_sd = 2.0 * std::sqrt(std::max(general.eigenvalues()(0), 0.0));
    r.rms_residual = std::sqrt(std::max(v.dot(m * v), 0.0) / wsum);
  }
  Vec3 s{v(0), v(1), v(2)};
  // The solar/antisolar ambiguity (spec §2.5).
  const Vec3* prior = settings.prior_sun ? &*settings.prior_sun : nullptr;
  if (prior && vec3::dot(s, *prior) != 0) {
    if (vec3::dot(s, *prior) < 0) s = vec3::mul(s, -1.0);
    r.root = SunRoot::Prior;
  } else {
    if (s[2] < 0) s = vec3::mul(s, -1.0);
    r.root = SunRoot::AboveHorizon;
  }
  r.sun = s;
  r.sun_az_deg = wrap360(rad2deg(std::atan2(s[1], s[0])));
  r.sun_el_deg = rad2deg(std::asin(std::clamp(s[2], -1.0, 1.0)));
  r.status = (r.root == SunRoot::AboveHorizon && r.sun_el_deg < settings.horizon_margin_deg)
                 ? SunVectorStatus::NearHorizon
                 : SunVectorStatus::Ok;
  return r;
}

SunAzimuthSolution sun_azimuth_single_point(const SkyPoints& points, const CameraIntrinsics& camera,
                                            const OrientationSettings& settings,
                                            std::optional<double> prior_sun_az_deg) {
  check_lengths(points);
  check_intrinsics(camera);
  check_orientation_settings(settings);
  // Axial mean of the E-vectors' image angles: Σ exp(2iψ), ψ = atan2(e_y, e_x).
  std::complex<double> sum{0, 0};
  int used = 0;
  const double r2 = settings.zenith_radius_px * settings.zenith_radius_px;
  for (std::size_t k = 0; k < points.aop_deg.size(); ++k) {
    if (!usable(points, k, settings)) continue;
    const double dx = points.x_px[k] - camera.x_c_px, dy = points.y_px[k] - camera.y_c_px;
    if (dx * dx + dy * dy > r2) continue;
    const double phi = deg2rad(points.aop_deg[k]);
    const Vec3 e = e_vector(std::cos(phi), std::sin(phi),
                            view_trig(points.x_px[k], points.y_px[k], camera), settings.conversion);
    const double psi = std::atan2(e[1], e[0]);
    sum += std::polar(1.0, 2.0 * psi);
    ++used;
  }
  SunAzimuthSolution r;
  r.points_used = r.points_selected = used;
  if (used == 0 || std::abs(sum) == 0) {
    r.status = SunAzimuthStatus::NoPoints;
    return r;
  }
  // The zenith E-vector is ⊥ the solar meridian.
  choose_half(r, rad2deg(0.5 * std::arg(sum)) + 90.0, prior_sun_az_deg);
  return r;
}

SunAzimuthSolution sun_azimuth_line(const SkyPoints& points, const CameraIntrinsics& camera,
                                    const OrientationSettings& settings,
                                    std::optional<double> prior_sun_az_deg) {
  check_lengths(points);
  check_intrinsics(camera);
  check_orientation_settings(settings);
  const int bins = static_cast<int>(std::ceil(180.0 / settings.hough_bin_deg));
  const double bin = 180.0 / bins;
  std::vector<int> votes(static_cast<std::size_t>(bins), 0);
  // The selected points' image angle α mod 180° (the line through the principal point).
  std::vector<double> line_deg;
  const double rmin2 = settings.line_min_radius_px * settings.line_min_radius_px;
  for (std::size_t k = 0; k < points.aop_deg.size(); ++k) {
    if (!usable(points, k, settings)) continue;
    const double dx = points.x_px[k] - camera.x_c_px, dy = points.y_px[k] - camera.y_c_px;
    if (dx * dx + dy * dy <= rmin2 || (dx == 0 && dy == 0)) continue;
    const double alpha = rad2deg(std::atan2(dy, dx));
    double phi = points.aop_deg[k];
    if (settings.conversion == AopConversion::Meridional) {
      phi -= alpha;
    } else {  // φ from X_i of the analyzer-in-front E-vector
      const Vec3 e = point_e_vector(phi, points.x_px[k], points.y_px[k], camera, settings.conversion);
      const ViewTrig t = view_trig(points.x_px[k], points.y_px[k], camera);
      const Vec3 xi{t.cg * t.ca, t.cg * t.sa, -t.sg}, yi{-t.sa, t.ca, 0};
      phi = rad2deg(std::atan2(vec3::dot(e, yi), vec3::dot(e, xi)));
    }
    if (std::abs(axis_difference_deg(phi, 90.0)) > settings.line_aop_tolerance_deg) continue;
    const double theta = wrap_axis_deg(alpha);
    line_deg.push_back(theta);
    votes[static_cast<std::size_t>(std::min(bins - 1, static_cast<int>(theta / bin)))] += 1;
  }
  SunAzimuthSolution r;
  r.points_selected = static_cast<int>(line_deg.size());
  if (line_deg.empty()) {
    r.status = SunAzimuthStatus::NoPoints;
    return r;
  }
  const int peak = static_cast<int>(std::max_element(votes.begin(), votes.end()) - votes.begin());
  // Refine: the axial mean of the angles within ±1.5 bins of the centre, the window re-centred on
  // that mean (mean shift) until it stops moving: a window fixed on the bin's centre would pull the
  // mean towards it wherever the band is wider than the window (near the zenith).
  double centre = (peak + 0.5) * bin;
  int used = 0;
  for (int iteration = 0; iteration < 20; ++iteration) {
    std::complex<double> sum{0, 0};
    used = 0;
    for (double theta : line_deg)
      if (std::abs(axis_difference_deg(theta, centre)) <= 1.5 * bin) {
        sum += std::polar(1.0, 2.0 * deg2rad(theta));
        ++used;
      }
    if (used == 0) break;  // cannot happen on the first pass (the peak bin has votes)
    const double mean = wrap_axis_deg(rad2deg(0.5 * std::arg(sum)));
    const double shift = axis_difference_deg(mean, centre);
    centre = mean;
    if (std::abs(shift) < 1e-9) break;
  }
  r.points_used = used;
  choose_half(r, centre, prior_sun_az_deg);
  return r;
}

double camera_heading_deg(double sun_azimuth_geo_deg, double sun_az_camera_deg) {
  return wrap360(sun_azimuth_geo_deg + sun_az_camera_deg);
}

Vec3 sun_in_level_camera(double sun_azimuth_geo_deg, double sun_elevation_deg, double heading_deg) {
  const double a = deg2rad(heading_deg - sun_azimuth_geo_deg), h = deg2rad(sun_elevation_deg);
  return {std::cos(h) * std::cos(a), std::cos(h) * std::sin(a), std::sin(h)};
}

std::string_view orientation_method_name(OrientationMethod m) {
  switch (m) {
    case OrientationMethod::Eigenvector: return "eigenvector";
    case OrientationMethod::SinglePoint: return "single-point";
    case OrientationMethod::LineDetection: return "line-detection";
  }
  return "?";
}

std::array<OrientationEstimate, 3> orient_frame(const SkyPoints& points,
                                                const CameraIntrinsics& camera,
                                                std::optional<double> sun_azimuth_geo_deg,
                                                const OrientationSettings& settings) {
  std::array<OrientationEstimate, 3> out;
  const SunVectorSolution eig = sun_vector_eigen(points, camera, settings);
  OrientationEstimate& e = out[0];
  e.method = OrientationMethod::Eigenvector;
  e.status = sun_vector_status_name(eig.status);
  e.solved = has_sun(eig.status);
  std::optional<double> prior;
  if (e.solved) {
    e.sun_az_deg = eig.sun_az_deg;
    e.sun_el_deg = eig.sun_el_deg;
    prior = eig.sun_az_deg;
  } else if (settings.prior_sun) {
    prior = wrap360(rad2deg(std::atan2((*settings.prior_sun)[1], (*settings.prior_sun)[0])));
  }
  const SunAzimuthSolution single = sun_azimuth_single_point(points, camera, settings, prior);
  const SunAzimuthSolution line = sun_azimuth_line(points, camera, settings, prior);
  for (auto [slot, method, sol] : {std::tuple{1, OrientationMethod::SinglePoint, &single},
                                   std::tuple{2, OrientationMethod::LineDetection, &line}}) {
    OrientationEstimate& o = out[static_cast<std::size_t>(slot)];
    o.method = method;
    o.status = sun_azimuth_status_name(sol->status);
    o.solved = sol->status == SunAzimuthStatus::Ok;
    if (sol->status != SunAzimuthStatus::NoPoints) o.sun_az_deg = sol->sun_az_deg;
  }
  for (OrientationEstimate& o : out)
    if (o.solved && sun_azimuth_geo_deg) o.heading_deg = camera_heading_deg(*sun_azimuth_geo_deg, o.sun_az_deg);
  return out;
}

}  // namespace polrig
