#include "polrig/ins/trajectory.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string_view>

#include <fmt/format.h>

#include "polrig/ins/earth.h"

namespace polrig {
namespace {

// The commanded part of the truth at one instant: speed and Euler angles with their rates.
struct Motion {
  double u = 0, du = 0;
  double yaw = 0, dyaw = 0;
  double pitch = 0, dpitch = 0;
  double roll = 0;
};

struct Position {
  double L = 0, lon = 0, h = 0;
};

Eigen::Vector3d velocity_n(const Motion& m) {
  const double cp = std::cos(m.pitch);
  return m.u * Eigen::Vector3d(std::sin(m.yaw) * cp, std::cos(m.yaw) * cp, std::sin(m.pitch));
}

Eigen::Vector3d acceleration_n(const Motion& m) {
  const double sy = std::sin(m.yaw), cy = std::cos(m.yaw), sp = std::sin(m.pitch), cp = std::cos(m.pitch);
  const Eigen::Vector3d dir(sy * cp, cy * cp, sp);
  const Eigen::Vector3d ddir(cy * cp * m.dyaw - sy * sp * m.dpitch, -sy * cp * m.dyaw - cy * sp * m.dpitch,
                             cp * m.dpitch);
  return m.du * dir + m.u * ddir;
}

Position position_rate(const Position& p, const Eigen::Vector3d& v) {
  const EarthRadii r = earth_radii(p.L);
  return {v.y() / (r.R_M + p.h), v.x() / ((r.R_N + p.h) * std::cos(p.L)), v.z()};
}

Position add(const Position& p, const Position& d, double s) {
  return {p.L + s * d.L, p.lon + s * d.lon, p.h + s * d.h};
}

// ω_nb^b of C_b^n = Rz(−ψ)·Rx(θ)·Ry(γ) with only ψ and θ changing.
Eigen::Vector3d omega_nb_b(const Motion& m) {
  const Eigen::Matrix3d RyT = Eigen::AngleAxisd(-m.roll, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Matrix3d RxT = Eigen::AngleAxisd(-m.pitch, Eigen::Vector3d::UnitX()).toRotationMatrix();
  return RyT * (RxT * Eigen::Vector3d(0, 0, -m.dyaw) + Eigen::Vector3d(m.dpitch, 0, 0));
}

struct BodyRates {
  Eigen::Vector3d omega_ib_b, f_b;
};

BodyRates body_rates(const Motion& m, const Position& p) {
  const Eigen::Matrix3d C_bn = C_bn_from_euler({m.roll, m.pitch, m.yaw});
  const Eigen::Vector3d v = velocity_n(m);
  const Eigen::Vector3d w_ie = omega_ie_n(p.L), w_en = omega_en_n(v, p.L, p.h);
  const Eigen::Vector3d a = acceleration_n(m) + (2 * w_ie + w_en).cross(v) - gravity_n(p.L, p.h);
  return {omega_nb_b(m) + C_bn.transpose() * (w_ie + w_en), C_bn.transpose() * a};
}

Motion motion_at(const Motion& start, const Segment& s, double t) {
  Motion m = start;
  m.du = m.dyaw = m.dpitch = 0;
  switch (s.kind) {
    case SegmentKind::Static: break;
    case SegmentKind::Accelerate: m.du = s.rate; break;
    case SegmentKind::Turn: m.dyaw = s.rate; break;
    case SegmentKind::Climb: m.dpitch = s.rate; break;
  }
  m.u += m.du * t;
  m.yaw += m.dyaw * t;
  m.pitch += m.dpitch * t;
  return m;
}

// One IMU interval [t0, t0 + dt] of the truth motion(t): ω_ib^b and f^b integrated by Simpson's
// rule over M substeps, the position p carried between the nodes by RK4 (and left at the end).
template <class MotionAt>
ImuSample integrate_interval(const MotionAt& motion, double t0, double dt, int M, Position& p) {
  const double hs = dt / M;
  const BodyRates r0 = body_rates(motion(t0), p);
  Eigen::Vector3d sum_w = r0.omega_ib_b, sum_f = r0.f_b;
  const auto rate = [&](double tt, const Position& q) { return position_rate(q, velocity_n(motion(tt))); };
  for (int j = 1; j <= M; ++j) {
    const double ta = t0 + (j - 1) * hs;
    const Position k1 = rate(ta, p);
    const Position k2 = rate(ta + hs / 2, add(p, k1, hs / 2));
    const Position k3 = rate(ta + hs / 2, add(p, k2, hs / 2));
    const Position k4 = rate(ta + hs, add(p, k3, hs));
    p = {p.L + hs / 6 * (k1.L + 2 * k2.L + 2 * k3.L + k4.L), p.lon + hs / 6 * (k1.lon + 2 * k2.lon + 2 * k3.lon + k4.lon),
         p.h + hs / 6 * (k1.h + 2 * k2.h + 2 * k3.h + k4.h)};
    const BodyRates r = body_rates(motion(ta + hs), p);
    const double w = (j == M) ? 1.0 : (j % 2 == 1 ? 4.0 : 2.0);
    sum_w += w * r.omega_ib_b;
    sum_f += w * r.f_b;
  }
  return {t0 + dt, sum_w * hs / 3, sum_f * hs / 3};
}

TruthSample truth_of(double t, const Motion& m, const Position& p) {
  TruthSample s;
  s.t_s = t;
  s.lat_rad = p.L;
  s.lon_rad = std::remainder(p.lon, 2 * std::numbers::pi);  // [−π, π]: a run round a parallel
  s.h_m = p.h;
  s.C_bn = C_bn_from_euler({m.roll, m.pitch, m.yaw});
  s.euler = euler_from_C_bn(s.C_bn);
  s.v_n = velocity_n(m);
  return s;
}

// The IMU's sampling both generators share; `what` names the generator in the message.
void check_sampling(std::string_view what, double imu_rate_hz, int substeps) {
  if (!(imu_rate_hz > 0)) throw std::invalid_argument(fmt::format("{}: IMU rate {} Hz must be > 0", what, imu_rate_hz));
  if (substeps < 2 || substeps % 2 != 0)
    throw std::invalid_argument(fmt::format("{}: substeps {} must be even and ≥ 2", what, substeps));
}

void check(const TrajectorySpec& spec) {
  check_sampling("trajectory", spec.imu_rate_hz, spec.substeps);
  if (spec.speed_mps < 0)
    throw std::invalid_argument(fmt::format("trajectory: speed {} m/s must be ≥ 0", spec.speed_mps));
  if (!(spec.vibration_mps2 >= 0) || !std::isfinite(spec.vibration_mps2))
    throw std::invalid_argument(fmt::format("trajectory: vibration {} m/s² must be finite and ≥ 0", spec.vibration_mps2));
}

long intervals_of(const Segment& s, double rate_hz, std::size_t index) {
  const double n = s.duration_s * rate_hz;
  const long k = std::lround(n);
  if (!(s.duration_s > 0) || std::abs(n - static_cast<double>(k)) > 1e-9 * std::max(1.0, n))
    throw std::invalid_argument(fmt::format(
        "trajectory: segment {} ({}) lasts {} s, not a positive whole number of IMU intervals at {} Hz",
        index, segment_kind_name(s.kind), s.duration_s, rate_hz));
  return k;
}

}  // namespace

std::string_view segment_kind_name(SegmentKind k) {
  switch (k) {
    case SegmentKind::Static: return "static";
    case SegmentKind::Accelerate: return "accelerate";
    case SegmentKind::Turn: return "turn";
    case SegmentKind::Climb: return "climb";
  }
  return "?";
}

namespace {

// The vibration's velocity in b at a truth sample, v_i = s·√2·a/ω_i·sin(ω_i t), s = min(1, u/1 m/s):
// each IMU interval's Δv gains v(t_k) − v(t_{k−1}), the exact integral of its acceleration.
Eigen::Vector3d vibration_velocity(const TruthSample& at, double rms_mps2) {
  const double scale = std::min(1.0, at.v_n.norm() / 1.0);
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    const double w = 2 * std::numbers::pi * kVibrationHz[i];
    v[i] = scale * std::sqrt(2.0) * rms_mps2 / w * std::sin(w * at.t_s);
  }
  return v;
}

void add_vibration(Trajectory& out, double rms_mps2) {
  for (std::size_t k = 0; k < out.imu.size(); ++k)
    out.imu[k].dv += vibration_velocity(out.truth[k + 1], rms_mps2) - vibration_velocity(out.truth[k], rms_mps2);
}

}  // namespace

Trajectory generate_trajectory(const TrajectorySpec& spec) {
  check(spec);
  const double dt = 1.0 / spec.imu_rate_hz;
  const int M = spec.substeps;
  Trajectory out;
  Motion seg_start{spec.speed_mps, 0, spec.attitude.yaw_rad, 0, spec.attitude.pitch_rad, 0, spec.attitude.roll_rad};
  Position p{spec.lat_rad, spec.lon_rad, spec.h_m};
  double t = 0;
  out.truth.push_back(truth_of(t, seg_start, p));
  for (std::size_t si = 0; si < spec.segments.size(); ++si) {
    const Segment& s = spec.segments[si];
    const long n = intervals_of(s, spec.imu_rate_hz, si);
    if (s.kind == SegmentKind::Static) {
      // A brake to rest ends at 0 up to rounding (a rate times a whole number of intervals).
      if (std::abs(seg_start.u) > 1e-9)
        throw std::invalid_argument(fmt::format("trajectory: segment {} is static while moving at {} m/s", si, seg_start.u));
      seg_start.u = 0;
    }
    if (s.kind == SegmentKind::Static) {
      // At rest ω_ib^b and f^b are constants (the position does not move): every interval's
      // increment is the same value·Δt, and the truth the same state at a later time.
      const Motion rest = motion_at(seg_start, s, 0);  // the previous segment's rates cleared
      const BodyRates r = body_rates(rest, p);
      TruthSample still = truth_of(t, rest, p);
      for (long k = 0; k < n; ++k) {
        t += dt;
        out.imu.push_back({t, r.omega_ib_b * dt, r.f_b * dt});
        still.t_s = t;
        out.truth.push_back(still);
      }
      continue;
    }
    const auto motion = [&](double tau) { return motion_at(seg_start, s, tau); };  // tau from the segment's start
    for (long k = 0; k < n; ++k) {
      const double tau0 = static_cast<double>(k) * dt;
      out.imu.push_back(integrate_interval(motion, tau0, dt, M, p));
      t += dt;
      out.imu.back().t_s = t;
      out.truth.push_back(truth_of(t, motion(tau0 + dt), p));
    }
    seg_start = motion_at(seg_start, s, static_cast<double>(n) * dt);
  }
  if (spec.vibration_mps2 > 0) add_vibration(out, spec.vibration_mps2);
  return out;
}

namespace {

// The sine-velocity truth at t: speed, yaw and pitch along v^n and their rates, from v and v̇:
//   u̇ = v·v̇/u,   ψ̇ = (v_N v̇_E − v_E v̇_N)/ρ²,   θ̇ = (ρ² v̇_U − v_U (v_E v̇_E + v_N v̇_N))/(ρ u²),
// ρ² = v_E² + v_N² (θ = atan2(v_U, ρ), ψ = atan2(v_E, v_N)).
Motion sine_velocity_motion(const SineVelocitySpec& spec, double t) {
  const double w = 2 * std::numbers::pi / spec.period_s;
  Eigen::Vector3d v, a;
  for (int i = 0; i < 3; ++i) {
    v[i] = spec.v_mean_enu[i] + spec.amplitude_enu[i] * std::sin(w * t + spec.phase_rad[i]);
    a[i] = spec.amplitude_enu[i] * w * std::cos(w * t + spec.phase_rad[i]);
  }
  const double rho2 = v.x() * v.x() + v.y() * v.y(), rho = std::sqrt(rho2), u = v.norm();
  Motion m;
  m.u = u;
  m.du = v.dot(a) / u;
  m.yaw = std::atan2(v.x(), v.y());
  m.dyaw = (v.y() * a.x() - v.x() * a.y()) / rho2;
  m.pitch = std::atan2(v.z(), rho);
  m.dpitch = (rho2 * a.z() - v.z() * (v.x() * a.x() + v.y() * a.y())) / (rho * u * u);
  return m;
}

void check(const SineVelocitySpec& spec) {
  check_sampling("sine-velocity trajectory", spec.imu_rate_hz, spec.substeps);
  if (!(spec.period_s > 0))
    throw std::invalid_argument(fmt::format("sine-velocity trajectory: period {} s must be > 0", spec.period_s));
  const double intervals = spec.duration_s * spec.imu_rate_hz;
  if (!(spec.duration_s > 0) || std::abs(intervals - std::round(intervals)) > 1e-9 * std::max(1.0, intervals))
    throw std::invalid_argument(fmt::format(
        "sine-velocity trajectory: {} s is not a positive whole number of IMU intervals at {} Hz", spec.duration_s,
        spec.imu_rate_hz));
  // ρ ≥ |v̄_h| − |A_h| > 0: the heading is defined throughout.
  const double mean_h = spec.v_mean_enu.head<2>().norm(), amplitude_h = spec.amplitude_enu.head<2>().norm();
  if (!(mean_h > amplitude_h))
    throw std::invalid_argument(fmt::format(
        "sine-velocity trajectory: the mean horizontal speed {} m/s must exceed the amplitude {} m/s "
        "(the heading follows the velocity)", mean_h, amplitude_h));
}

}  // namespace

Trajectory generate_sine_velocity_trajectory(const SineVelocitySpec& spec) {
  check(spec);
  const double dt = 1.0 / spec.imu_rate_hz;
  const long n = std::lround(spec.duration_s * spec.imu_rate_hz);
  const auto motion = [&](double t) { return sine_velocity_motion(spec, t); };
  Trajectory out;
  Position p{spec.lat_rad, spec.lon_rad, spec.h_m};
  out.truth.push_back(truth_of(0, motion(0), p));
  for (long k = 0; k < n; ++k) {
    const double t0 = static_cast<double>(k) * dt, t1 = static_cast<double>(k + 1) * dt;
    out.imu.push_back(integrate_interval(motion, t0, dt, spec.substeps, p));
    out.imu.back().t_s = t1;
    out.truth.push_back(truth_of(t1, motion(t1), p));
  }
  return out;
}

}  // namespace polrig
