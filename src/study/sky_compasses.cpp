#include "polrig/study/sky_compasses.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "polrig/device/dofp_camera.h"
#include "polrig/device/four_camera.h"
#include "polrig/device/unit_array.h"
#include "polrig/compass/heading.h"
#include "polrig/random.h"
#include "polrig/sky/vector_rt_sky.h"
#include "polrig/statistics.h"
#include "polrig/units.h"

namespace polrig {

// Named, not anonymous: the library is built in unity files.
namespace sky_compass_detail {

using namespace vec3;

constexpr double kSunAzimuthDeg = 180;                      // [C] the sun due south
constexpr double kKmPerDeg = 6371.0 * std::numbers::pi / 180;  // 111.195 km of arc per degree

std::vector<Vec3> camera_grid(const CameraIntrinsics& camera, int width, int height, int cols,
                              std::vector<double>& x_px, std::vector<double>& y_px) {
  const int rows = std::max(1, static_cast<int>(std::lround(static_cast<double>(cols) * height / width)));
  std::vector<Vec3> views;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      const double x = (c + 0.5) * width / cols, y = (r + 0.5) * height / rows;
      const PointView p = point_view(x, y, camera);  // Eq. 9, compass/orientation.h's own mapping
      x_px.push_back(x);
      y_px.push_back(y);
      views.push_back({std::sin(p.gamma_rad) * std::cos(p.alpha_rad), std::sin(p.gamma_rad) * std::sin(p.alpha_rad),
                       std::cos(p.gamma_rad)});
    }
  return views;
}

// What the compass sees of one sky: per view its E-vector in b (zero where the sky gives none or
// the view is below the horizon) and its DoP.
struct SkySeen {
  std::vector<Vec3> e_b;
  std::vector<double> dop;
};

SkySeen look(const SkyCompass& compass, const SunSky& sky, const Axes3& C_bn) {
  SkySeen seen;
  for (const Vec3& v_b : compass.views_b) {
    const Vec3 v_n = vec3::apply(C_bn, v_b);
    if (v_n[2] <= 0) {
      seen.e_b.push_back({0, 0, 0});
      seen.dop.push_back(NAN);
      continue;
    }
    const SkyRay ray = sky.along(v_n);
    seen.e_b.push_back(apply_transpose(C_bn, ray.e_vector));
    seen.dop.push_back(ray.dop);
  }
  return seen;
}

// A reading's angle 2ψ and DoP d with Gaussian noise σ on q = d·cos 2ψ and u = d·sin 2ψ: (ψ′, d′).
struct NoisyReading {
  double psi_rad, dop;
};
NoisyReading add_noise(double psi_rad, double dop, double sd, std::uint64_t seed, int trial, std::size_t view) {
  if (sd == 0 || trial < 0) return {psi_rad, dop};
  const double q = dop * std::cos(2 * psi_rad) + sd * standard_normal(seed, static_cast<std::uint64_t>(trial), 0, view);
  const double u = dop * std::sin(2 * psi_rad) + sd * standard_normal(seed, static_cast<std::uint64_t>(trial), 1, view);
  return {0.5 * std::atan2(u, q), std::hypot(q, u)};
}

// One reading's outcome: the body sun (Eigenvector, UnitPair) or the heading (ZenithEVector).
struct SkyEstimate {
  std::string status;
  bool ok = false;
  Vec3 s_b{};
  double heading_deg = NAN;
};

OrientationSettings orientation_for(SkyMethod m, const SkyStudySettings& s, const Vec3& prior) {
  OrientationSettings o;
  o.prior_sun = prior;  // the root near the truth: the study measures the bias, not the ambiguity
  if (m == SkyMethod::DopWeighted || m == SkyMethod::AllUnits) o.dop_weighting = true;
  if (m == SkyMethod::MinDop) o.min_dop = s.min_dop;
  return o;
}

SkyEstimate from_sun_vector(const SunVectorSolution& sol) {
  return {std::string(sun_vector_status_name(sol.status)), has_sun(sol.status), sol.sun, NAN};
}

SkyEstimate eigenvector_estimate(const SkyCompass& c, const SkySeen& seen, SkyMethod m, const SkyStudySettings& s,
                              const Vec3& prior, std::uint64_t seed, int trial) {
  SkyPoints p;
  p.x_px = c.x_px;
  p.y_px = c.y_px;
  for (std::size_t k = 0; k < seen.e_b.size(); ++k) {
    if (norm(seen.e_b[k]) == 0) {
      p.aop_deg.push_back(NAN);
      p.dop.push_back(NAN);
      continue;
    }
    const NoisyReading n = add_noise(image_plane_aop_rad(c.views_b[k], seen.e_b[k]), seen.dop[k], s.noise_sd, seed, trial, k);
    p.aop_deg.push_back(n.psi_rad / kDeg);
    p.dop.push_back(n.dop);
  }
  return from_sun_vector(sun_vector_eigen(p, c.camera, orientation_for(m, s, prior)));
}

// The units' readings φ_i in their own frames (compass/unit_array.h's sense), noisy for trial ≥ 0.
std::vector<UnitReading> unit_readings(const SkyCompass& c, const SkySeen& seen, const SkyStudySettings& s,
                                       std::uint64_t seed, int trial) {
  std::vector<UnitReading> r;
  for (std::size_t k = 0; k < c.units.size(); ++k) {
    if (norm(seen.e_b[k]) == 0) {
      r.push_back({NAN, 0});
      continue;
    }
    const double phi = unit_aop_rad(apply_transpose(c.units[k].C_mb, seen.e_b[k]));
    const NoisyReading n = add_noise(phi, seen.dop[k], s.noise_sd, seed, trial, k);
    r.push_back({n.psi_rad, n.dop});
  }
  return r;
}

// The unit views as points of a pinhole camera in b (f = 1000 px, principal point 0): what the
// eigenvector method reads (AllUnits).
SkyEstimate all_units_estimate(const SkyCompass& c, const std::vector<UnitReading>& r, const SkyStudySettings& s,
                            const Vec3& prior) {
  const CameraIntrinsics camera{1000, 0, 0};
  SkyPoints p;
  for (std::size_t k = 0; k < c.units.size(); ++k) {
    const Vec3 v = c.views_b[k];
    p.x_px.push_back(camera.f_c_px * v[0] / v[2]);
    p.y_px.push_back(camera.f_c_px * v[1] / v[2]);
    const bool seen = std::isfinite(r[k].aop_rad) && r[k].dop > 0;
    p.aop_deg.push_back(seen ? image_plane_aop_rad(v, vec3::apply(c.units[k].C_mb, unit_e_vector(r[k].aop_rad))) / kDeg : NAN);
    p.dop.push_back(seen ? r[k].dop : NAN);
  }
  return from_sun_vector(sun_vector_eigen(p, camera, orientation_for(SkyMethod::AllUnits, s, prior)));
}

SkyEstimate unit_estimate(const SkyCompass& c, const SkySeen& seen, SkyMethod m, const SkyStudySettings& s,
                       const Vec3& prior, std::uint64_t seed, int trial) {
  const std::vector<UnitReading> r = unit_readings(c, seen, s, seed, trial);
  if (m == SkyMethod::AllUnits) return all_units_estimate(c, r, s, prior);
  const UnitSun u = sun_from_units(r, c.units);
  return {std::string(unit_sun_status_name(u.status)), u.status == UnitSunStatus::Ok, u.s_b, NAN};
}

SkyEstimate zenith_estimate(const SkySeen& seen, double heading_deg, const Tilt& tilt, const Vec3& s_n,
                         const SkyStudySettings& s, std::uint64_t seed, int trial) {
  if (norm(seen.e_b[0]) == 0) return {"no-e-vector", false, {}, NAN};
  const double theta_b = std::atan2(seen.e_b[0][1], seen.e_b[0][0]);
  const NoisyReading n = add_noise(theta_b, seen.dop[0], s.noise_sd, seed, trial, 0);
  double aop_deg = std::fmod(n.psi_rad / kDeg, 180.0);
  if (aop_deg < 0) aop_deg += 180;
  const HeadingSolution h = solve_heading(s_n, aop_deg, tilt, heading_deg);
  return {std::string(heading_status_name(h.status)), has_heading(h.status), {}, h.heading_deg};
}

struct SkyErrors {
  double heading_deg = NAN, sun_el_deg = NAN;
  bool antisun = false;  // the method's root is the antisun (its sign rule, e.g. Z21's s_z^b > 0)
};
SkyErrors errors_of(const SkyEstimate& e, const Axes3& C_bn, double heading_deg, double sun_el_deg, const Vec3& s_b) {
  if (!e.ok) return {};
  if (std::isfinite(e.heading_deg)) return {heading_difference_deg(e.heading_deg, heading_deg), NAN};
  if (dot(e.s_b, s_b) < 0) return {NAN, NAN, true};
  const Vec3 s_n = vec3::apply(C_bn, unit(e.s_b));
  const double A = std::atan2(s_n[0], s_n[1]) / kDeg;
  return {heading_difference_deg(kSunAzimuthDeg, A), std::asin(std::clamp(s_n[2], -1.0, 1.0)) / kDeg - sun_el_deg};
}

struct SkyAttitude {
  std::size_t sky = 0, sun = 0, tilt = 0, heading = 0;
};

std::vector<SkyCase> sky_cases(const SkyStudySettings& s) {
  std::vector<SkyCase> cases{SkyCase{}};
  for (double tau : s.tau)
    for (double albedo : s.albedo) cases.push_back({SkyKind::VectorRt, tau, albedo});
  return cases;
}

SkyModel model_of(const SkyCase& c, const SkyStudySettings& s) {
  SkyModel m;
  m.P_max = s.P_max;
  if (c.kind == SkyKind::VectorRt) {
    VectorRtSettings rt = s.rt;
    rt.tau_rayleigh = c.tau;
    rt.ground_albedo = c.albedo;
    m.kind = SkyKind::VectorRt;
    m.vector_rt = vector_rt_sky(rt);
  }
  return m;
}

Vec3 sun_enu(double sun_el_deg) {
  const double h = sun_el_deg * kDeg, A = kSunAzimuthDeg * kDeg;
  return {std::cos(h) * std::sin(A), std::cos(h) * std::cos(A), std::sin(h)};
}

void summarize_trials(SkyBiasRow& row, const std::vector<SkyErrors>& noisy) {
  std::vector<double> heading, el;
  for (const SkyErrors& e : noisy) {
    row.antisun += e.antisun;
    if (!std::isfinite(e.heading_deg)) continue;
    heading.push_back(e.heading_deg);
    if (std::isfinite(e.sun_el_deg)) el.push_back(e.sun_el_deg);
  }
  row.trials = static_cast<int>(noisy.size());
  row.solved = static_cast<int>(heading.size());
  if (!heading.empty()) {
    const MeanAndSpread h = mean_and_population_sd(heading);
    row.heading_mean_deg = h.mean;
    row.heading_sd_deg = h.sd;
  }
  if (!el.empty()) {
    const MeanAndSpread e = mean_and_population_sd(el);
    row.sun_el_mean_deg = e.mean;
    row.sun_el_sd_deg = e.sd;
  }
}

// Every method's row for one sky, sun and attitude.
std::vector<SkyBiasRow> attitude_rows(const SkyCompass& c, const SkyStudySettings& s, const SkyCase& sky_case,
                                      const SunSky& sky, double sun_el_deg, double tilt_deg, double rel_heading_deg,
                                      std::uint64_t seed) {
  const double H = wrap_heading_deg(kSunAzimuthDeg + rel_heading_deg);
  const Tilt tilt{tilt_deg, 0};
  const Axes3 C_bn = body_axes_enu(H, tilt_deg, 0);
  const Vec3 s_n = sun_enu(sun_el_deg);
  const Vec3 prior = apply_transpose(C_bn, s_n);
  const SkySeen seen = look(c, sky, C_bn);
  std::vector<SkyBiasRow> rows;
  for (SkyMethod m : sky_methods(c.kind)) {
    const std::uint64_t row_seed = derive_seed(seed, static_cast<std::uint64_t>(m));
    const auto estimate = [&](int trial) {
      switch (c.kind) {
        case SkyCompassKind::ZenithEVector: return zenith_estimate(seen, H, tilt, s_n, s, row_seed, trial);
        case SkyCompassKind::Eigenvector: return eigenvector_estimate(c, seen, m, s, prior, row_seed, trial);
        case SkyCompassKind::UnitPair: return unit_estimate(c, seen, m, s, prior, row_seed, trial);
      }
      return SkyEstimate{};
    };
    SkyBiasRow row;
    row.sky = sky_case;
    row.sun_el_deg = sun_el_deg;
    row.tilt_deg = tilt_deg;
    row.heading_deg = rel_heading_deg;
    row.method = m;
    const SkyEstimate e = estimate(-1);
    const SkyErrors err = errors_of(e, C_bn, H, sun_el_deg, prior);
    row.status = err.antisun ? "antisun" : e.status;
    row.heading_error_deg = err.heading_deg;
    row.sun_el_error_deg = err.sun_el_deg;
    row.position_line_km = kKmPerDeg * err.sun_el_deg;
    std::vector<SkyErrors> noisy;
    for (int t = 0; t < s.trials; ++t) noisy.push_back(errors_of(estimate(t), C_bn, H, sun_el_deg, prior));
    summarize_trials(row, noisy);
    double sum = 0;
    int n = 0;
    for (double d : seen.dop)
      if (std::isfinite(d)) sum += d, ++n;
    row.mean_dop = n > 0 ? sum / n : NAN;
    rows.push_back(std::move(row));
  }
  return rows;
}

// The upper hemisphere's equal-area cells: cos θ = (k + ½)/M, math azimuth (j + ½)·2π/(4M).
std::vector<Vec3> hemisphere_cells(int M) {
  std::vector<Vec3> v;
  for (int k = 0; k < M; ++k) {
    const double mu = (k + 0.5) / M, st = std::sqrt(1 - mu * mu);
    for (int j = 0; j < 4 * M; ++j) {
      const double phi = (j + 0.5) * 2 * std::numbers::pi / (4 * M);
      v.push_back({st * std::cos(phi), st * std::sin(phi), mu});
    }
  }
  return v;
}

SkyDopRow dop_row(const SkyCompass& c, const SkyCase& sky_case, const SunSky& sky, double sun_el_deg,
                  const std::vector<Vec3>& cells) {
  SkyDopRow row;
  row.sky = sky_case;
  row.sun_el_deg = sun_el_deg;
  row.zenith_dop = sky.along({0, 0, 1}).dop;
  row.max_dop_sky = 0;
  for (const Vec3& v : cells) row.max_dop_sky = std::max(row.max_dop_sky, sky.along(v).dop);
  const SkySeen seen = look(c, sky, body_axes_enu(kSunAzimuthDeg, 0, 0));
  double sum = 0, mx = 0;
  int n = 0;
  for (double d : seen.dop)
    if (std::isfinite(d)) sum += d, mx = std::max(mx, d), ++n;
  row.max_dop_compass = n ? mx : NAN;
  row.mean_dop_compass = n ? sum / n : NAN;
  return row;
}

// The E-vector error of the single-scattering sky's prediction against the vector-RT sky, by the
// vector-RT DoP: the angle about v from e_ss to e_rt, axial, in [−90°, 90°).
std::vector<EvectorByDopRow> evector_rows(const SkyCase& sky_case, const SunSky& exact, const SunSky& single,
                                          double sun_el_deg, const std::vector<Vec3>& cells) {
  constexpr int kBins = 20;
  std::array<std::vector<double>, kBins> bins;
  for (const Vec3& v : cells) {
    const SkyRay rt = exact.along(v), ss = single.along(v);
    if (norm(rt.e_vector) == 0 || norm(ss.e_vector) == 0) continue;
    double d = std::atan2(dot(cross(ss.e_vector, rt.e_vector), v), dot(ss.e_vector, rt.e_vector)) / kDeg;
    d = std::fmod(d + 90.0, 180.0);
    d = (d < 0 ? d + 180 : d) - 90;
    bins[std::min(kBins - 1, static_cast<int>(rt.dop * kBins))].push_back(d);
  }
  std::vector<EvectorByDopRow> rows;
  for (int b = 0; b < kBins; ++b) {
    EvectorByDopRow r;
    r.sky = sky_case;
    r.sun_el_deg = sun_el_deg;
    r.dop_lo = static_cast<double>(b) / kBins;
    r.dop_hi = static_cast<double>(b + 1) / kBins;
    r.cells = static_cast<int>(bins[b].size());
    if (!bins[b].empty()) {
      std::vector<double> a;
      double ss = 0;
      for (double d : bins[b]) a.push_back(std::abs(d)), ss += d * d;
      const MeanAndSpread m = mean_and_population_sd(a);
      r.mean_abs_deg = m.mean;
      r.sd_abs_deg = m.sd;
      r.rms_deg = std::sqrt(ss / static_cast<double>(a.size()));
      r.max_abs_deg = *std::max_element(a.begin(), a.end());
    }
    rows.push_back(r);
  }
  return rows;
}

}  // namespace sky_compass_detail

using namespace sky_compass_detail;

std::string_view sky_method_name(SkyMethod m) {
  switch (m) {
    case SkyMethod::Published: return "published";
    case SkyMethod::DopWeighted: return "dop-weighted";
    case SkyMethod::MinDop: return "min-dop";
    case SkyMethod::AllUnits: return "all-units";
  }
  return "?";
}

std::vector<SkyMethod> sky_methods(SkyCompassKind kind) {
  switch (kind) {
    case SkyCompassKind::ZenithEVector: return {SkyMethod::Published};
    case SkyCompassKind::Eigenvector: return {SkyMethod::Published, SkyMethod::DopWeighted, SkyMethod::MinDop};
    case SkyCompassKind::UnitPair: return {SkyMethod::Published, SkyMethod::AllUnits};
  }
  return {};
}

std::string SkyCase::name() const { return std::string(sky_kind_name(kind)); }

SkyCompass sky_compass(const Rig& rig, int grid_cols) {
  if (grid_cols < 4 || grid_cols > 2048)
    throw std::invalid_argument(fmt::format("grid_cols: expected a whole number in [4, 2048], got {}", grid_cols));
  const Instrument& inst = rig.instrument();
  SkyCompass c;
  c.device = rig.device_kind;
  if (inst.has(Instrument::kUnitArray)) {
    c.kind = SkyCompassKind::UnitPair;
    for (const Axes3& C : unit_array_truth(rig.units, rig.seed).nominal) {
      c.units.push_back({C});
      c.views_b.push_back(C[2]);
    }
  } else if (inst.has(Instrument::kCameraArray)) {
    const VirtualCamera vc = virtual_camera(four_camera_truth(rig.four_camera));
    c.kind = SkyCompassKind::Eigenvector;
    c.camera = {vc.f_c, vc.cx, vc.cy};
    c.views_b = camera_grid(c.camera, vc.width, vc.height, grid_cols, c.x_px, c.y_px);
  } else if (inst.has(Instrument::kMosaic)) {
    c.kind = SkyCompassKind::Eigenvector;
    c.camera = {focal_px(rig.camera), rig.camera.width_px / 2.0, rig.camera.height_px / 2.0};
    c.views_b = camera_grid(c.camera, rig.camera.width_px, rig.camera.height_px, grid_cols, c.x_px, c.y_px);
  } else if (inst.has(Instrument::kPairVoltages)) {
    c.kind = SkyCompassKind::ZenithEVector;
    c.views_b = {{0, 0, 1}};
  } else {
    throw std::invalid_argument(fmt::format("device.kind {} reads no sky polrig can study", rig.device_kind));
  }
  return c;
}

void check_sky_study_settings(const SkyStudySettings& s, const std::function<std::string(std::string_view)>& name) {
  const auto range = [&](double v, const char* field, double lo, double hi, const char* unit) {
    if (!(std::isfinite(v) && v >= lo && v <= hi))
      throw std::invalid_argument(fmt::format("{}: expected a finite number in [{}, {}]{}{}, got {}", name(field), lo,
                                              hi, *unit ? " " : "", unit, v));
  };
  const auto list = [&](const std::vector<double>& v, const char* field, double lo, double hi, const char* unit) {
    if (v.empty()) throw std::invalid_argument(fmt::format("{}: expected at least one value", name(field)));
    for (double x : v) range(x, field, lo, hi, unit);
  };
  const auto whole = [&](int v, const char* field, int lo, int hi) {
    if (v < lo || v > hi)
      throw std::invalid_argument(fmt::format("{}: expected a whole number in [{}, {}], got {}", name(field), lo, hi, v));
  };
  for (double t : s.tau)
    if (!(std::isfinite(t) && t > 0 && t <= 10))
      throw std::invalid_argument(fmt::format("{}: expected an optical depth in (0, 10], got {}", name("tau"), t));
  if (s.tau.empty()) throw std::invalid_argument(fmt::format("{}: expected at least one value", name("tau")));
  list(s.albedo, "albedo", 0, 1, "");
  list(s.sun_el_deg, "sun_el_deg", min_sun_elevation_deg(s.rt), 89, "°");
  list(s.tilt_deg, "tilt_deg", 0, 30, "°");
  list(s.heading_deg, "heading_deg", -360, 360, "°");
  range(s.noise_sd, "noise_sd", 0, 1, "");
  whole(s.trials, "trials", 0, 100000);
  range(s.min_dop, "min_dop", 0, 1, "");
  whole(s.grid_cols, "grid_cols", 4, 2048);
  whole(s.mu_cells, "mu_cells", 4, 1000);
  check_vector_rt(s.rt);
  check_sky_model(SkyModel{s.P_max});
}

SkyStudy sky_study(const SkyCompass& compass, const SkyStudySettings& s, const Progress& progress) {
  check_sky_study_settings(s);
  SkyStudy study{s, compass, {}, {}, {}};
  const std::vector<SkyCase> cases = sky_cases(s);
  std::vector<SkyModel> models;
  for (const SkyCase& c : cases) models.push_back(model_of(c, s));

  // The skies first, one (sky, sun) each: every vector-RT solve is made here, in parallel.
  const std::size_t n_sun = s.sun_el_deg.size();
  const std::vector<Vec3> cells = hemisphere_cells(s.mu_cells);
  std::vector<SkyDopRow> dop(cases.size() * n_sun);
  std::vector<std::vector<EvectorByDopRow>> evector(cases.size() * n_sun);
  progress.begin("study sky: skies", static_cast<long long>(dop.size()));
  tbb::parallel_for(std::size_t{0}, dop.size(), [&](std::size_t i) {
    const std::size_t k = i / n_sun, j = i % n_sun;
    const Vec3 s_n = sun_enu(s.sun_el_deg[j]);
    const SunSky sky(s_n, models[k]);
    dop[i] = dop_row(compass, cases[k], sky, s.sun_el_deg[j], cells);
    if (cases[k].kind == SkyKind::VectorRt)
      evector[i] = evector_rows(cases[k], sky, SunSky(s_n, models[0]), s.sun_el_deg[j], cells);
    progress.advance(1);
  });
  progress.finish();
  study.dop = std::move(dop);
  for (auto& rows : evector) study.evector_by_dop.insert(study.evector_by_dop.end(), rows.begin(), rows.end());

  std::vector<SkyAttitude> attitudes;
  for (std::size_t k = 0; k < cases.size(); ++k)
    for (std::size_t j = 0; j < n_sun; ++j)
      for (std::size_t t = 0; t < s.tilt_deg.size(); ++t)
        for (std::size_t h = 0; h < s.heading_deg.size(); ++h) attitudes.push_back({k, j, t, h});
  // The same noise for every sky at one sun and attitude (common random numbers: the skies differ
  // by what they are, not by their draws).
  const std::size_t per_sky = n_sun * s.tilt_deg.size() * s.heading_deg.size();
  std::vector<std::vector<SkyBiasRow>> rows(attitudes.size());
  progress.begin("study sky: compasses", static_cast<long long>(attitudes.size()));
  tbb::parallel_for(std::size_t{0}, attitudes.size(), [&](std::size_t i) {
    const SkyAttitude& a = attitudes[i];
    const SunSky sky(sun_enu(s.sun_el_deg[a.sun]), models[a.sky]);
    rows[i] = attitude_rows(compass, s, cases[a.sky], sky, s.sun_el_deg[a.sun], s.tilt_deg[a.tilt],
                            s.heading_deg[a.heading], derive_seed(s.seed, i % per_sky));
    progress.advance(1);
  });
  progress.finish();
  for (auto& r : rows) study.bias.insert(study.bias.end(), r.begin(), r.end());
  return study;
}

}  // namespace polrig
