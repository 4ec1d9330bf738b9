#include "polrig/study/navigation_study.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <tuple>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "polrig/compass/unit_array.h"
#include "polrig/random.h"
#include "polrig/rig/error.h"
#include "polrig/rig/keys.h"
#include "polrig/source/source.h"
#include "polrig/statistics.h"
#include "polrig/units.h"

namespace polrig {

namespace {

// The stream of derive_seed the tilt directions draw from (study/navigation.cpp's IMU and unit
// streams are 0x494D55 and 0x554E4954): "TILT".
constexpr std::uint64_t kFig17TiltStream = 0x54494C54;

Axes3 axes_of(const Eigen::Matrix3d& C) {
  return {Vec3{C(0, 0), C(1, 0), C(2, 0)}, Vec3{C(0, 1), C(1, 1), C(2, 1)}, Vec3{C(0, 2), C(1, 2), C(2, 2)}};
}

const std::vector<NavigationMode> kModes{NavigationMode::Sins, NavigationMode::Pns, NavigationMode::Integrated};

double type7(const std::vector<double>& sorted, double q) {  // type 7, as NumPy's default
  if (sorted.empty()) return kNaN;
  const double pos = q * static_cast<double>(sorted.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (pos - static_cast<double>(lo)) * (sorted[hi] - sorted[lo]);
}

// E_Δ|asin(sin H cos τ + cos H sin τ cos Δ) − H| over Δ uniform in [0, 2π): the midpoint rule, whose
// error on this periodic integrand (kinks where the error changes sign) is O(h²) ≈ 1e-8 relative.
double exact_tilt_error_rad(double H, double tau) {
  constexpr int n = 36000;
  double sum = 0;
  for (int i = 0; i < n; ++i) {
    const double d = 2 * kPi * (i + 0.5) / n;
    sum += std::abs(std::asin(std::clamp(std::sin(H) * std::cos(tau) + std::cos(H) * std::sin(tau) * std::cos(d),
                                         -1.0, 1.0)) - H);
  }
  return sum / n;
}

// Z21 Fig. 17's mean sun-elevation errors (spec §4.5).
double z21_tilt_deg(double tilt) {
  if (tilt == 0.5) return 0.113;
  if (tilt == 1) return 0.221;
  if (tilt == 2) return 0.887;
  return kNaN;
}

// The NEES of the integrated solution's last fix against the filter's P (NavigationTrialResult).
std::pair<double, double> final_nees(const NavigationFix& fix, const Matrix15& P, const NavigationTruth& truth) {
  const TruthSample& t = truth_at(truth, fix.t_s);
  const Eigen::Vector2d e_pos(fix.lat_rad - t.lat_rad, std::remainder(fix.lon_rad - t.lon_rad, 2 * kPi));
  const Eigen::Matrix2d P_pos = P.block<2, 2>(kDLat, kDLat);
  // C̃_b^n·C_n^b = I − [φ×]: φ from its antisymmetric part (small angles; exact to O(φ²)).
  const Eigen::Matrix3d D = C_bn_from_euler(fix.attitude) * t.C_bn.transpose();
  const Eigen::Vector3d phi(0.5 * (D(1, 2) - D(2, 1)), 0.5 * (D(2, 0) - D(0, 2)), 0.5 * (D(0, 1) - D(1, 0)));
  const Eigen::Matrix3d P_att = P.block<3, 3>(kPhi, kPhi);
  return {e_pos.dot(P_pos.ldlt().solve(e_pos)), phi.dot(P_att.ldlt().solve(phi))};
}

ConsistencyBand band_of(double sum, long long count, long long dof) {
  ConsistencyBand b;
  b.dof = dof;
  if (count == 0 || dof == 0) return b;
  b.mean = sum / static_cast<double>(count);
  const double per = static_cast<double>(dof) / static_cast<double>(count);  // d
  b.lo = per * chi2_mean_quantile(static_cast<double>(dof), -kNormalQuantile975);
  b.hi = per * chi2_mean_quantile(static_cast<double>(dof), kNormalQuantile975);
  return b;
}

// What one trial gives: its rows, and for cell 0 the per-reading detail the rig's figures need.
struct TrialOutput {
  std::vector<NavigationTrialResult> rows;  // per mode
  std::vector<double> t_s;                              // cell 0: the readings' times
  std::vector<std::vector<double>> horizontal_m;        // cell 0: per mode, per reading
  std::vector<std::vector<double>> tilt_error_rad;      // cell 0: per tilt, per reading with a sun
  std::vector<double> elevation_rad;                    // cell 0: H^n (true attitude), per reading with a sun
  std::vector<double> dop, true_dop, aop_error_deg;     // cell 0: every unit reading with an angle
};

std::vector<NavigationGoal> navigation_goal(const std::vector<NavigationMode>& modes, const std::vector<TrialOutput>& outputs,
                                            std::size_t cells, std::size_t trials) {
  const auto index = [&](NavigationMode m) { return std::find(modes.begin(), modes.end(), m) - modes.begin(); };
  const auto sins = static_cast<std::size_t>(index(NavigationMode::Sins)), pns = static_cast<std::size_t>(index(NavigationMode::Pns)),
             integrated = static_cast<std::size_t>(index(NavigationMode::Integrated));
  if (sins == modes.size() || pns == modes.size() || integrated == modes.size()) return {};
  std::vector<NavigationGoal> out;
  for (std::size_t c = 0; c < cells; ++c) {
    NavigationGoal g;
    g.cell = static_cast<int>(c);
    for (std::size_t t = 0; t < trials; ++t) {
      const std::vector<NavigationTrialResult>& rows = outputs[c * trials + t].rows;
      const NavigationTrialResult &s = rows[sins], &p = rows[pns], &i = rows[integrated];
      if (!std::isfinite(i.final_error_m) || !std::isfinite(s.final_error_m)) continue;
      const double better = std::isfinite(p.final_error_m) ? std::min(s.final_error_m, p.final_error_m) : s.final_error_m;
      const bool position = i.final_error_m <= better;
      const bool heading = std::abs(i.final_heading_error_deg) <= std::abs(s.final_heading_error_deg);
      ++g.trials;
      g.position_met += position ? 1 : 0;
      g.heading_met += heading ? 1 : 0;
      g.both_met += position && heading ? 1 : 0;
    }
    out.push_back(g);
  }
  return out;
}

TrialOutput run_trial(const Rig& cell_rig, const NavigationScene& scene, int cell, int trial,
                      const NavigationStudySettings& settings) {
  Rig rig = cell_rig;
  rig.seed = derive_seed(cell_rig.seed, static_cast<std::uint64_t>(trial));
  const NavigationDataset data = simulate_navigation(rig, scene);
  const NavigationRun run = navigate(data, rig);
  const NavigationTruth& truth = *data.truth;
  const bool detail = cell == 0;
  TrialOutput out;
  if (detail)
    for (const CompassEpoch& e : data.compass) out.t_s.push_back(e.t_s);
  for (std::size_t m = 0; m < run.modes.size(); ++m) {
    const std::vector<NavigationFix>& fixes = run.fixes[m];
    NavigationTrialResult r;
    r.cell = cell;
    r.trial = trial;
    r.mode = run.modes[m];
    r.seed = rig.seed;
    std::vector<double> lat, lon, horizontal;
    PositionError last{kNaN, kNaN, kNaN, kNaN};
    for (const NavigationFix& f : fixes) {
      PositionError e{kNaN, kNaN, kNaN, kNaN};
      if (std::isfinite(f.lat_rad) && std::isfinite(f.lon_rad)) e = position_error(f, truth_at(truth, f.t_s));
      lat.push_back(e.lat_deg);
      lon.push_back(e.lon_deg);
      if (detail) horizontal.push_back(std::hypot(e.north_m, e.east_m));
      last = e;
    }
    r.final_t_s = fixes.empty() ? kNaN : fixes.back().t_s;
    r.final_north_m = last.north_m;
    r.final_east_m = last.east_m;
    r.final_error_m = std::hypot(last.north_m, last.east_m);
    if (!fixes.empty())
      r.final_heading_error_deg =
          rad2deg(std::remainder(fixes.back().attitude.yaw_rad - truth_at(truth, fixes.back().t_s).euler.yaw_rad, 2 * kPi));
    r.lat_deg = error_statistics(lat);
    r.lon_deg = error_statistics(lon);
    if (r.mode == NavigationMode::Integrated) {
      r.filter_nis_mean = run.filter_summary.mean_nis;
      r.filter_updates = run.filter_summary.updates;
      if (!fixes.empty() && fixes.back().status == "ok") std::tie(r.nees_position, r.nees_attitude) = final_nees(fixes.back(), run.final_P, truth);
    }
    out.rows.push_back(r);
    if (detail) out.horizontal_m.push_back(std::move(horizontal));
  }
  if (!detail) return out;

  // Fig. 17: the same s^b turned into n by the true and by the tilted attitude.
  out.tilt_error_rad.resize(settings.tilts_deg.size());
  const std::uint64_t tilt_seed = derive_seed(rig.seed, kFig17TiltStream);
  for (std::size_t k = 0; k < data.compass.size(); ++k) {
    const CompassEpoch& e = data.compass[k];
    const UnitSun sun = sun_from_units(e.units, data.mounts);
    if (sun.status != UnitSunStatus::Ok) continue;
    const Eigen::Matrix3d C = truth_at(truth, e.t_s).C_bn;
    out.elevation_rad.push_back(sun_in_nav(sun.s_b, axes_of(C)).elevation_rad);
    // The up axis tipped towards azimuth a (clockwise from north): a rotation about
    // u = up × (sin a, cos a, 0) = (−cos a, sin a, 0).
    const double a = 2 * kPi * uniform_unit(tilt_seed, k, 0, 0);
    const Eigen::Vector3d u(-std::cos(a), std::sin(a), 0);
    for (std::size_t i = 0; i < settings.tilts_deg.size(); ++i) {
      const Eigen::Matrix3d tilted = Eigen::AngleAxisd(deg2rad(settings.tilts_deg[i]), u).toRotationMatrix() * C;
      out.tilt_error_rad[i].push_back(sun_in_nav(sun.s_b, axes_of(tilted)).elevation_rad - out.elevation_rad.back());
    }
  }
  // Fig. 16: every unit's reading against the sky along its true view.
  for (const CompassEpoch& e : data.compass)
    for (const UnitSample& u : e.samples) {
      if (!std::isfinite(u.aop_rad) || !std::isfinite(u.dop)) continue;
      out.dop.push_back(u.dop);
      out.true_dop.push_back(u.true_dop);
      out.aop_error_deg.push_back(rad2deg(std::abs(std::remainder(u.aop_rad - u.true_aop_rad, kPi))));
    }
  return out;
}

// The DoP bins' edges b·5/100 (0.15, not 0.15000000000000002), and the bin of d: the b with
// edge(b) ≤ d < edge(b + 1) (a negative d in bin 0).
double dop_bin_edge(std::size_t b) { return static_cast<double>(b) * 5 / 100; }
std::size_t dop_bin(double d) {
  if (!(d > 0)) return 0;
  auto b = static_cast<std::size_t>(std::floor(d * 20));
  while (b > 0 && d < dop_bin_edge(b)) --b;
  while (d >= dop_bin_edge(b + 1)) ++b;
  return b;
}

std::string value_text(double v) { return fmt::format("{}", v); }

}  // namespace

const std::vector<NavigationSweep>& navigation_sweeps() {
  static const std::vector<NavigationSweep> sweeps{
      {"duration", "trajectory.duration_s", "durations_s", &NavigationStudySettings::durations_s},
      {"p_max", "sky.p_max", "p_max", &NavigationStudySettings::p_max},
      {"noise", "electronics.noise_sigma_V", "noise_sigma_V", &NavigationStudySettings::noise_sigma_V},
      {"ring_tilt", "device.units.ring_tilt_deg", "ring_tilts_deg", &NavigationStudySettings::ring_tilts_deg}};
  return sweeps;
}

Rig rig_with_value(const Rig& rig, std::string_view path, double value) {
  const auto fail = [&](const std::string& why) {
    throw RigError(fmt::format("{}={}: {}", path, value_text(value), why));
  };
  const RigKey* key = find_rig_key(path);
  if (!key || key->kind != RigKey::Kind::Real) fail("not a real-valued rig key");
  if (!key->read_by_instrument(rig.device_kind))
    fail(fmt::format("device.kind {} does not read it (only device.kind {} does)", rig.device_kind, key->instruments));
  if (!key->read_by_source(rig.source.model))
    fail(fmt::format("source.model {} does not read it (only source.model {} does)", rig.source.model, key->sources));
  if (!std::isfinite(value) || (key->valid_real && !key->valid_real(value)))
    fail(fmt::format("expected {}, got {}", key->expects, value_text(value)));
  if (path == "trajectory.duration_s" && !rig.trajectory.segment_s.empty())
    fail("the rig's trajectory.segment_s replaces trajectory.duration_s; the value would be unused");
  if (path == "sky.p_max" && !rig.source.sky.p_max_table.empty())
    fail("the rig's sky.p_max_table replaces sky.p_max; the value would be unused");
  if (path == "device.units.ring_tilt_deg" && !rig.units.tilt_deg.empty())
    fail("the rig's explicit layout (device.units.tilt_deg) replaces the ring; the value would be unused");
  Rig out = rig;
  key->real(out) = value;
  if (const std::optional<RigProblem> p = check_rig(out))
    fail(fmt::format("{}: {}", p->path, p->message));
  // As the parser's last step: a source that sets the rig's d (the sky's at the first stop, which
  // sky.p_max changes) gives device.d.
  if (const std::optional<double> d = out.light->rig_degree_of_polarization(out.source_view())) out.device.d = *d;
  return out;
}

namespace {
// A run without a compass reading has no statistic to give (every one would be nan), and
// navigate refuses it: so does the study (the third review's finding 17).
void require_a_reading(const Rig& r, const std::string& what) {
  const double T = trajectory_spec(r).duration_s(), f = r.units.rate_hz;
  if (!(std::floor(T * f * (1 + 1e-12)) >= 1))
    throw RigError(fmt::format("{}: a {} s run holds no compass reading (device.units.rate_hz {} Hz: the first at {} s); "
                               "the study needs at least one", what, T, f, 1 / f));
}
}  // namespace

void check_navigation_study_settings(const Rig& rig, const NavigationStudySettings& s,
                                     const std::function<std::string(std::string_view field)>& name) {
  require_instrument(rig, Instrument::kUnitArray, "study navigation");
  if (!rig_sky(rig)) throw RigError(no_sky_message(rig, "study navigation"));
  if (s.trials < 1 || s.trials > 100000)
    throw std::invalid_argument(fmt::format("{}: expected a whole number in [1, 100000], got {}", name("trials"), s.trials));
  if (s.tilts_deg.size() > 32)
    throw std::invalid_argument(fmt::format("{}: expected at most 32 tilts, got {}", name("tilts_deg"), s.tilts_deg.size()));
  for (double t : s.tilts_deg)
    if (!std::isfinite(t) || t < 0 || t > 10)
      throw std::invalid_argument(fmt::format("{}: expected finite tilts in [0, 10] °, got {}", name("tilts_deg"), value_text(t)));
  for (const NavigationSweep& sw : navigation_sweeps()) {
    const std::vector<double>& values = s.*sw.values;
    if (values.size() > 1000)
      throw std::invalid_argument(fmt::format("{}: expected at most 1000 values, got {}", name(sw.field), values.size()));
    for (double v : values) {
      try {
        require_a_reading(rig_with_value(rig, sw.key, v), std::string(sw.key));
      } catch (const RigError& e) {
        throw RigError(fmt::format("{} {}: {}", name(sw.field), value_text(v), e.what()));
      }
    }
  }
  require_a_reading(rig, "trajectory.duration_s");
}

Percentiles percentiles(std::vector<double> values) {
  std::erase_if(values, [](double v) { return !std::isfinite(v); });
  std::sort(values.begin(), values.end());
  Percentiles p;
  p.count = static_cast<int>(values.size());
  if (values.empty()) return p;
  p.p05 = type7(values, 0.05);
  p.p25 = type7(values, 0.25);
  p.p50 = type7(values, 0.5);
  p.p75 = type7(values, 0.75);
  p.p95 = type7(values, 0.95);
  return p;
}

NavigationStudy navigation_study(const Rig& rig, const NavigationStudySettings& settings, const Progress& progress) {
  check_navigation_study_settings(rig, settings);
  NavigationStudy study;
  study.settings = settings;
  study.modes = kModes;
  std::vector<Rig> rigs{rig};
  study.cells.push_back({0, "baseline", "", kNaN, 0});
  for (const NavigationSweep& sw : navigation_sweeps())
    for (double v : settings.*sw.values) {
      study.cells.push_back({static_cast<int>(study.cells.size()), std::string(sw.factor), std::string(sw.key), v, 0});
      rigs.push_back(rig_with_value(rig, sw.key, v));
    }
  for (std::size_t c = 0; c < rigs.size(); ++c) study.cells[c].duration_s = trajectory_spec(rigs[c]).duration_s();

  // Cells in parallel, each making its scene (the trajectory and the sun, the same for every seed)
  // once and running its trials in parallel. The trials are isolated: a thread waiting for them
  // takes no other cell, so at most one scene per thread is alive.
  const std::size_t trials = static_cast<std::size_t>(settings.trials), tasks = rigs.size() * trials;
  std::vector<TrialOutput> outputs(tasks);
  progress.begin("study navigation: trials", static_cast<long long>(tasks));
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rigs.size(), 1), [&](const tbb::blocked_range<std::size_t>& cells) {
    for (std::size_t c = cells.begin(); c < cells.end(); ++c) {
      const NavigationScene scene = navigation_scene(rigs[c]);
      tbb::this_task_arena::isolate([&] {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, trials, 1), [&](const tbb::blocked_range<std::size_t>& r) {
          for (std::size_t i = r.begin(); i < r.end(); ++i) {
            outputs[c * trials + i] = run_trial(rigs[c], scene, static_cast<int>(c), static_cast<int>(i), settings);
            progress.advance(1);
          }
        });
      });
    }
  });
  progress.finish();

  // Everything below in index order: the same sums for any thread count.
  for (const TrialOutput& o : outputs) study.trials.insert(study.trials.end(), o.rows.begin(), o.rows.end());
  const std::size_t modes = study.modes.size();
  for (std::size_t c = 0; c < rigs.size(); ++c)
    for (std::size_t m = 0; m < modes; ++m) {
      std::vector<double> final_m, lat, lon;
      for (std::size_t t = 0; t < trials; ++t) {
        const NavigationTrialResult& r = outputs[c * trials + t].rows[m];
        final_m.push_back(r.final_error_m);
        lat.push_back(r.lat_deg.mae);
        lon.push_back(r.lon_deg.mae);
      }
      study.summary.push_back({static_cast<int>(c), study.modes[m], settings.trials, percentiles(final_m),
                               percentiles(lat), percentiles(lon)});
    }

  // The integrated filter's consistency per cell.
  const auto integrated = std::find(study.modes.begin(), study.modes.end(), NavigationMode::Integrated);
  if (integrated != study.modes.end())
    for (std::size_t c = 0; c < rigs.size(); ++c) {
      const std::size_t m = static_cast<std::size_t>(integrated - study.modes.begin());
      double pos = 0, att = 0, nis = 0;
      long long n = 0, updates = 0;
      for (std::size_t t = 0; t < trials; ++t) {
        const NavigationTrialResult& r = outputs[c * trials + t].rows[m];
        if (r.filter_updates > 0 && std::isfinite(r.filter_nis_mean)) {
          nis += r.filter_nis_mean * r.filter_updates;
          updates += r.filter_updates;
        }
        if (!std::isfinite(r.nees_position) || !std::isfinite(r.nees_attitude)) continue;
        pos += r.nees_position;
        att += r.nees_attitude;
        ++n;
      }
      study.consistency.push_back({static_cast<int>(c), static_cast<int>(n), band_of(pos, n, 2 * n),
                                   band_of(att, n, 3 * n), band_of(nis, updates, updates)});
    }

  study.goal = navigation_goal(study.modes, outputs, rigs.size(), trials);

  // Cell 0's figures.
  const std::vector<double>& times = outputs[0].t_s;
  for (std::size_t m = 0; m < modes; ++m) {
    NavigationErrorBand band{study.modes[m], times, {}};
    for (std::size_t k = 0; k < times.size(); ++k) {
      std::vector<double> at;
      for (std::size_t t = 0; t < trials; ++t) at.push_back(outputs[t].horizontal_m[m][k]);
      band.error_m.push_back(percentiles(std::move(at)));
    }
    study.bands.push_back(std::move(band));
  }

  double sum_H = 0;
  long long readings = 0;
  for (std::size_t t = 0; t < trials; ++t)
    for (double H : outputs[t].elevation_rad) {
      sum_H += H;
      ++readings;
    }
  const double mean_H = readings > 0 ? sum_H / static_cast<double>(readings) : kNaN;
  study.tilt_mean_elevation_deg = rad2deg(mean_H);
  for (std::size_t i = 0; i < settings.tilts_deg.size(); ++i) {
    TiltErrorRow row;
    row.tilt_deg = settings.tilts_deg[i];
    std::vector<double> abs_deg;
    double sum2 = 0;
    for (std::size_t t = 0; t < trials; ++t)
      for (double e : outputs[t].tilt_error_rad[i]) {
        abs_deg.push_back(rad2deg(std::abs(e)));
        sum2 += rad2deg(e) * rad2deg(e);
      }
    row.draws = static_cast<long long>(abs_deg.size());
    if (!abs_deg.empty()) {
      const double n = static_cast<double>(abs_deg.size());
      double sum = 0;
      for (double v : abs_deg) sum += v;
      row.mean_abs_deg = sum / n;
      double dev2 = 0;
      for (double v : abs_deg) dev2 += (v - row.mean_abs_deg) * (v - row.mean_abs_deg);
      row.sd_abs_deg = std::sqrt(dev2 / n);
      row.rms_deg = std::sqrt(sum2 / n);
      row.max_abs_deg = *std::max_element(abs_deg.begin(), abs_deg.end());
      row.exact_deg = rad2deg(exact_tilt_error_rad(mean_H, deg2rad(row.tilt_deg)));
    }
    row.first_order_deg = 2 / kPi * row.tilt_deg;
    row.z21_deg = z21_tilt_deg(row.tilt_deg);
    study.tilt.push_back(row);
  }

  // Fig. 16: the bins up to the largest DoP seen.
  double max_dop = 0;
  for (std::size_t t = 0; t < trials; ++t)
    for (double d : outputs[t].dop) max_dop = std::max(max_dop, d);
  const std::size_t bins = dop_bin(max_dop) + 1;
  std::vector<std::vector<double>> err(bins), tdop(bins);
  for (std::size_t t = 0; t < trials; ++t)
    for (std::size_t j = 0; j < outputs[t].dop.size(); ++j) {
      const std::size_t b = dop_bin(outputs[t].dop[j]);
      err[b].push_back(outputs[t].aop_error_deg[j]);
      tdop[b].push_back(outputs[t].true_dop[j]);
    }
  for (std::size_t b = 0; b < bins; ++b) {
    DopBin bin;
    bin.lo = dop_bin_edge(b);
    bin.hi = dop_bin_edge(b + 1);
    bin.count = static_cast<long long>(err[b].size());
    if (!err[b].empty()) {
      const double n = static_cast<double>(err[b].size());
      double sum = 0, sum_d = 0;
      for (double v : err[b]) sum += v;
      for (double v : tdop[b]) sum_d += v;
      bin.mean_abs_deg = sum / n;
      double dev2 = 0;
      for (double v : err[b]) dev2 += (v - bin.mean_abs_deg) * (v - bin.mean_abs_deg);
      bin.sd_abs_deg = std::sqrt(dev2 / n);
      bin.mean_true_dop = sum_d / n;
    }
    if (b == 5) bin.z21_mean_deg = 2.05, bin.z21_sd_deg = 2.38;    // 25–30 %
    if (b == 10) bin.z21_mean_deg = 0.14, bin.z21_sd_deg = 0.17;   // 50–55 %
    study.dop.push_back(bin);
  }
  return study;
}

}  // namespace polrig
