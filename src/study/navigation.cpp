#include "polrig/study/navigation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include "polrig/ins/earth.h"
#include "polrig/ins/smoother.h"
#include "polrig/ins/zupt.h"
#include "polrig/random.h"
#include "polrig/rig/error.h"
#include "polrig/sky/sun.h"
#include "polrig/units.h"

namespace polrig {

namespace {


// Stream indices of derive_seed: the IMU's errors and the units' noise draw from separate streams.
constexpr std::uint64_t kImuStream = 0x494D55, kUnitStream = 0x554E4954, kStartStream = 0x5354415254;

Eigen::Vector3d si(const std::array<double, 3>& v, double scale) {
  return Eigen::Vector3d(v[0], v[1], v[2]) * scale;
}

SensorErrorSpec triad_spec(const TriadSettings& t, double bias_scale, double white_scale, double walk_scale) {
  SensorErrorSpec s;
  s.bias = si(t.bias, bias_scale);
  s.turn_on_bias_sigma = si(t.turn_on_sigma, bias_scale);
  s.bias_instability = si(t.bias_instability, bias_scale);
  s.correlation_time_s = si(t.correlation_time_s, 1.0);
  s.white_noise = si(t.white_noise, white_scale);
  s.random_walk = si(t.random_walk, walk_scale);
  s.scale_factor_sigma = si(t.scale_factor_ppm, 1e-6);
  s.misalignment_sigma_rad = deg2rad(t.misalignment_deg);
  return s;
}


// IMU samples per compass reading (check_rig makes the IMU rate a whole multiple of the units').
std::size_t imu_samples_per_reading(const Rig& rig) {
  return static_cast<std::size_t>(std::lround(rig.imu.rate_hz / rig.units.rate_hz));
}

Sky sky_of(const Rig& rig) {
  const std::optional<Sky> sky = rig_sky(rig);
  if (!sky) throw RigError(no_sky_message(rig, "navigation"));
  return *sky;
}

// The measured H^n: the sun of the two highest-DoP units turned into n by the attitude C_b^n.
double elevation_n(const UnitSun& sun, const Eigen::Matrix3d& C_bn) {
  if (sun.status != UnitSunStatus::Ok) return kNaN;
  return sun_in_nav(sun.s_b, axes_of(C_bn)).elevation_rad;
}

}  // namespace

TrajectorySpec trajectory_spec(const Rig& rig) {
  const Sky sky = sky_of(rig);
  const TrajectorySettings& t = rig.trajectory;
  TrajectorySpec spec;
  spec.lat_rad = deg2rad(sky.site.lat_deg);
  spec.lon_rad = deg2rad(sky.site.lon_deg);
  spec.h_m = sky.site.height_m;
  spec.attitude = {deg2rad(t.roll_deg), deg2rad(t.pitch_deg), deg2rad(t.heading_deg)};
  spec.speed_mps = t.speed_mps;
  spec.imu_rate_hz = rig.imu.rate_hz;
  spec.vibration_mps2 = t.vibration_mps2;
  const auto at = [](const std::vector<double>& v, std::size_t i) { return v.empty() ? 0.0 : v[i]; };
  double u = t.speed_mps;
  const std::size_t n = t.segment_s.size();
  for (std::size_t i = 0; i < std::max<std::size_t>(n, 1); ++i) {
    Segment s;
    s.duration_s = n == 0 ? t.duration_s : t.segment_s[i];
    const double a = n == 0 ? 0 : at(t.segment_accel_mps2, i), w = n == 0 ? 0 : at(t.segment_turn_deg_s, i),
                 c = n == 0 ? 0 : at(t.segment_climb_deg_s, i);
    if (a != 0) s = {SegmentKind::Accelerate, s.duration_s, a};
    else if (w != 0) s = {SegmentKind::Turn, s.duration_s, deg2rad(w)};
    else if (c != 0) s = {SegmentKind::Climb, s.duration_s, deg2rad(c)};
    else s = {std::abs(u) <= 1e-9 ? SegmentKind::Static : SegmentKind::Accelerate, s.duration_s, 0.0};
    u += a * s.duration_s;
    spec.segments.push_back(s);
  }
  return spec;
}

ImuErrorSpec imu_error_spec(const ImuSettings& imu) {
  // °/h → rad/s, °/√h → rad/√s, °/h/√h → rad/s/√s; µg → m/s², µg/√Hz → m/s/√s, µg/√s → m/s²/√s.
  const double g = 1e-6 * kStandardGravity;
  ImuErrorSpec spec;
  spec.rate_hz = imu.rate_hz;
  spec.gyro = triad_spec(imu.gyro, deg2rad(1.0) / 3600, deg2rad(1.0) / 60, deg2rad(1.0) / 3600 / 60);
  spec.accel = triad_spec(imu.accel, g, g, g);
  return spec;
}

FilterSettings filter_settings(const Rig& rig) {
  const NavigationSettings& n = rig.navigation;
  FilterSettings s;
  s.sigma_H_rad = deg2rad(n.sigma_H_deg);
  s.sigma_A_rad = deg2rad(n.sigma_A_deg);
  s.adaptive = n.adaptive;
  s.sage_husa_b = n.forgetting_factor;
  using M = FilterSettings::SunMeasurement;
  for (M m : {M::ElevationZ21, M::Elevation, M::Azimuth, M::SunVector, M::PnsFix})
    if (n.measurement == sun_measurement_name(m)) s.measurement = m;

  // P once per compass reading by van Loan (ins/filter.h): the state is mechanized at the IMU rate.
  s.covariance_step = FilterSettings::CovarianceStep::AtUpdates;
  if (n.hold_height) s.mechanization.hold_height_m = sky_of(rig).site.height_m;
  s.noise = error_model_noise(imu_error_spec(rig.imu));
  return s;
}

InsState initial_state(const Rig& rig, StartErrors errors) {
  const TrajectorySpec spec = trajectory_spec(rig);
  const auto& e = rig.navigation.initial_attitude_error_deg;
  InsState s;
  s.q_bn = Eigen::Quaterniond(C_bn_from_euler({spec.attitude.roll_rad + deg2rad(e[0]),
                                               spec.attitude.pitch_rad + deg2rad(e[1]),
                                               spec.attitude.yaw_rad + deg2rad(e[2])}));
  const double yaw = spec.attitude.yaw_rad, pitch = spec.attitude.pitch_rad;
  s.v_n = spec.speed_mps * Eigen::Vector3d(std::sin(yaw) * std::cos(pitch), std::cos(yaw) * std::cos(pitch), std::sin(pitch));
  s.lat_rad = spec.lat_rad;
  s.lon_rad = spec.lon_rad;
  s.h_m = spec.h_m;
  if (errors == StartErrors::DrawnFromP0 && rig.navigation.initial_errors == "drawn") {
    // The error state x ~ N(0, P0) for φ, δV and δL, δλ, δh (the biases are the IMU's own draws);
    // the INS's start is the truth with x put in: feed_back's inverse (ins/error_model.h).
    const Matrix15 P0 = initial_covariance(rig);
    const std::uint64_t seed = derive_seed(rig.seed, kStartStream);
    Vector15 x = Vector15::Zero();
    for (int i = kPhi; i <= kDh; ++i) x[i] = std::sqrt(P0(i, i)) * standard_normal(seed, 0, 0, static_cast<std::uint64_t>(i));
    // Held: P0's v_U and h entries are 0 (pinned), so their draws are 0 too.
    s.q_bn = (quaternion_from_rotation_vector(-x.segment<3>(kPhi)) * s.q_bn).normalized();
    s.v_n += x.segment<3>(kDV);
    s.lat_rad += x[kDLat];
    s.lon_rad += x[kDLon];
    s.h_m += x[kDh];
  }
  return s;
}

Matrix15 initial_covariance(const Rig& rig) {
  const NavigationSettings& n = rig.navigation;
  const Site site = sky_of(rig).site;
  const double L = deg2rad(site.lat_deg);
  const EarthRadii r = earth_radii(L);
  const ImuErrorSpec imu = imu_error_spec(rig.imu);
  Vector15 sd;
  for (int i = 0; i < 3; ++i) {
    sd[kPhi + i] = deg2rad(n.attitude_sigma_deg[static_cast<std::size_t>(i)]);
    sd[kDV + i] = n.velocity_sigma_mps;
    sd[kGyroBias + i] = std::hypot(imu.gyro.bias[i], imu.gyro.turn_on_bias_sigma[i], imu.gyro.bias_instability[i]);
    sd[kAccelBias + i] = std::hypot(imu.accel.bias[i], imu.accel.turn_on_bias_sigma[i], imu.accel.bias_instability[i]);
  }
  sd[kDLat] = n.position_sigma_m / (r.R_M + site.height_m);
  sd[kDLon] = n.position_sigma_m / ((r.R_N + site.height_m) * std::cos(L));
  sd[kDh] = n.position_sigma_m;
  if (n.hold_height) sd[kDV + 2] = sd[kDh] = 0;  // pinned: held h and v_U have no error (ins/filter.cpp)
  return sd.cwiseAbs2().asDiagonal();
}

Matrix15 initial_covariance(const Rig& rig, const NavigationDataset& data) {
  Matrix15 P0 = initial_covariance(rig);
  if (!data.stated_start) return P0;
  const StartSigma& s = *data.stated_start;
  const EarthRadii r = earth_radii(data.initial.lat_rad);
  Vector15 sd = Vector15::Zero();
  sd.segment<3>(kPhi) = s.attitude_rad;
  sd.segment<3>(kDV) = s.velocity_mps;
  sd[kDLat] = s.position_m.x() / (r.R_M + data.initial.h_m);
  sd[kDLon] = s.position_m.y() / ((r.R_N + data.initial.h_m) * std::cos(data.initial.lat_rad));
  sd[kDh] = s.position_m.z();
  if (rig.navigation.hold_height) sd[kDV + 2] = sd[kDh] = 0;
  for (int i = kPhi; i <= kDh; ++i) P0(i, i) = sd[i] * sd[i];
  return P0;
}

FilterSettings filter_settings(const Rig& rig, const NavigationDataset& data) {
  FilterSettings s = filter_settings(rig);
  if (data.stated_start && rig.navigation.hold_height) s.mechanization.hold_height_m = data.initial.h_m;
  return s;
}

NavigationScene navigation_scene(const Rig& rig, const Progress& progress) {
  require_instrument(rig, Instrument::kUnitArray, "a navigation run");
  const Sky sky = sky_of(rig);
  progress.begin("navigation: trajectory", 1);
  NavigationScene scene{generate_trajectory(trajectory_spec(rig)), {}};
  progress.finish();
  const std::vector<TruthSample>& truth = scene.trajectory.truth;
  for (const TruthSample& t : truth)
    if (!(std::abs(t.lat_rad) <= deg2rad(kInsMaxLatitudeDeg)))
      throw std::invalid_argument(fmt::format(
          "the trajectory (sky.lat_deg {}°, trajectory.heading_deg {}°, trajectory.speed_mps and trajectory.segment_*) "
          "reaches latitude {:.6f}° at t = {:.3f} s, beyond the INS's ±{}° (its local-level frame is singular at the poles)",
          rig.source.sky.sky.site.lat_deg, rig.trajectory.heading_deg, rad2deg(t.lat_rad), t.t_s, kInsMaxLatitudeDeg));
  const std::size_t step = imu_samples_per_reading(rig);
  scene.sun.resize(scene.trajectory.imu.size() / step);
  progress.begin("navigation: the sun along the trajectory", static_cast<long long>(scene.sun.size()));
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, scene.sun.size(), 16), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t k = r.begin(); k < r.end(); ++k) {
      const TruthSample& at = truth[(k + 1) * step];
      scene.sun[k] = sun_position(sky.first_stop.plus_seconds(at.t_s),
                                  {rad2deg(at.lat_rad), rad2deg(at.lon_rad), at.h_m}, sky.sun);
    }
    progress.advance(static_cast<long long>(r.size()));
  });
  progress.finish();
  return scene;
}

NavigationDataset simulate_navigation(const Rig& rig, const Progress& progress) {
  return simulate_navigation(rig, navigation_scene(rig, progress), progress);
}

NavigationDataset simulate_navigation(const Rig& rig, const NavigationScene& scene, const Progress& progress) {
  require_instrument(rig, Instrument::kUnitArray, "a navigation run");
  const Sky sky = sky_of(rig);
  const Trajectory& tr = scene.trajectory;
  const std::size_t step = imu_samples_per_reading(rig);
  const std::size_t samples = static_cast<std::size_t>(std::llround(trajectory_spec(rig).duration_s() * rig.imu.rate_hz)) + 1;
  const std::size_t epochs = (samples - 1) / step;
  if (tr.truth.size() != samples || scene.sun.size() != epochs)
    throw std::invalid_argument(fmt::format("navigation scene: {} samples and {} compass epochs, the rig's run has {} and {}",
                                            tr.truth.size(), scene.sun.size(), samples, epochs));
  progress.begin("navigation: IMU errors", 1);
  CorruptedImu imu = corrupt_imu(tr.imu, imu_error_spec(rig.imu), derive_seed(rig.seed, kImuStream));
  progress.finish();

  NavigationDataset d;
  d.start = sky.first_stop;
  d.initial = initial_state(rig, StartErrors::DrawnFromP0);
  d.imu = std::move(imu.samples);
  NavigationTruth truth{tr.truth, unit_array_truth(rig.units, rig.seed), imu.drawn, {}};
  for (const Axes3& C : truth.units.nominal) d.mounts.push_back({C});

  d.compass.resize(scene.sun.size());
  truth.sun_elevation_rad.resize(scene.sun.size());
  const std::uint64_t unit_seed = derive_seed(rig.seed, kUnitStream);
  progress.begin("navigation: compass readings", static_cast<long long>(scene.sun.size()));
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, scene.sun.size(), 16), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t k = r.begin(); k < r.end(); ++k) {
      const TruthSample& at = tr.truth[(k + 1) * step];
      CompassEpoch& e = d.compass[k];
      e.t_s = at.t_s;
      e.samples = read_units(rig, truth.units, sun_direction_enu(scene.sun[k]), sky.model, axes_of(at.C_bn), unit_seed, k);
      for (const UnitSample& u : e.samples) e.units.push_back({u.aop_rad, u.dop});
      truth.sun_elevation_rad[k] = deg2rad(scene.sun[k].elevation_deg);
    }
    progress.advance(static_cast<long long>(r.size()));
  });
  progress.finish();
  d.truth = std::move(truth);
  return d;
}

std::string_view navigation_mode_name(NavigationMode m) {
  switch (m) {
    case NavigationMode::Sins: return "sins";
    case NavigationMode::Pns: return "pns";
    case NavigationMode::Integrated: return "integrated";
    case NavigationMode::Smoothed: return "smoothed";
  }
  return "?";
}

std::vector<NavigationMode> parse_navigation_modes(std::string_view text) {
  constexpr NavigationMode kAll[] = {NavigationMode::Sins, NavigationMode::Pns, NavigationMode::Integrated,
                                     NavigationMode::Smoothed};
  bool wanted[std::size(kAll)] = {};
  std::size_t from = 0;
  while (true) {
    const std::size_t comma = std::min(text.find(',', from), text.size());
    const std::string_view name = text.substr(from, comma - from);
    bool known = name == "all";
    if (known) wanted[0] = wanted[1] = wanted[2] = true;
    for (std::size_t i = 0; i < std::size(kAll); ++i)
      if (name == navigation_mode_name(kAll[i])) known = wanted[i] = true;
    if (!known)
      throw std::invalid_argument(fmt::format("mode '{}': expected sins, pns, integrated, smoothed or all, or a "
                                              "comma-separated list of them (e.g. all,smoothed)", text));
    if (comma == text.size()) break;
    from = comma + 1;
  }
  std::vector<NavigationMode> out;
  for (std::size_t i = 0; i < std::size(kAll); ++i)
    if (wanted[i]) out.push_back(kAll[i]);
  return out;
}

namespace {

// The IMU sample index each compass epoch falls on.
std::vector<std::size_t> epoch_samples(const NavigationDataset& data, std::size_t mounts) {
  for (std::size_t i = 1; i < data.imu.size(); ++i)
    if (!(data.imu[i].t_s > data.imu[i - 1].t_s))
      throw std::invalid_argument(fmt::format("IMU sample {}: time {} s is not after the previous {} s", i + 1,
                                              data.imu[i].t_s, data.imu[i - 1].t_s));
  std::vector<std::size_t> out;
  std::size_t j = 0;
  for (std::size_t k = 0; k < data.compass.size(); ++k) {
    const CompassEpoch& e = data.compass[k];
    if (e.units.size() != mounts)
      throw std::invalid_argument(fmt::format("compass reading at {} s: {} units, expected {}", e.t_s, e.units.size(), mounts));
    while (j < data.imu.size() && data.imu[j].t_s < e.t_s - 1e-3) ++j;
    if (j == data.imu.size() || std::abs(data.imu[j].t_s - e.t_s) > 1e-3)
      throw std::invalid_argument(fmt::format("compass reading at {} s falls on no IMU sample (within 1 ms)", e.t_s));
    if (!out.empty() && j <= out.back())
      throw std::invalid_argument(fmt::format("compass reading at {} s: times must increase", e.t_s));
    out.push_back(j);
  }
  return out;
}

NavigationFix fix_of(const InsState& s) {
  return {s.t_s, s.lat_rad, s.lon_rad, s.h_m, s.euler(), "ok", s.v_n};
}

// The IMU samples the SINS mode reports at: the compass readings' (`at`), or every
// imu.rate_hz/rate-th sample (every one in a log without readings).
std::vector<std::size_t> sins_samples(const NavigationDataset& data, const Rig& rig, double rate_hz,
                                      const std::vector<std::size_t>& at) {
  if (rate_hz == 0 && !data.compass.empty()) return at;
  const double ratio = rate_hz == 0 ? 1.0 : rig.imu.rate_hz / rate_hz;
  const std::size_t step = static_cast<std::size_t>(std::llround(ratio));
  if (!(rate_hz >= 0) || !std::isfinite(ratio) || step < 1 || std::abs(ratio - static_cast<double>(step)) > 1e-9 * ratio)
    throw std::invalid_argument(fmt::format("the SINS output rate {} Hz does not divide imu.rate_hz ({} Hz) into a whole "
                                            "number of IMU samples", rate_hz, rig.imu.rate_hz));
  std::vector<std::size_t> out;
  for (std::size_t i = step - 1; i < data.imu.size(); i += step) out.push_back(i);
  return out;
}

// An INS solution that has left the mechanization's domain (past ±kInsMaxLatitudeDeg, or not
// finite) is not a position: from then on every epoch reports `diverged` at the last state inside it.
struct DivergenceWatch {
  std::optional<InsState> last_good;  // the start (which the rig's checks hold inside), then each good state
  bool diverged = false;
  NavigationFix fix(const InsState& s) {
    if (!diverged && in_ins_domain(s)) {
      last_good = s;
      return fix_of(s);
    }
    diverged = true;
    NavigationFix f = last_good ? fix_of(*last_good) : fix_of(s);
    f.t_s = s.t_s;
    f.status = "diverged";
    return f;
  }
};

// The INS alone, its state at every compass epoch.
std::vector<InsState> run_sins(const NavigationDataset& data, const std::vector<std::size_t>& at,
                               const MechanizationOptions& options) {
  std::vector<InsState> out;
  InsState s = data.initial;
  std::size_t next = 0;
  for (std::size_t i = 0; i < data.imu.size() && next < at.size(); ++i) {
    s = mechanize(s, i == 0 ? data.imu[0] : data.imu[i - 1], data.imu[i], options);
    if (i == at[next]) {
      out.push_back(s);
      ++next;
    }
  }
  return out;
}

struct SunModel {
  SunTrack track;
  UtcTime start;
  // δ and GHA at t (one interpolation of the track for both).
  std::pair<double, double> dec_gha_rad(double t) const {
    const SunTrack::HourAngle h = track.hour_angle_at(start.plus_seconds(t));
    return {std::atan2(h.sin_dec, h.cos_dec), std::atan2(h.sin_gha, h.cos_gha)};
  }
};

// The accelerometers' level over a reading's interval (the IMU samples after the previous reading):
// the up direction in b, the mean specific force normalized (f^b = C_n^b·(0, 0, g) when the vehicle
// neither accelerates nor turns), and whether it was steady enough to trust [C]: the mean |f| within
// 5e-3 m/s² (500 µg) of g and the mean rate below 0.05°/s (the Earth's is 0.004°/s). A 0.5 m/s²
// acceleration changes |f| by 0.013 m/s², a 3°/s turn exceeds the rate; a 0.5° level error then
// corrupts H^n by up to 0.5°, worth ~55 km of PNS.
struct Level {
  Vec3 up_b{};
  bool steady = false;
};
Level level_of(const NavigationDataset& data, const std::vector<std::size_t>& at, std::size_t k, double g) {
  Eigen::Vector3d dv = Eigen::Vector3d::Zero(), dtheta = Eigen::Vector3d::Zero();
  const std::size_t first = k == 0 ? 0 : at[k - 1] + 1;
  for (std::size_t i = first; i <= at[k]; ++i) dv += data.imu[i].dv, dtheta += data.imu[i].dtheta;
  const double T = data.imu[at[k]].t_s - (first == 0 ? 0.0 : data.imu[first - 1].t_s);
  const bool steady = std::abs(dv.norm() / T - g) <= 5e-3 && dtheta.norm() / T <= deg2rad(0.05);
  dv.normalize();
  return {{dv.x(), dv.y(), dv.z()}, steady};
}

// A reading's sighting for PNS: the zenith angle of the units' sun levelled by the accelerometers
// (C_bn null: an unsteady reading gets weight 0) or by the attitude C_bn; weight 0 without a sun.
ZenithSighting pns_sighting(const NavigationDataset& data, const std::vector<std::size_t>& at, std::size_t k,
                            const UnitSun& sun, const Eigen::Matrix3d* C_bn, double g) {
  double H = kNaN;
  if (sun.status == UnitSunStatus::Ok && !C_bn) {
    const Level level = level_of(data, at, k, g);
    if (level.steady) H = std::asin(std::clamp(vec3::dot(level.up_b, sun.s_b), -1.0, 1.0));
  } else if (sun.status == UnitSunStatus::Ok) {
    H = elevation_n(sun, *C_bn);
  }
  return {data.start.plus_seconds(data.compass[k].t_s), std::isfinite(H) ? 90 - rad2deg(H) : 90.0,
          std::isfinite(H) ? 1.0 : 0.0};
}

// The positioning fit's options for every PNS window of a run: one track at the start's site
// (compass/positioning.h: the parallax over the PNS's few km is far below its noise), and the root
// nearest the prior only.
PositionOptions pns_options(const NavigationDataset& data, const Sky& sky) {
  PositionOptions options;
  options.sun = sky.sun;
  const double end = data.compass.empty() ? 1.0 : data.compass.back().t_s + 1.0;
  options.ephemeris = std::make_shared<const SunTrack>(
      data.start, data.start.plus_seconds(end),
      Site{rad2deg(data.initial.lat_rad), rad2deg(data.initial.lon_rad), data.initial.h_m}, sky.sun);
  options.second_root = false;
  return options;
}

// navigation.measurement pns-fix: the PNS fix of each window of navigation.pns_window_s that does
// not overlap the last (the readings after the previous fix), its prior the filter's position.
struct PnsFixWindow {
  std::vector<ZenithSighting> sightings;
  double start_s = 0;
};
std::optional<PositionFix> pns_window_fix(PnsFixWindow& w, double t_s, double window_s, const InsState& s,
                                          const PositionOptions& options) {
  if (t_s - w.start_s < window_s - 1e-9) return std::nullopt;
  const PositionFix fix = fix_position(w.sightings, {rad2deg(s.lat_rad), rad2deg(s.lon_rad), s.h_m}, options);
  w.sightings.clear();
  w.start_s = t_s;
  return fix;
}

// The fit's covariance of north and east (m²), when it has one.
std::optional<Eigen::Matrix2d> fix_covariance_m2(const PositionRoot& r) {
  if (!std::isfinite(r.sd_north_km) || !std::isfinite(r.sd_east_km) || !(std::abs(r.corr_north_east) < 1))
    return std::nullopt;  // no covariance, or not positive definite
  const double n = r.sd_north_km * 1e3, e = r.sd_east_km * 1e3, c = r.corr_north_east * n * e;
  Eigen::Matrix2d cov;
  cov << n * n, c, c, e * e;
  return cov;
}

// The rest detector over a reading's interval (the IMU samples after the previous reading, as
// level_of's), at the filter's attitude and bias estimates.
ZeroVelocityTest rest_test(const NavigationDataset& data, const std::vector<std::size_t>& at, std::size_t k,
                           const InsFilter& filter, const ZeroVelocityDetector& detector) {
  const std::size_t first = k == 0 ? 0 : at[k - 1] + 1;
  if (at[k] + 1 - first < 2) return {kNaN, kNaN, false};  // one sample a reading: no window to test
  const double t0 = first == 0 ? data.initial.t_s : data.imu[first - 1].t_s;
  const InsState& s = filter.state();
  RestModel rest;
  rest.g_mps2 = normal_gravity(s.lat_rad, s.h_m);
  rest.omega_b = s.C_bn().transpose() * omega_ie_n(s.lat_rad) + filter.gyro_bias();
  rest.accel_bias = filter.accel_bias();
  return detector.test(std::span(data.imu).subspan(first, at[k] + 1 - first), t0, rest);
}

// The INS with the filter, its state and the filter's record at every compass epoch.
// The filtered state at a compass epoch, with the bias estimates feed_back moves too.
struct FilteredEpoch {
  InsState state;
  Eigen::Vector3d gyro_bias, accel_bias;
};

// The RTS smoother over the filter's epochs (ins/smoother.h): each filtered state with its smoothed
// correction fed back as the filter's own are (a held height's δh and δv_U get none: their rows of
// P, hence of C, are 0); the epochs past a divergence keep the filter's rows.
std::vector<NavigationFix> smoothed_fixes(const std::vector<FilterRecord>& records,
                                          const std::vector<FilteredEpoch>& filtered,
                                          const std::vector<NavigationFix>& integrated, const InsState& start,
                                          std::vector<Matrix15>& P) {
  const std::vector<SmoothedEpoch> smoothed = rts_smooth(records);
  P.clear();
  for (const SmoothedEpoch& e : smoothed) P.push_back(e.P);
  std::vector<NavigationFix> out;
  DivergenceWatch watch{start};
  for (std::size_t k = 0; k < smoothed.size(); ++k) {
    FilteredEpoch e = filtered[k];
    feed_back(smoothed[k].correction, e.state, e.gyro_bias, e.accel_bias);
    e.state.lon_rad = std::remainder(e.state.lon_rad, 2 * std::numbers::pi);
    out.push_back(watch.fix(e.state));
  }
  for (std::size_t k = out.size(); k < integrated.size(); ++k) out.push_back(integrated[k]);
  return out;
}

// navigation.measurement pns-fix at one reading: its sighting into the window, and at the window's
// end the fix, when usable with a covariance, as a position update.
void pns_fix_update(const NavigationDataset& data, const std::vector<std::size_t>& at, std::size_t k, double g,
                    const Rig& rig, const PositionOptions& options, PnsFixWindow& window, InsFilter& filter,
                    FilterEpoch& f) {
  f.update = f.azimuth_update = {kNaN, kNaN, kNaN, kNaN};  // no sun update
  window.sightings.push_back(pns_sighting(data, at, k, f.sun, nullptr, g));
  const std::optional<PositionFix> fix =
      pns_window_fix(window, data.compass[k].t_s, rig.navigation.pns_window_s, filter.state(), options);
  const std::optional<Eigen::Matrix2d> cov = fix && fix->usable() ? fix_covariance_m2(fix->chosen) : std::nullopt;
  if (!cov) {
    filter.propagate_covariance();
    return;
  }
  f.pns_fix_lat_rad = deg2rad(fix->chosen.lat_deg);
  f.pns_fix_lon_rad = deg2rad(fix->chosen.lon_deg);
  f.position_update = filter.update_position(f.pns_fix_lat_rad, f.pns_fix_lon_rad, *cov);
}

void run_integrated(const NavigationDataset& data, const std::vector<std::size_t>& at,
                    std::span<const UnitMount> mounts, const Rig& rig, const Sky& sky, const SunModel& sun,
                    NavigationRun& run, std::vector<NavigationFix>& fixes, std::vector<NavigationFix>* smoothed,
                    const Progress& progress) {
  const FilterSettings settings = filter_settings(rig, data);
  InsFilter filter(data.initial, initial_covariance(rig, data), settings);
  const bool pns_fix = settings.measurement == FilterSettings::SunMeasurement::PnsFix;
  const PositionOptions pns = pns_fix ? pns_options(data, sky) : PositionOptions{};
  PnsFixWindow window{{}, data.initial.t_s};
  DivergenceWatch watch{data.initial};
  std::vector<FilterRecord> records;    // for the smoother
  std::vector<FilteredEpoch> filtered;
  // H^n's level: the filter's attitude (Z21) or the accelerometers (navigation.integrated_level).
  const bool accelerometer = rig.navigation.integrated_level == "accelerometer";
  const double g = normal_gravity(data.initial.lat_rad, data.initial.h_m);
  const ImuErrorSpec imu = imu_error_spec(rig.imu);
  const ZeroVelocityDetector detector{imu.gyro.white_noise, imu.accel.white_noise};
  std::size_t next = 0;
  for (std::size_t i = 0; i < data.imu.size() && next < at.size(); ++i) {
    filter.predict(data.imu[i]);
    if (i != at[next]) continue;
    const CompassEpoch& e = data.compass[next++];
    FilterEpoch f;
    f.t_s = filter.state().t_s;
    if (rig.navigation.zupt) {
      const ZeroVelocityTest rest = rest_test(data, at, next - 1, filter, detector);
      f.rest_statistic = rest.statistic;
      if (rest.at_rest) f.zero_velocity = filter.update_zero_velocity(rig.navigation.zupt_sigma_mps);
    }
    f.sun = sun_from_units(e.units, mounts);
    if (!accelerometer) {
      f.elevation_rad = elevation_n(f.sun, filter.state().C_bn());
    } else if (f.sun.status == UnitSunStatus::Ok) {  // unsteady readings: no measurement
      const Level level = level_of(data, at, next - 1, g);
      f.elevation_rad = level.steady ? std::asin(std::clamp(vec3::dot(level.up_b, f.sun.s_b), -1.0, 1.0)) : kNaN;
    } else {
      f.elevation_rad = kNaN;
    }
    const auto [dec, gha] = sun.dec_gha_rad(e.t_s);
    f.model_elevation_rad =
        std::asin(sun_elevation_model(filter.state().lat_rad, filter.state().lon_rad, dec, gha).sin_H);
    f.model_azimuth_rad = sun_azimuth_model(filter.state().lat_rad, filter.state().lon_rad, dec, gha).azimuth;
    f.azimuth_rad = kNaN;
    if (pns_fix) {
      pns_fix_update(data, at, next - 1, g, rig, pns, window, filter, f);
    } else if (std::isfinite(f.elevation_rad)) {
      const Vec3 s_n = sun_in_nav(f.sun.s_b, axes_of(filter.state().C_bn())).s_n;
      f.azimuth_rad = std::atan2(s_n[0], s_n[1]);
      const SunUpdate u = filter.update({f.t_s, f.elevation_rad, dec, gha, s_n[0], s_n[1]});
      f.update = u.elevation;
      f.azimuth_update = u.azimuth;
    } else {
      f.update = f.azimuth_update = {kNaN, kNaN, kNaN, kNaN};
      filter.propagate_covariance();
    }
    const InsState& s = filter.state();
    const InsFilterEpoch record = filter.end_epoch();
    fixes.push_back(watch.fix(s));
    if (smoothed && !watch.diverged) {
      records.push_back({record.Phi, record.P_prior, record.P_post, record.correction});
      filtered.push_back({s, filter.gyro_bias(), filter.accel_bias()});
    }
    if (watch.diverged) {  // the filter's record ends here (filter.csv); the solution says diverged
      for (std::size_t k = next; k < at.size(); ++k) {
        NavigationFix d = fixes.back();
        d.t_s = data.imu[at[k]].t_s;
        fixes.push_back(d);
      }
      progress.advance(static_cast<long long>(at.size() - next + 1));
      break;
    }
    const EarthRadii r = earth_radii(s.lat_rad);
    f.sigma_north_m = std::sqrt(filter.P()(kDLat, kDLat)) * (r.R_M + s.h_m);
    f.sigma_east_m = std::sqrt(filter.P()(kDLon, kDLon)) * (r.R_N + s.h_m) * std::cos(s.lat_rad);
    f.sigma_heading_rad = std::sqrt(filter.P()(kPhi + 2, kPhi + 2));
    f.corr_north_east = filter.P()(kDLat, kDLon) / std::sqrt(filter.P()(kDLat, kDLat) * filter.P()(kDLon, kDLon));
    run.filter.push_back(f);
    progress.advance(1);
  }
  run.filter_summary = filter.summary();
  run.final_P = filter.P();
  if (watch.diverged) run.filter_summary.status = FilterStatus::Diverged;
  if (smoothed)
    *smoothed = smoothed_fixes(records, filtered, fixes, data.initial, run.smoothed_P);
}

// PNS: at each epoch the positioning fit over the window's elevations (the SINS's attitude).
std::vector<NavigationFix> run_pns(const NavigationDataset& data, const std::vector<std::size_t>& at,
                                   const std::vector<InsState>& sins,
                                   std::span<const UnitMount> mounts, const Rig& rig, const Sky& sky,
                                   const Progress& progress) {
  const std::size_t n = sins.size();
  const bool accelerometer = rig.navigation.pns_level == "accelerometer";
  const double g = normal_gravity(data.initial.lat_rad, data.initial.h_m);
  std::vector<ZenithSighting> sightings(n);
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Matrix3d C_bn = sins[k].C_bn();
    sightings[k] = pns_sighting(data, at, k, sun_from_units(data.compass[k].units, mounts), accelerometer ? nullptr : &C_bn, g);
  }
  const PositionOptions options = pns_options(data, sky);
  const Site prior{rad2deg(data.initial.lat_rad), rad2deg(data.initial.lon_rad), data.initial.h_m};
  const double window = rig.navigation.pns_window_s;
  const double period = n > 1 ? data.compass[1].t_s - data.compass[0].t_s : 0.0;
  std::vector<NavigationFix> out(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 8), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t k = r.begin(); k < r.end(); ++k) {
      NavigationFix& f = out[k];
      f = {data.compass[k].t_s, kNaN, kNaN, data.initial.h_m, sins[k].euler(), "window_filling"};
      // A fix once the window is full (its readings span window − one period): a shorter arc of the
      // sun fixes the position along its azimuth only, and the fit's second coordinate is noise.
      if (data.compass[k].t_s - data.compass[0].t_s < window - period - 1e-9) continue;
      std::size_t first = k;
      while (first > 0 && data.compass[k].t_s - data.compass[first - 1].t_s < window - 1e-9) --first;
      const PositionFix fix = fix_position(std::span(sightings).subspan(first, k + 1 - first), prior, options);
      f.status = std::string(position_termination_name(fix.chosen.summary.termination));
      if (fix.usable()) {
        f.lat_rad = deg2rad(fix.chosen.lat_deg);
        f.lon_rad = deg2rad(fix.chosen.lon_deg);
      }
    }
    progress.advance(static_cast<long long>(r.size()));
  });
  return out;
}

}  // namespace

NavigationRun navigate(const NavigationDataset& data, const Rig& rig, const NavigationOptions& options,
                       const Progress& progress) {
  const std::span<const UnitMount> mounts = options.mounts.empty() ? data.mounts : options.mounts;
  if (options.mounts.size() > 0 && options.mounts.size() != data.mounts.size())
    throw std::invalid_argument(fmt::format("navigate: {} calibrated units for a compass of {}", options.mounts.size(),
                                            data.mounts.size()));
  const std::vector<std::size_t> at = epoch_samples(data, mounts.size());
  const Sky sky = sky_of(rig);
  NavigationRun run;
  run.modes = options.modes;
  run.vertical_channel = vertical_channel_text(rig, data);
  run.start = start_text(data, rig);
  const auto wants = [&](NavigationMode m) { return std::find(run.modes.begin(), run.modes.end(), m) != run.modes.end(); };
  if (data.compass.empty() && (wants(NavigationMode::Pns) || wants(NavigationMode::Integrated) ||
                               wants(NavigationMode::Smoothed)))
    throw std::invalid_argument("no compass readings (units.csv): PNS and the integrated mode need them; an IMU log "
                                "alone runs mode sins");
  const std::vector<std::size_t> sins_at = sins_samples(data, rig, options.sins_rate_hz, at);
  if (data.truth && wants(NavigationMode::Sins))
    for (std::size_t i : sins_at)
      if (!find_truth(*data.truth, data.imu[i].t_s))
        throw std::invalid_argument(fmt::format("truth.csv has no row at t = {} s, a SINS output time (the truth must "
                                                "hold every time the solution is reported at)", data.imu[i].t_s));
  std::string stage = "navigate:";
  for (NavigationMode m : run.modes) stage += fmt::format(" {}", navigation_mode_name(m));
  // The filter's epochs once for the integrated and the smoothed modes (one run of the filter).
  const bool filter_runs = wants(NavigationMode::Integrated) || wants(NavigationMode::Smoothed);
  progress.begin(stage, static_cast<long long>(at.size() * ((wants(NavigationMode::Pns) ? 1 : 0) + (filter_runs ? 1 : 0)) +
                                                (wants(NavigationMode::Sins) ? sins_at.size() : 0)));
  // The filter beside the SINS and the PNS (which takes the SINS's attitude): independent
  // computations, each the same whichever thread runs it.
  std::vector<InsState> sins, sins_output;
  std::vector<NavigationFix> pns, integrated, smoothed;
  tbb::parallel_invoke(
      [&] {
        if (!wants(NavigationMode::Sins) && !wants(NavigationMode::Pns)) return;
        const MechanizationOptions mech = filter_settings(rig, data).mechanization;
        if (wants(NavigationMode::Pns)) sins = run_sins(data, at, mech);
        if (wants(NavigationMode::Sins)) {
          sins_output = sins_at == at && wants(NavigationMode::Pns) ? sins : run_sins(data, sins_at, mech);
          progress.advance(static_cast<long long>(sins_at.size()));
        }
        if (wants(NavigationMode::Pns)) pns = run_pns(data, at, sins, mounts, rig, sky, progress);
      },
      [&] {
        if (!filter_runs) return;
        const double end = data.imu.empty() ? 1.0 : data.imu.back().t_s + 1.0;
        const SunModel sun{SunTrack(data.start, data.start.plus_seconds(end),
                                    {rad2deg(data.initial.lat_rad), rad2deg(data.initial.lon_rad), data.initial.h_m},
                                    sky.sun),
                           data.start};
        run_integrated(data, at, mounts, rig, sky, sun, run, integrated,
                       wants(NavigationMode::Smoothed) ? &smoothed : nullptr, progress);
      });
  progress.finish();
  for (const NavigationFix& f : pns) run.pns_usable += std::isfinite(f.lat_rad) ? 1 : 0;
  for (NavigationMode m : run.modes) {
    if (m == NavigationMode::Sins) {
      std::vector<NavigationFix> fixes;
      DivergenceWatch watch{data.initial};
      for (const InsState& st : sins_output) fixes.push_back(watch.fix(st));
      run.fixes.push_back(std::move(fixes));
    } else {
      run.fixes.push_back(m == NavigationMode::Pns ? pns : m == NavigationMode::Smoothed ? smoothed : integrated);
    }
  }
  return run;
}

std::string vertical_channel_text(const Rig& rig, const NavigationDataset& data) {
  if (rig.navigation.hold_height && data.stated_start)
    return fmt::format("held  # navigation.hold_height: h = {} m (start.yaml's h_m), v_U = 0", data.initial.h_m);
  if (rig.navigation.hold_height)
    return fmt::format("held  # navigation.hold_height: h = {} m (sky.height_m), v_U = 0", sky_of(rig).site.height_m);
  return "free  # navigation.hold_height false: h and v_U integrated (gravity: docs/physics.md §18.1)";
}

std::string start_text(const NavigationDataset& data, const Rig& rig) {
  if (data.stated_start) return "start.yaml  # the dataset's stated start and its P0 blocks";
  if (data.truth && rig.navigation.initial_errors == "drawn")
    return "rig  # the truth's start plus errors drawn from P0 (navigation.initial_errors drawn)";
  return "rig  # sky.lat_deg/lon_deg/height_m, trajectory.heading/pitch/roll_deg and speed_mps, navigation.*_sigma*";
}

PositionError position_error(const NavigationFix& fix, const TruthSample& truth) {
  const EarthRadii r = earth_radii(truth.lat_rad);
  const double dL = fix.lat_rad - truth.lat_rad;
  const double dlon = std::remainder(fix.lon_rad - truth.lon_rad, 2 * std::numbers::pi);
  return {rad2deg(dL), rad2deg(dlon), dL * (r.R_M + truth.h_m), dlon * (r.R_N + truth.h_m) * std::cos(truth.lat_rad)};
}

const TruthSample* find_truth(const NavigationTruth& truth, double t_s) {
  const auto& v = truth.trajectory;
  auto it = std::lower_bound(v.begin(), v.end(), t_s - 1e-3, [](const TruthSample& s, double t) { return s.t_s < t; });
  return it != v.end() && std::abs(it->t_s - t_s) <= 1e-3 ? &*it : nullptr;
}

const TruthSample& truth_at(const NavigationTruth& truth, double t_s) {
  if (const TruthSample* s = find_truth(truth, t_s)) return *s;
  throw std::invalid_argument(fmt::format("no truth at {} s", t_s));
}

ErrorStatistics error_statistics(std::span<const double> errors) {
  ErrorStatistics s;
  double sum = 0, sum_abs = 0, sum2 = 0;
  for (double e : errors) {
    if (!std::isfinite(e)) continue;
    ++s.count;
    sum += e;
    sum_abs += std::abs(e);
    sum2 += e * e;
  }
  if (s.count == 0) return {kNaN, kNaN, kNaN, 0};
  const double n = s.count, mean = sum / n;
  double dev2 = 0;  // about the mean in a second pass: no cancellation
  for (double e : errors)
    if (std::isfinite(e)) dev2 += (e - mean) * (e - mean);
  s.mae = sum_abs / n;
  s.rmse = std::sqrt(sum2 / n);
  s.std = std::sqrt(dev2 / n);
  return s;
}

}  // namespace polrig
