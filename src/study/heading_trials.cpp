#include "polrig/study/heading_trials.h"

#include <algorithm>
#include <array>
#include <utility>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <tbb/parallel_for.h>

#include "polrig/calib/angles.h"
#include "polrig/device/sensor.h"
#include "polrig/random.h"
#include "polrig/sky/rayleigh.h"
#include "polrig/sky/sensor_view.h"
#include "polrig/units.h"
#include "polrig/statistics.h"

namespace polrig {

namespace {

using Eigen::AngleAxisd;
using Eigen::Matrix3d;
using Eigen::Vector3d;

Vector3d to_eigen(const Vec3& v) { return {v[0], v[1], v[2]}; }
Vec3 to_vec3(const Vector3d& v) { return {v.x(), v.y(), v.z()}; }

// C_b^n as a matrix, from compass/'s own rotation (columns: the body axes in n).
Matrix3d body_to_n(double heading_deg, const Tilt& tilt) {
  Matrix3d C;
  for (int k = 0; k < 3; ++k) {
    Vec3 axis{0, 0, 0};
    axis[static_cast<std::size_t>(k)] = 1;
    C.col(k) = to_eigen(body_to_enu(axis, heading_deg, tilt));
  }
  return C;
}

// The sensor's frame in the body's: Rx(m_x)·Ry(m_y)·Rz(m_z).
Matrix3d mount(double mx_deg, double my_deg, double mz_deg) {
  return (AngleAxisd(deg2rad(mx_deg), Vector3d::UnitX()) * AngleAxisd(deg2rad(my_deg), Vector3d::UnitY()) *
          AngleAxisd(deg2rad(mz_deg), Vector3d::UnitZ()))
      .toRotationMatrix();
}

struct Seen {
  double theta_deg;  // the sensor's angle in polrig's sensor frame (anticlockwise seen from above)
  double dop;
};

// What a sensor with frame C (sensor → n, looking along its Z) sees of the sky: its angle from
// X_s towards Y_s (sky/sensor_view.h, the frame the device model and the sky source use).
Seen sensor_sees(const Matrix3d& C, const Vec3& sun, const SkyModel& sky) {
  const SkyLight light = sky_light(sun, to_vec3(C.col(2)), sky);
  const double theta = sensor_frame_angle_rad(light.e_vector, to_vec3(C.col(0)), to_vec3(C.col(1)));
  return {wrap_axis_deg(rad2deg(theta)), light.dop};
}

double error_of(const HeadingSolution& r, double truth_deg) {
  return has_heading(r.status) ? heading_difference_deg(r.heading_deg, truth_deg)
                               : std::numeric_limits<double>::quiet_NaN();
}

// The device model: six films' response to (θ, d), pair voltages, noise per sample, the ADC,
// the mean, and θ_sec back through calib/angles with the device's own (true) parameters.
double through_device(const Rig& rig, std::uint64_t seed, const Seen& seen, int samples) {
  const std::array<double, 6> E{1, 1, 1, 1, 1, 1};  // the sky at infinity: equal irradiance
  const std::array<double, 3> V0 =
      pair_voltages(rig.device.truth, rig.electronics, E, seen.theta_deg, seen.dop);
  std::array<double, 3> V{0, 0, 0};
  for (int i = 0; i < 3; ++i) {
    double sum = 0;
    for (int k = 0; k < samples; ++k)
      sum += adc_quantize(V0[static_cast<std::size_t>(i)] +
                              rig.electronics.noise_sigma_V *
                                  standard_normal(seed, 0, static_cast<std::uint64_t>(i),
                                                  static_cast<std::uint64_t>(k)),
                          rig.electronics);
    V[static_cast<std::size_t>(i)] = sum / samples;
  }
  return sensor_angles(rig.device.truth, rig.electronics, V).theta_sec_deg;
}

HeadingTrial run_trial(const Rig& rig, const HeadingStudySettings& s, const Vec3& sun, int index) {
  HeadingTrial t;
  t.index = index;
  t.seed = derive_seed(rig.seed, static_cast<std::uint64_t>(index));
  const auto u = [&](std::uint64_t c) { return uniform_unit(t.seed, 1, 0x4EAD, c); };
  const auto n = [&](std::uint64_t c) { return standard_normal(t.seed, 1, 0x4EAD, c); };
  t.heading_deg = 360.0 * u(0);
  t.roll_deg = s.roll_sd_deg * n(1);
  t.pitch_deg = s.pitch_sd_deg * n(2);
  t.sync_s = s.sync_max_s * (2.0 * u(3) - 1.0);
  t.turn_rate_dps = s.turn_rate_max_dps * (2.0 * u(4) - 1.0);
  t.ins_roll_error_deg = s.ins_tilt_sd_deg * n(5);
  t.ins_pitch_error_deg = s.ins_tilt_sd_deg * n(6);
  t.mount_x_deg = s.mount_tilt_sd_deg * n(7);
  t.mount_y_deg = s.mount_tilt_sd_deg * n(8);
  t.mount_z_deg = s.mount_azimuth_sd_deg * n(9);
  t.p_max = s.p_max_min + (s.p_max_max - s.p_max_min) * u(10);
  SkyModel sky;
  sky.P_max.constant = t.p_max;

  const Tilt truth{t.roll_deg, t.pitch_deg};
  const Tilt ins{t.roll_deg + t.ins_roll_error_deg, t.pitch_deg + t.ins_pitch_error_deg};
  // The body when the sensor samples: turned by ω·Δt since the INS's epoch.
  const double heading_at_sensor = t.heading_deg + t.turn_rate_dps * t.sync_s;
  const Matrix3d C_now = body_to_n(t.heading_deg, truth);
  const Matrix3d C_sensor_time = body_to_n(heading_at_sensor, truth);
  const Matrix3d M = mount(t.mount_x_deg, t.mount_y_deg, t.mount_z_deg);
  // θ_b = θ_mount + θ with the nominal θ_mount = 0: θ and θ_b both turn anticlockwise seen from
  // above (spec §1.5's Eq. 22 has θ_mount − θ_meas for the spec's clockwise θ_meas).
  const auto body_angle = [](double theta) { return wrap_axis_deg(theta); };
  const auto solve = [&](double aop_b, const Tilt& tilt) {
    return solve_heading(sun, aop_b, tilt, t.heading_deg);
  };

  const Seen all = sensor_sees(C_sensor_time * M, sun, sky);
  t.dop = all.dop;
  t.aop_meas_deg = body_angle(through_device(rig, t.seed, all, s.samples));
  const HeadingSolution r = solve(t.aop_meas_deg, ins);
  t.status = r.status;
  t.heading_est_deg = has_heading(r.status) ? r.heading_deg : std::numeric_limits<double>::quiet_NaN();
  t.error_deg = error_of(r, t.heading_deg);

  // Each factor alone.
  const Seen ideal = sensor_sees(C_now, sun, sky);
  t.aop_true_deg = body_angle(ideal.theta_deg);
  t.error_sync_deg = error_of(solve(body_angle(sensor_sees(C_sensor_time, sun, sky).theta_deg), truth),
                              t.heading_deg);
  t.error_ins_tilt_deg = error_of(solve(t.aop_true_deg, ins), t.heading_deg);
  t.error_mount_deg = error_of(solve(body_angle(sensor_sees(C_now * M, sun, sky).theta_deg), truth),
                               t.heading_deg);
  t.error_noise_deg =
      error_of(solve(body_angle(through_device(rig, t.seed, ideal, s.samples)), truth), t.heading_deg);
  return t;
}

}  // namespace

namespace {

HeadingErrorStats stats_of(std::string factor, std::string error, double lo, double hi,
                           const std::vector<double>& errors) {
  HeadingErrorStats s{std::move(factor), std::move(error), lo, hi};
  s.trials = static_cast<int>(errors.size());
  std::vector<double> a;
  double sum = 0, sum_sq = 0;
  for (double e : errors)
    if (!std::isnan(e)) {
      a.push_back(std::abs(e));
      sum += e;
      sum_sq += e * e;
    }
  s.solved = static_cast<int>(a.size());
  if (a.empty()) return s;
  std::sort(a.begin(), a.end());
  const double n = static_cast<double>(a.size());
  s.mean_deg = sum / n;
  s.rms_deg = std::sqrt(sum_sq / n);
  s.p50_abs_deg = quantile_of_sorted(a, 0.5);
  s.p95_abs_deg = quantile_of_sorted(a, 0.95);
  s.max_abs_deg = a.back();
  return s;
}

using TrialValue = double (*)(const HeadingTrial&);

// The full error, then each factor alone: summary.csv's "all" rows and cdf.csv's columns.
constexpr std::array<std::pair<const char*, TrialValue>, 5> kErrors{{
    {"error_deg", [](const HeadingTrial& t) { return t.error_deg; }},
    {"error_sync_deg", [](const HeadingTrial& t) { return t.error_sync_deg; }},
    {"error_ins_tilt_deg", [](const HeadingTrial& t) { return t.error_ins_tilt_deg; }},
    {"error_mount_deg", [](const HeadingTrial& t) { return t.error_mount_deg; }},
    {"error_noise_deg", [](const HeadingTrial& t) { return t.error_noise_deg; }},
}};

std::vector<double> column_of(const std::vector<HeadingTrial>& trials, TrialValue get) {
  std::vector<double> v;
  for (const HeadingTrial& t : trials) v.push_back(get(t));
  return v;
}

}  // namespace

std::vector<HeadingErrorStats> summarize_heading_trials(const std::vector<HeadingTrial>& trials) {
  std::vector<HeadingErrorStats> rows;
  for (const auto& [name, get] : kErrors) rows.push_back(stats_of("all", name, NAN, NAN, column_of(trials, get)));
  const std::array<std::pair<const char*, TrialValue>, 6> factors{{
      {"sync_heading_deg", [](const HeadingTrial& t) { return t.sync_heading_deg(); }},
      {"tilt_deg", [](const HeadingTrial& t) { return std::hypot(t.roll_deg, t.pitch_deg); }},
      {"mount_tilt_deg", [](const HeadingTrial& t) { return t.mount_tilt_deg(); }},
      {"mount_z_deg", [](const HeadingTrial& t) { return t.mount_z_deg; }},
      {"p_max", [](const HeadingTrial& t) { return t.p_max; }},
      {"dop", [](const HeadingTrial& t) { return t.dop; }},
  }};
  constexpr int kBins = 8;
  for (const auto& [name, get] : factors) {
    const std::vector<double> x = column_of(trials, get);
    if (x.empty()) break;
    const auto [lo_it, hi_it] = std::minmax_element(x.begin(), x.end());
    const double lo = *lo_it, hi = *hi_it;
    if (!(hi > lo)) continue;
    for (int b = 0; b < kBins; ++b) {
      const double a = lo + (hi - lo) * b / kBins, z = lo + (hi - lo) * (b + 1) / kBins;
      std::vector<double> e;
      for (const HeadingTrial& t : trials) {
        const double v = get(t);
        if (v >= a && (v < z || (b == kBins - 1 && v <= z))) e.push_back(t.error_deg);
      }
      rows.push_back(stats_of(name, "error_deg", a, z, e));
    }
  }
  return rows;
}

HeadingErrorCdf heading_error_cdf(const std::vector<HeadingTrial>& trials) {
  HeadingErrorCdf c;
  const std::size_t n = trials.size();
  for (std::size_t k = 0; k < n; ++k)
    c.fraction.push_back((static_cast<double>(k) + 0.5) / static_cast<double>(n));
  for (std::size_t m = 0; m < kErrors.size(); ++m) {
    std::vector<double>& col = c.abs_error_deg[m];
    for (double e : column_of(trials, kErrors[m].second))
      if (!std::isnan(e)) col.push_back(std::abs(e));
    std::sort(col.begin(), col.end());
    col.resize(n, std::nan(""));
  }
  return c;
}

bool use_rig_sky(const Rig& rig, HeadingStudySettings& settings) {
  const std::optional<Sky> found = rig_sky(rig);
  if (!found) return false;
  const Sky& sky = *found;
  settings.site = sky.site;
  settings.utc = sky.first_stop;
  settings.sun.ut1_minus_utc_s = sky.sun.ut1_minus_utc_s;
  settings.sun.refraction = sky.sun.refraction;
  return true;
}

void check_heading_study_settings(const HeadingStudySettings& s,
                                  const std::function<std::string(std::string_view)>& name) {
  const auto whole = [&](int v, const char* field, int lo, int hi) {
    if (v < lo || v > hi)
      throw std::invalid_argument(fmt::format("{}: expected a whole number in [{}, {}], got {}",
                                              name(field), lo, hi, v));
  };
  const auto range = [&](double v, const char* field, double lo, double hi, const char* unit) {
    if (!(std::isfinite(v) && v >= lo && v <= hi))
      throw std::invalid_argument(fmt::format("{}: expected a finite number in [{}, {}]{}{}, got {}",
                                              name(field), lo, hi, *unit ? " " : "", unit, v));
  };
  whole(s.trials, "trials", 1, 10000000);
  whole(s.samples, "samples", 1, 100000);
  range(s.roll_sd_deg, "roll_sd_deg", 0, 30, "°");
  range(s.pitch_sd_deg, "pitch_sd_deg", 0, 30, "°");
  range(s.sync_max_s, "sync_max_s", 0, 10, "s");
  range(s.turn_rate_max_dps, "turn_rate_max_dps", 0, 360, "°/s");
  range(s.ins_tilt_sd_deg, "ins_tilt_sd_deg", 0, 10, "°");
  range(s.mount_tilt_sd_deg, "mount_tilt_sd_deg", 0, 10, "°");
  range(s.mount_azimuth_sd_deg, "mount_azimuth_sd_deg", 0, 10, "°");
  range(s.p_max_min, "p_max_min", 0.05, 1, "");
  range(s.p_max_max, "p_max_max", 0.05, 1, "");
  if (s.p_max_min > s.p_max_max)
    throw std::invalid_argument(fmt::format("{} {} is above {} {}", name("p_max_min"), s.p_max_min,
                                            name("p_max_max"), s.p_max_max));
}

std::vector<HeadingTrial> heading_trials(const Rig& rig, const HeadingStudySettings& s,
                                         const Progress& progress) {
  require_instrument(rig, Instrument::kPairVoltages, "study heading");
  check_heading_study_settings(s);
  const Vec3 sun = sun_direction_enu(sun_position(s.utc, s.site, s.sun));
  std::vector<HeadingTrial> trials(static_cast<std::size_t>(std::max(0, s.trials)));
  progress.begin("study heading: trials", s.trials);
  tbb::parallel_for(0, s.trials, [&](int k) {
    trials[static_cast<std::size_t>(k)] = run_trial(rig, s, sun, k);
    progress.advance();
  });
  progress.finish();
  return trials;
}

}  // namespace polrig
