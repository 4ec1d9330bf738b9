#include "polrig/compass/positioning.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <utility>

#include <Eigen/Dense>
#include <Eigen/SVD>
#include <fmt/format.h>
#include <unsupported/Eigen/LevenbergMarquardt>

#include "polrig/compass/heading.h"
#include "polrig/compass/orientation.h"
#include "polrig/units.h"

namespace polrig {

namespace {

// Eigen's Levenberg–Marquardt statuses as terminations (as calib/fit.cpp; MINPACK's 6–8 say no
// further improvement is possible in double precision: converged as far as it can).
struct Outcome {
  const char* name;
  bool converged;
  const char* message;
};
Outcome termination_of(Eigen::LevenbergMarquardtSpace::Status s) {
  using S = Eigen::LevenbergMarquardtSpace::Status;
  switch (s) {
    case S::NotStarted: return {"NotStarted", false, "the iteration did not start"};
    case S::Running: return {"Running", false, "the iteration limit came before convergence"};
    case S::ImproperInputParameters:
      return {"ImproperInputParameters", false, "the solver refused its input or its QR step failed"};
    case S::RelativeReductionTooSmall:
      return {"RelativeReductionTooSmall", true, "the relative reduction of the cost is below the function tolerance"};
    case S::RelativeErrorTooSmall:
      return {"RelativeErrorTooSmall", true, "the relative step is below the parameter tolerance"};
    case S::RelativeErrorAndReductionTooSmall:
      return {"RelativeErrorAndReductionTooSmall", true, "the relative reduction and step are below their tolerances"};
    case S::CosinusTooSmall:
      return {"CosinusTooSmall", true, "the residuals are orthogonal to the Jacobian"};
    case S::TooManyFunctionEvaluation:
      return {"TooManyFunctionEvaluation", false, "the evaluation limit came before convergence"};
    case S::FtolTooSmall: return {"FtolTooSmall", true, "no further reduction is possible in double precision"};
    case S::XtolTooSmall: return {"XtolTooSmall", true, "no further improvement is possible in double precision"};
    case S::GtolTooSmall: return {"GtolTooSmall", true, "the residuals are orthogonal to the Jacobian to double precision"};
    case S::UserAsked: return {"UserAsked", false, "the residual function stopped the iteration"};
  }
  return {"unknown", false, "unknown solver status"};
}

// The used sightings (positive weight): times, θ_meas (rad) and √w.
struct Data {
  std::vector<UtcTime> utc;
  std::vector<double> zenith_rad, sqrt_w;
  double weight_sum = 0;
  UtcTime first, last;
};

// The sun at one site for every sighting: sin and cos of its topocentric δ and GHA, and the
// refraction θ_geometric − θ_refracted (rad, 0 with refraction off), held while LM runs from
// that site.
struct Linearization {
  std::vector<double> sin_dec, cos_dec, sin_gha, cos_gha, refraction;
};

Linearization linearize(const Data& d, double lat_deg, double lon_deg, double height_m,
                        const PositionOptions& o) {
  const Site site{lat_deg, lon_deg, height_m};
  const std::shared_ptr<const SunTrack> own =
      o.ephemeris ? nullptr : std::make_shared<const SunTrack>(d.first, d.last, site, o.sun, o.track_node_spacing_s);
  const SunTrack& track = o.ephemeris ? *o.ephemeris : *own;
  Linearization lin;
  const std::size_t n = d.utc.size();
  for (auto* v : {&lin.sin_dec, &lin.cos_dec, &lin.sin_gha, &lin.cos_gha}) v->resize(n);
  lin.refraction.assign(n, 0.0);
  const double sL = std::sin(deg2rad(lat_deg)), cL = std::cos(deg2rad(lat_deg));
  const double sl = std::sin(deg2rad(lon_deg)), cl = std::cos(deg2rad(lon_deg));
  for (std::size_t k = 0; k < n; ++k) {
    const SunTrack::HourAngle h = track.hour_angle_at(d.utc[k]);
    lin.sin_dec[k] = h.sin_dec;
    lin.cos_dec[k] = h.cos_dec;
    lin.sin_gha[k] = h.sin_gha;
    lin.cos_gha[k] = h.cos_gha;
    if (o.sun.refraction) {
      const double cH = h.cos_gha * cl - h.sin_gha * sl;
      const double geometric = std::acos(std::clamp(sL * h.sin_dec + cL * h.cos_dec * cH, -1.0, 1.0));
      lin.refraction[k] = geometric - deg2rad(track.at(d.utc[k]).zenith_deg);
    }
  }
  return lin;
}

// Eq. 17's residuals r_k = √w_k·(θ_meas − θ_S) and their Jacobian, as zenith_model computes them
// (tests/test_positioning.cpp checks both against it), from the linearization's sines and cosines:
// cos(GHA + λ) by the addition theorem, one acos and one square root per sighting.
struct Eq17Residuals : Eigen::DenseFunctor<double> {
  Eq17Residuals(const Data& data, const Linearization& lin)
      : Eigen::DenseFunctor<double>(2, static_cast<int>(data.utc.size())), d(data), l(lin) {}
  template <class Row>
  void each(const InputType& x, Row&& row) const {
    const double sL = std::sin(x(0)), cL = std::cos(x(0)), sl = std::sin(x(1)), cl = std::cos(x(1));
    for (std::size_t k = 0; k < d.utc.size(); ++k) {
      const double cH = l.cos_gha[k] * cl - l.sin_gha[k] * sl, sH = l.sin_gha[k] * cl + l.cos_gha[k] * sl;
      const double c = std::clamp(sL * l.sin_dec[k] + cL * l.cos_dec[k] * cH, -1.0, 1.0);
      row(k, c, cH, sH, sL, cL);
    }
  }
  int operator()(const InputType& x, ValueType& r) const {
    each(x, [&](std::size_t k, double c, double, double, double, double) {
      r(static_cast<Eigen::Index>(k)) = d.sqrt_w[k] * (d.zenith_rad[k] - (std::acos(c) - l.refraction[k]));
    });
    return 0;
  }
  int df(const InputType& x, JacobianType& J) const {
    each(x, [&](std::size_t k, double c, double cH, double sH, double sL, double cL) {
      const double s = std::sqrt((1 - c) * (1 + c));  // sin θ_S; a sun at the zenith gives no direction
      const double g = s > 0 ? d.sqrt_w[k] / s : 0.0;
      const auto i = static_cast<Eigen::Index>(k);
      J(i, 0) = g * (cL * l.sin_dec[k] - sL * l.cos_dec[k] * cH);  // −√w·∂θ/∂L
      J(i, 1) = -g * cL * l.cos_dec[k] * sH;                         // −√w·∂θ/∂λ
    });
    return 0;
  }
  const Data& d;
  const Linearization& l;
};

// (L, λ) in radians on the sphere: L in [−π/2, π/2], λ in (−π, π] (LM runs unconstrained; the
// model is the same at (π − L, λ + π)).
Eigen::Vector2d normalized(Eigen::Vector2d x) {
  double lat = std::remainder(x(0), 2 * kPi), lon = x(1);
  if (lat > kPi / 2) {
    lat = kPi - lat;
    lon += kPi;
  } else if (lat < -kPi / 2) {
    lat = -kPi - lat;
    lon += kPi;
  }
  lon = std::remainder(lon, 2 * kPi);
  if (lon <= -kPi) lon += 2 * kPi;
  return {lat, lon};
}

Vec3 unit_vector(double lat_rad, double lon_rad) {
  return {std::cos(lat_rad) * std::cos(lon_rad), std::cos(lat_rad) * std::sin(lon_rad), std::sin(lat_rad)};
}

// One root: re-linearize at the estimate, LM from it, until the estimate stays put.
PositionRoot fit_root(const Data& d, Eigen::Vector2d x, const Site& prior, const PositionOptions& o,
                      Linearization* last_lin = nullptr) {
  PositionRoot root;
  PositionSummary& s = root.summary;
  s.sightings = static_cast<int>(d.utc.size());
  const auto finish_site = [&] {
    x = normalized(x);
    root.lat_deg = rad2deg(x(0));
    root.lon_deg = rad2deg(x(1));
    root.prior_distance_km = great_circle_km(root.lat_deg, root.lon_deg, prior.lat_deg, prior.lon_deg);
  };
  const auto stop = [&](PositionTermination t, std::string message) {
    s.termination = t;
    s.message = std::move(message);
    finish_site();
    return root;
  };
  if (d.utc.size() < 2)
    return stop(PositionTermination::TooFewSightings,
                fmt::format("{} sighting(s) with a positive weight; Eq. 17 has 2 unknowns", d.utc.size()));

  Linearization lin;
  Outcome outcome{"NotStarted", false, "the iteration did not start"};
  bool settled = false;
  using S = Eigen::LevenbergMarquardtSpace::Status;
  while (s.relinearizations < o.max_relinearizations) {
    x = normalized(x);
    lin = linearize(d, rad2deg(x(0)), rad2deg(x(1)), prior.height_m, o);
    ++s.relinearizations;
    Eq17Residuals f(d, lin);
    Eigen::LevenbergMarquardt<Eq17Residuals> lm(f);
    lm.setXtol(o.parameter_tolerance);
    lm.setFtol(o.function_tolerance);
    lm.setGtol(0);
    lm.setMaxfev(std::max(1, o.max_evaluations - s.evaluations));
    const Eigen::Vector2d before = x;
    Eigen::VectorXd xv = x;
    S status = lm.minimizeInit(xv);
    if (s.relinearizations == 1) s.initial_cost_deg2 = 0.5 * lm.fvec().squaredNorm() * rad2deg(1) * rad2deg(1);
    if (status == S::NotStarted) {
      status = S::Running;
      while (status == S::Running && s.iterations + lm.njev() < o.max_iterations)
        status = lm.minimizeOneStep(xv);
    }
    s.iterations += static_cast<int>(lm.njev());
    s.evaluations += static_cast<int>(lm.nfev());
    outcome = termination_of(status);
    x = xv;
    if (!outcome.converged) break;
    // The move on the sphere in metres.
    const double moved_m = vec3::norm(vec3::sub(unit_vector(x(0), x(1)), unit_vector(before(0), before(1)))) *
                           kEarthMeanRadiusKm * 1e3;
    if (moved_m < o.site_tolerance_m || o.ephemeris) {  // a given ephemeris: nothing to re-linearize
      settled = true;
      break;
    }
  }
  s.solver_status = outcome.name;
  if (last_lin) *last_lin = lin;

  // Cost, conditioning and the covariance at the end (the last linearization: the exact sun at a
  // site within site_tolerance_m of the estimate).
  Eq17Residuals f(d, lin);
  const auto n = static_cast<Eigen::Index>(d.utc.size());
  Eigen::VectorXd r(n);
  Eigen::MatrixXd J(n, 2);
  f(x, r);
  f.df(x, J);
  const double rss = r.squaredNorm();
  s.final_cost_deg2 = 0.5 * rss * rad2deg(1) * rad2deg(1);
  s.residual_rms_deg = rad2deg(std::sqrt(rss / d.weight_sum));
  // Metric columns: north = R·dL, east = R·cos L·dλ.
  const double cos_lat = std::cos(x(0));
  Eigen::MatrixXd Jm = J;
  Jm.col(1) /= std::max(cos_lat, 1e-12);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(Jm, Eigen::ComputeThinV);
  const Eigen::Vector2d sigma = svd.singularValues();
  s.singular_ratio = sigma(0) > 0 ? sigma(1) / sigma(0) : 0;
  s.rank = sigma(0) > 0 ? (s.singular_ratio >= o.min_singular_ratio ? 2 : 1) : 0;
  if (s.rank == 2 && d.utc.size() > 2) {
    // s² per unit weight: RSS/(N − 2) with N the used sightings (weights scale as given).
    const double s2 = rss / static_cast<double>(d.utc.size() - 2);
    const Eigen::Matrix2d V = svd.matrixV();
    const Eigen::Matrix2d cov = V * sigma.cwiseAbs2().cwiseInverse().asDiagonal() * V.transpose() * s2;
    root.sd_north_km = std::sqrt(cov(0, 0)) * kEarthMeanRadiusKm;
    root.sd_east_km = std::sqrt(cov(1, 1)) * kEarthMeanRadiusKm;
    root.sd_major_km = std::sqrt(s2) / sigma(1) * kEarthMeanRadiusKm;
    root.corr_north_east = cov(0, 1) / std::sqrt(cov(0, 0) * cov(1, 1));
  }
  if (s.rank < 2)
    return stop(PositionTermination::RankDeficient,
                fmt::format("the window cannot fix both coordinates (σ_min/σ_max = {:.1e} < {:.1e}): "
                            "the sun's azimuth hardly changes over it; observe longer",
                            s.singular_ratio, o.min_singular_ratio));
  if (!outcome.converged)
    return stop(PositionTermination::NoConvergence,
                fmt::format("{} ({} iterations, {} evaluations allowed; solver status {})",
                            outcome.message, o.max_iterations, o.max_evaluations, outcome.name));
  if (!settled)
    return stop(PositionTermination::NoConvergence,
                fmt::format("the estimate still moved after {} re-linearizations of the sun",
                            o.max_relinearizations));
  return stop(PositionTermination::Converged, outcome.message);
}

}  // namespace

void check_position_options(const PositionOptions& o) {
  const auto bad = [](const std::string& what) { throw std::invalid_argument("positioning: " + what); };
  if (!(o.max_iterations >= 1 && o.max_iterations <= 100000)) bad(fmt::format("max_iterations {} is outside [1, 100000]", o.max_iterations));
  if (!(o.max_evaluations >= 1 && o.max_evaluations <= 100000)) bad(fmt::format("max_evaluations {} is outside [1, 100000]", o.max_evaluations));
  if (!(o.max_relinearizations >= 1 && o.max_relinearizations <= 100)) bad(fmt::format("max_relinearizations {} is outside [1, 100]", o.max_relinearizations));
  if (!(o.site_tolerance_m > 0 && o.site_tolerance_m <= 1e5)) bad(fmt::format("site_tolerance_m {} is outside (0, 1e5] m", o.site_tolerance_m));
  if (!(o.function_tolerance >= 0 && o.function_tolerance < 1)) bad(fmt::format("function_tolerance {} is outside [0, 1)", o.function_tolerance));
  if (!(o.parameter_tolerance >= 0 && o.parameter_tolerance < 1)) bad(fmt::format("parameter_tolerance {} is outside [0, 1)", o.parameter_tolerance));
  if (!(o.min_singular_ratio >= 0 && o.min_singular_ratio < 1)) bad(fmt::format("min_singular_ratio {} is outside [0, 1)", o.min_singular_ratio));
  if (!(o.track_node_spacing_s >= 1 && o.track_node_spacing_s <= 7200)) bad(fmt::format("track_node_spacing_s {} is outside [1, 7200] s", o.track_node_spacing_s));
}

std::string_view position_termination_name(PositionTermination t) {
  switch (t) {
    case PositionTermination::Converged: return "converged";
    case PositionTermination::NoConvergence: return "no_convergence";
    case PositionTermination::RankDeficient: return "rank_deficient";
    case PositionTermination::TooFewSightings: return "too_few_sightings";
  }
  return "?";
}

std::string PositionSummary::brief_report() const {
  if (solver_status.empty())
    return fmt::format("{}: not fitted, {} sightings; {}", position_termination_name(termination),
                       sightings, message);
  return fmt::format("{}: {} iterations, {} evaluations, {} re-linearizations, {} sightings, cost "
                     "{:.6g} -> {:.6g} deg^2, rms {:.3g} deg, rank {}, sigma ratio {:.3g}; {}",
                     position_termination_name(termination), iterations, evaluations,
                     relinearizations, sightings, initial_cost_deg2, final_cost_deg2,
                     residual_rms_deg, rank, singular_ratio, message);
}

ZenithModel zenith_model(double dec_rad, double gha_rad, double lat_rad, double lon_rad) {
  const double sL = std::sin(lat_rad), cL = std::cos(lat_rad);
  const double sd = std::sin(dec_rad), cd = std::cos(dec_rad);
  const double H = gha_rad + lon_rad, cH = std::cos(H), sH = std::sin(H);
  const double c = std::clamp(sL * sd + cL * cd * cH, -1.0, 1.0);
  ZenithModel m;
  m.zenith_rad = std::acos(c);
  const double s = std::sqrt((1 - c) * (1 + c));  // sin θ_S
  if (s > 0) {
    // dθ = −dc / sin θ
    m.d_lat = -(cL * sd - sL * cd * cH) / s;
    m.d_lon = cL * cd * sH / s;
  }
  return m;
}

TwoSightingError two_sighting_error(double eps_a, double eps_b, double az_a, double az_b) {
  for (const double e : {eps_a, eps_b})
    if (!(e >= 0 && std::isfinite(e)))
      throw std::invalid_argument(fmt::format("Eq. 15: zenith-angle error {} is not a finite number ≥ 0", e));
  for (const double a : {az_a, az_b})
    if (!std::isfinite(a)) throw std::invalid_argument(fmt::format("Eq. 15: azimuth {} is not finite", a));
  const double s = std::abs(std::sin(deg2rad(std::remainder(az_a - az_b, 180.0))));  // 0 at 180°
  TwoSightingError e;
  e.angle_deg = s > 0 ? std::hypot(eps_a, eps_b) / s : std::numeric_limits<double>::infinity();
  e.km = e.angle_deg * kKmPerDegree;
  return e;
}

double great_circle_km(double lat1, double lon1, double lat2, double lon2) {
  const double p1 = deg2rad(lat1), p2 = deg2rad(lat2);
  const double a = std::pow(std::sin((p2 - p1) / 2), 2) +
                   std::cos(p1) * std::cos(p2) * std::pow(std::sin(deg2rad(lon2 - lon1) / 2), 2);
  return 2 * kEarthMeanRadiusKm * std::asin(std::min(1.0, std::sqrt(a)));
}

PositionFix fix_position(std::span<const ZenithSighting> sightings, const Site& prior,
                         const PositionOptions& o) {
  check_position_options(o);
  if (const auto problem = site_problem(prior)) throw std::invalid_argument("positioning: prior " + *problem);
  Data d;
  for (std::size_t k = 0; k < sightings.size(); ++k) {
    const ZenithSighting& z = sightings[k];
    if (!(z.zenith_deg >= 0 && z.zenith_deg <= 180))
      throw std::invalid_argument(fmt::format("positioning: sighting {}: zenith angle {} is outside [0, 180] °", k, z.zenith_deg));
    if (!(z.weight >= 0 && std::isfinite(z.weight)))
      throw std::invalid_argument(fmt::format("positioning: sighting {}: weight {} is not a finite number ≥ 0", k, z.weight));
    check_sun_inputs(z.utc, prior, o.sun);
    if (z.weight == 0) continue;
    d.utc.push_back(z.utc);
    d.zenith_rad.push_back(deg2rad(z.zenith_deg));
    d.sqrt_w.push_back(std::sqrt(z.weight));
    d.weight_sum += z.weight;
  }
  if (!d.utc.empty()) {
    d.first = *std::min_element(d.utc.begin(), d.utc.end());
    d.last = *std::max_element(d.utc.begin(), d.utc.end());
  }

  PositionFix fix;
  const Eigen::Vector2d start(deg2rad(prior.lat_deg), deg2rad(prior.lon_deg));
  Linearization lin;
  PositionRoot first = fit_root(d, start, prior, o, &lin);
  if (!o.second_root || d.utc.size() < 2) {
    fix.chosen = std::move(first);
    if (o.second_root) fix.alternative_note = "no fit";
    return fix;
  }
  // The mirror start: the first root reflected about the great circle through the first and last
  // sub-solar points (latitude δ, longitude −GHA), in whose plane the equal-altitude circles'
  // centres lie.
  std::size_t i_first = 0, i_last = 0;
  for (std::size_t k = 0; k < d.utc.size(); ++k) {
    if (d.utc[k] < d.utc[i_first]) i_first = k;
    if (d.utc[i_last] < d.utc[k]) i_last = k;
  }
  // The sub-solar point (δ, −GHA) as a unit vector: (cos δ·cos GHA, −cos δ·sin GHA, sin δ).
  const auto sub_solar = [&](std::size_t k) {
    return Vec3{lin.cos_dec[k] * lin.cos_gha[k], -lin.cos_dec[k] * lin.sin_gha[k], lin.sin_dec[k]};
  };
  const Vec3 a = sub_solar(i_first), b = sub_solar(i_last);
  const Vec3 axis = vec3::cross(a, b);
  if (!(vec3::norm(axis) > 1e-9)) {
    fix.chosen = std::move(first);
    fix.alternative_note = "the sun's ground track is a point over the window: no mirror start";
    return fix;
  }
  const Vec3 nrm = vec3::unit(axis);
  const Vec3 p = unit_vector(deg2rad(first.lat_deg), deg2rad(first.lon_deg));
  const Vec3 m = vec3::sub(p, vec3::mul(nrm, 2 * vec3::dot(p, nrm)));
  const Eigen::Vector2d mirror(std::asin(std::clamp(m[2], -1.0, 1.0)), std::atan2(m[1], m[0]));
  PositionRoot second = fit_root(d, mirror, prior, o);
  const bool distinct = great_circle_km(first.lat_deg, first.lon_deg, second.lat_deg, second.lon_deg) > 1.0;
  // The chosen root: usable before not, then the nearer the prior.
  const auto better = [](const PositionRoot& u, const PositionRoot& v) {
    if (u.summary.usable() != v.summary.usable()) return u.summary.usable();
    return u.prior_distance_km < v.prior_distance_km;
  };
  if (!distinct) {
    fix.chosen = better(second, first) ? std::move(second) : std::move(first);
    fix.alternative_note = "the mirror start converged onto the same root";
    return fix;
  }
  if (better(second, first)) std::swap(first, second);
  fix.chosen = std::move(first);
  fix.alternative = std::move(second);
  return fix;
}

Location locate(std::span<const SunSighting> sightings, const Site& prior, const PositionOptions& o) {
  std::vector<ZenithSighting> z(sightings.size());
  Location loc;
  loc.samples.resize(sightings.size());
  for (std::size_t k = 0; k < sightings.size(); ++k) {
    const SunSighting& s = sightings[k];
    const double len = vec3::norm(s.sun_camera);
    if (!(len > 0 && std::isfinite(len)))
      throw std::invalid_argument(fmt::format("locate: sighting {}: the sun vector ({}, {}, {}) is zero or not finite",
                                              k, s.sun_camera[0], s.sun_camera[1], s.sun_camera[2]));
    LocateSample& out = loc.samples[k];
    out.utc = s.utc;
    out.weight = s.weight;
    // Eq. 16: θ_S = arccos(s_3) of the unit vector; atan2 for accuracy near the zenith.
    out.zenith_deg = rad2deg(std::atan2(std::hypot(s.sun_camera[0], s.sun_camera[1]), s.sun_camera[2]));
    out.alpha_s_deg = wrap_heading_deg(-rad2deg(std::atan2(s.sun_camera[1], s.sun_camera[0])));
    out.zenith_fix_deg = out.residual_deg = out.beta_deg = out.heading_deg =
        std::numeric_limits<double>::quiet_NaN();
    z[k] = {s.utc, out.zenith_deg, s.weight};
  }
  loc.fix = fix_position(z, prior, o);
  if (!loc.fix.usable() || sightings.empty()) return loc;
  UtcTime first = sightings[0].utc, last = sightings[0].utc;
  for (const SunSighting& s : sightings) {
    first = std::min(first, s.utc);
    last = std::max(last, s.utc);
  }
  const SunTrack track(first, last, loc.fix.chosen.site(prior.height_m), o.sun, o.track_node_spacing_s);
  double c = 0, sn = 0, wsum = 0;
  for (std::size_t k = 0; k < sightings.size(); ++k) {
    LocateSample& out = loc.samples[k];
    const SunPosition sun = track.at(out.utc);
    out.zenith_fix_deg = sun.zenith_deg;
    out.residual_deg = out.zenith_deg - sun.zenith_deg;
    out.beta_deg = sun.azimuth_deg;
    // Eq. 18, ψ = β − α_S with α_S clockwise = β + atan2(s_y, s_x): camera_heading_deg.
    out.heading_deg = camera_heading_deg(sun.azimuth_deg, -out.alpha_s_deg);
    if (out.weight > 0) {
      c += out.weight * std::cos(deg2rad(out.heading_deg));
      sn += out.weight * std::sin(deg2rad(out.heading_deg));
      wsum += out.weight;
    }
  }
  if (wsum > 0) {
    loc.heading_mean_deg = wrap_heading_deg(rad2deg(std::atan2(sn, c)));
    double ss = 0;
    for (const LocateSample& s : loc.samples)
      if (s.weight > 0) ss += s.weight * std::pow(heading_difference_deg(s.heading_deg, loc.heading_mean_deg), 2);
    loc.heading_sd_deg = std::sqrt(ss / wsum);
  }
  return loc;
}

}  // namespace polrig
