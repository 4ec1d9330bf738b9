#include "polrig/study/positioning.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Dense>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "polrig/random.h"
#include "polrig/units.h"
#include "polrig/statistics.h"

namespace polrig {

namespace {

// random.h streams of a trial: (seed, trial, stream, sample).
constexpr std::uint64_t kNoiseStream = 0, kTiltStream = 1, kPriorStream = 2;

std::vector<double> default_times() {
  std::vector<double> t(3601);
  for (std::size_t k = 0; k < t.size(); ++k) t[k] = static_cast<double>(k);
  return t;
}

std::vector<double> default_windows(double span) {
  std::vector<double> w;
  for (const double f : {1.0 / 60, 1.0 / 30, 1.0 / 12, 1.0 / 6, 1.0 / 3, 1.0 / 2, 1.0}) w.push_back(span * f);
  return w;
}

std::size_t sightings_in(const std::vector<double>& times, double window_s) {
  return static_cast<std::size_t>(std::upper_bound(times.begin(), times.end(), times.front() + window_s * (1 + 1e-12)) - times.begin());
}

// The linearized least-squares error of a cell (km): √trace(P·Σ·Pᵀ).
double linear_rms_km(const std::vector<double>& times, const std::vector<ZenithModel>& model,
                     const std::vector<double>& beta_rad, double lat_rad, std::size_t n, double sigma_rad,
                     double tilt_rad, double correlation_s) {
  const auto N = static_cast<Eigen::Index>(n);
  Eigen::MatrixXd J(N, 2);  // rad per km, north and east
  for (Eigen::Index k = 0; k < N; ++k) {
    J(k, 0) = model[static_cast<std::size_t>(k)].d_lat / kEarthMeanRadiusKm;
    J(k, 1) = model[static_cast<std::size_t>(k)].d_lon / (kEarthMeanRadiusKm * std::cos(lat_rad));
  }
  const Eigen::Matrix2d JtJ = J.transpose() * J;
  if (!(std::abs(JtJ.determinant()) > 0)) return std::numeric_limits<double>::infinity();
  const Eigen::MatrixXd P = JtJ.inverse() * J.transpose();  // 2 × N
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  if (sigma_rad > 0) {
    if (correlation_s > 0) {
      // P·Σ·Pᵀ with Σ_kl = σ²·exp(−|t_k − t_l|/τ), row by row.
      Eigen::VectorXd row(N);
      for (Eigen::Index k = 0; k < N; ++k) {
        for (Eigen::Index l = 0; l < N; ++l)
          row(l) = std::exp(-std::abs(times[static_cast<std::size_t>(k)] - times[static_cast<std::size_t>(l)]) / correlation_s);
        cov += sigma_rad * sigma_rad * (P.col(k) * (P * row).transpose());
      }
    } else {
      cov += sigma_rad * sigma_rad * P * P.transpose();
    }
  }
  if (tilt_rad > 0) {
    // δθ_k ≈ −τ·cos(β_k − A_t) with A_t uniform: Σ_kl = τ²/2·cos(β_k − β_l) = τ²/2·(c·cᵀ + s·sᵀ).
    Eigen::VectorXd c(N), s(N);
    for (Eigen::Index k = 0; k < N; ++k) {
      c(k) = std::cos(beta_rad[static_cast<std::size_t>(k)]);
      s(k) = std::sin(beta_rad[static_cast<std::size_t>(k)]);
    }
    const Eigen::Vector2d pc = P * c, ps = P * s;
    cov += tilt_rad * tilt_rad / 2 * (pc * pc.transpose() + ps * ps.transpose());
  }
  return std::sqrt(cov.trace());
}

// The site `km` from `from` towards bearing `bearing_rad` (clockwise from north), on the sphere.
Site moved(const Site& from, double km, double bearing_rad) {
  const double d = km / kEarthMeanRadiusKm, p1 = deg2rad(from.lat_deg);
  const double p2 = std::asin(std::sin(p1) * std::cos(d) + std::cos(p1) * std::sin(d) * std::cos(bearing_rad));
  const double dl = std::atan2(std::sin(bearing_rad) * std::sin(d) * std::cos(p1), std::cos(d) - std::sin(p1) * std::sin(p2));
  return {rad2deg(p2), std::remainder(from.lon_deg + rad2deg(dl), 360.0), from.height_m};
}

}  // namespace

void check_positioning_study_settings(const PositioningStudySettings& s,
                                      const std::function<std::string(std::string_view)>& name) {
  const auto bad = [&](std::string_view field, const std::string& what) {
    throw std::invalid_argument(fmt::format("{}: {}", name(field), what));
  };
  const auto range = [&](std::string_view field, double v, double lo, double hi, const char* unit) {
    if (!(v >= lo && v <= hi)) bad(field, fmt::format("expected a finite number in [{}, {}] {}, got {}", lo, hi, unit, v));
  };
  if (!(s.trials >= 1 && s.trials <= 1000000)) bad("trials", fmt::format("expected an integer in [1, 1000000], got {}", s.trials));
  if (const auto p = site_problem(s.site)) bad("site", *p);
  check_sun_inputs(s.first, s.site, s.sun);
  const std::vector<double> times = s.times_s.empty() ? default_times() : s.times_s;
  for (std::size_t k = 0; k < times.size(); ++k) {
    range("times_s", times[k], 0, 1e7, "s");
    if (k > 0 && !(times[k] > times[k - 1]))
      bad("times_s", fmt::format("sample times must rise: {} s after {} s (sample {})", times[k], times[k - 1], k));
  }
  if (times.size() < 2) bad("times_s", fmt::format("{} sample time(s): a fix needs at least two", times.size()));
  check_sun_inputs(s.first.plus_seconds(times.back()), s.site, s.sun);
  const double span = times.back() - times.front();
  for (const double w : s.windows_s) {
    range("windows_s", w, 0, span, "s (the rig's stops span that)");
    if (sightings_in(times, w) < 2) bad("windows_s", fmt::format("a window of {} s holds fewer than two sightings", w));
  }
  if (s.noise_sd_deg.empty()) bad("noise_sd_deg", "no values");
  if (s.tilt_deg.empty()) bad("tilt_deg", "no values");
  for (const double v : s.noise_sd_deg) range("noise_sd_deg", v, 0, 10, "°");
  for (const double v : s.tilt_deg) range("tilt_deg", v, 0, 10, "°");
  range("baseline_noise_sd_deg", s.baseline_noise_sd_deg, 0, 10, "°");
  range("baseline_tilt_deg", s.baseline_tilt_deg, 0, 10, "°");
  range("correlation_s", s.correlation_s, 0, 1e5, "s");
  range("prior_offset_km", s.prior_offset_km, 0, 2000, "km");
}

PositioningStudy positioning_study(const PositioningStudySettings& settings, const Progress& progress) {
  check_positioning_study_settings(settings);
  PositioningStudy study;
  PositioningStudySettings& s = study.settings;
  s = settings;
  if (s.times_s.empty()) s.times_s = default_times();
  const std::vector<double>& times = s.times_s;
  const double span = times.back() - times.front();
  if (s.windows_s.empty()) s.windows_s = default_windows(span);
  const std::size_t n_all = times.size();

  // The truth: the full ephemeris at every sample (what the sky source simulates).
  std::vector<Vec3> sun_enu(n_all);
  std::vector<double> beta_rad(n_all);
  std::vector<ZenithModel> model(n_all);
  const double lat_rad = deg2rad(s.site.lat_deg), lon_rad = deg2rad(s.site.lon_deg);
  tbb::parallel_for(std::size_t{0}, n_all, [&](std::size_t k) {
    const SunPosition p = sun_position(s.first.plus_seconds(times[k]), s.site, s.sun);
    sun_enu[k] = sun_direction_enu(p);
    beta_rad[k] = deg2rad(p.azimuth_deg);
    model[k] = zenith_model(deg2rad(p.declination_deg), deg2rad(p.gha_deg), lat_rad, lon_rad);
  });

  const auto add_cell = [&](const char* factor, double window, double sigma, double tilt) {
    PositioningCell c;
    c.index = static_cast<int>(study.cells.size());
    c.factor = factor;
    c.window_s = window;
    c.noise_sd_deg = sigma;
    c.tilt_deg = tilt;
    const std::size_t n = sightings_in(times, window);
    c.sightings = static_cast<int>(n);
    c.delta_beta_deg = rad2deg(std::remainder(beta_rad[n - 1] - beta_rad[0], 2 * M_PI));
    c.eq15_km = two_sighting_error(std::hypot(sigma, tilt), std::hypot(sigma, tilt),
                                   rad2deg(beta_rad[0]), rad2deg(beta_rad[n - 1])).km;
    c.linear_rms_km = linear_rms_km(times, model, beta_rad, lat_rad, n, deg2rad(sigma), deg2rad(tilt), s.correlation_s);
    // M′: the window's noise-free, level zenith angles fitted from the truth with the mirror search.
    std::vector<ZenithSighting> clean(n);
    for (std::size_t k = 0; k < n; ++k)
      clean[k] = {s.first.plus_seconds(times[k]), rad2deg(std::acos(std::clamp(sun_enu[k][2], -1.0, 1.0))), 1.0};
    PositionOptions mirror;
    mirror.sun = s.sun;
    mirror.second_root = true;
    const PositionFix both = fix_position(clean, s.site, mirror);
    if (both.alternative && both.alternative->summary.termination == PositionTermination::Converged) {
      c.mirror_lat_deg = both.alternative->lat_deg;
      c.mirror_lon_deg = both.alternative->lon_deg;
      c.mirror_km = great_circle_km(c.mirror_lat_deg, c.mirror_lon_deg, s.site.lat_deg, s.site.lon_deg);
    }
    study.cells.push_back(c);
  };
  for (const double w : s.windows_s) add_cell("window", w, s.baseline_noise_sd_deg, s.baseline_tilt_deg);
  for (const double v : s.noise_sd_deg) add_cell("noise", span, v, s.baseline_tilt_deg);
  for (const double v : s.tilt_deg) add_cell("tilt", span, s.baseline_noise_sd_deg, v);

  const std::size_t trials = static_cast<std::size_t>(s.trials);
  study.trials.resize(study.cells.size() * trials);
  PositionOptions options;
  options.sun = s.sun;
  options.second_root = s.second_root;
  progress.begin("study positioning: fits", static_cast<long long>(study.trials.size()));
  tbb::parallel_for(std::size_t{0}, study.trials.size(), [&](std::size_t i) {
    const PositioningCell& c = study.cells[i / trials];
    const std::size_t trial = i % trials;
    PositioningTrial& out = study.trials[i];
    out.cell = c.index;
    out.trial = static_cast<int>(trial);
    const auto n = static_cast<std::size_t>(c.sightings);
    // The tilted axis: τ towards azimuth A_t (clockwise from north) in ENU.
    out.tilt_azimuth_deg = 360 * uniform_unit(s.seed, trial, kTiltStream, 0);
    const double tau = deg2rad(c.tilt_deg), At = deg2rad(out.tilt_azimuth_deg);
    const Vec3 axis{std::sin(tau) * std::sin(At), std::sin(tau) * std::cos(At), std::cos(tau)};
    const double sigma = c.noise_sd_deg;
    std::vector<ZenithSighting> z(n);
    double e = 0;
    for (std::size_t k = 0; k < n; ++k) {
      const double nk = standard_normal(s.seed, trial, kNoiseStream, k);
      if (k == 0 || s.correlation_s <= 0) {
        e = sigma * nk;
      } else {
        const double rho = std::exp(-(times[k] - times[k - 1]) / s.correlation_s);
        e = rho * e + sigma * std::sqrt((1 - rho) * (1 + rho)) * nk;
      }
      const double theta = rad2deg(std::acos(std::clamp(vec3::dot(sun_enu[k], axis), -1.0, 1.0)));
      z[k] = {s.first.plus_seconds(times[k]), std::clamp(theta + e, 0.0, 180.0), 1.0};
    }
    const Site prior = moved(s.site, s.prior_offset_km, 2 * M_PI * uniform_unit(s.seed, trial, kPriorStream, 0));
    out.prior_lat_deg = prior.lat_deg;
    out.prior_lon_deg = prior.lon_deg;
    const PositionFix fix = fix_position(z, prior, options);
    const PositionRoot& r = fix.chosen;
    out.lat_deg = r.lat_deg;
    out.lon_deg = r.lon_deg;
    out.error_km = great_circle_km(r.lat_deg, r.lon_deg, s.site.lat_deg, s.site.lon_deg);
    const double km_per_rad = kEarthMeanRadiusKm;
    out.north_km = deg2rad(r.lat_deg - s.site.lat_deg) * km_per_rad;
    out.east_km = deg2rad(std::remainder(r.lon_deg - s.site.lon_deg, 360.0)) * km_per_rad * std::cos(lat_rad);
    out.termination = r.summary.termination;
    out.iterations = r.summary.iterations;
    out.residual_rms_deg = r.summary.residual_rms_deg;
    out.sd_major_km = r.sd_major_km;
    progress.advance();
  });
  progress.finish();

  for (const PositioningCell& c : study.cells) {
    PositioningStats st;
    st.cell = c.index;
    st.trials = s.trials;
    std::vector<double> err;
    double ss = 0, sum = 0, north = 0, east = 0;
    for (std::size_t t = 0; t < trials; ++t) {
      const PositioningTrial& r = study.trials[static_cast<std::size_t>(c.index) * trials + t];
      if (r.termination != PositionTermination::Converged) continue;
      err.push_back(r.error_km);
      ss += r.error_km * r.error_km;
      sum += r.error_km;
      north += r.north_km;
      east += r.east_km;
      if (std::isfinite(c.mirror_km) &&
          great_circle_km(r.lat_deg, r.lon_deg, c.mirror_lat_deg, c.mirror_lon_deg) < r.error_km)
        ++st.wrong_root;
    }
    st.converged = static_cast<int>(err.size());
    if (!err.empty()) {
      const double m = static_cast<double>(err.size());
      st.rms_km = std::sqrt(ss / m);
      st.mean_km = sum / m;
      std::sort(err.begin(), err.end());
      st.p50_km = quantile_of_sorted(err, 0.5);
      st.p95_km = quantile_of_sorted(err, 0.95);
      st.max_km = err.back();
      st.mean_north_km = north / m;
      st.mean_east_km = east / m;
    }
    study.stats.push_back(st);
  }
  return study;
}

}  // namespace polrig
