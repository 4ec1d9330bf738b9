#include "polrig/ins/mechanization.h"

#include <cmath>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>

#include "polrig/ins/earth.h"

namespace polrig {
namespace {

struct Rates {
  Eigen::Vector3d w_ie, w_en, g;
};

// The Earth at one point of the step: its radii, normal gravity (one GeographicLib call), rate and
// tan L, held for the step's three rate evaluations: over 10 ms they change by ~1e-10 of themselves.
struct EarthPoint {
  double L = 0, h = 0;
  EarthRadii r;
  Eigen::Vector3d g, w_ie;
  double tan_L = 0;
};

EarthPoint earth_at(double L, double h) {
  return {L, h, earth_radii(L), gravity_n(L, h), omega_ie_n(L), std::tan(L)};
}

Rates rates_at(const EarthPoint& e, const Eigen::Vector3d& v) {
  const double RNh = e.r.R_N + e.h;
  return {e.w_ie, {-v.y() / (e.r.R_M + e.h), v.x() / RNh, v.x() * e.tan_L / RNh}, e.g};
}

// The velocity increment over dt from the state's velocity v and the rates r.
Eigen::Vector3d delta_v(const Eigen::Matrix3d& C_bn, const Eigen::Vector3d& dv_f_b, const Eigen::Vector3d& v,
                        const Rates& r, double dt) {
  const Eigen::Vector3d zeta = (r.w_ie + r.w_en) * dt;
  const Eigen::Vector3d dv_f_n = quaternion_from_rotation_vector(-0.5 * zeta) * (C_bn * dv_f_b);
  return dv_f_n + (r.g - (2 * r.w_ie + r.w_en).cross(v)) * dt;
}

}  // namespace

InsState mechanize(const InsState& s, const ImuSample& prev, const ImuSample& cur,
                   const MechanizationOptions& options) {
  const double dt = cur.t_s - s.t_s;
  if (!(dt > 0)) throw std::invalid_argument(fmt::format("mechanize: interval {} s must be > 0", dt));
  const Eigen::Matrix3d C_bn = s.C_bn();

  // Velocity: a first pass (the start's velocity in the transport rate and Coriolis) gives the
  // midpoint's velocity, the second pass uses it; the Earth at the midpoint in both. The rotation
  // compensation as half-angle rotations in b and in n (not I ± ½[·×]): for a static IMU they
  // cancel exactly, where the first-order forms leave ¼[ζ×]²g·Δt per step.
  const Eigen::Vector3d dv_f_b = quaternion_from_rotation_vector(0.5 * cur.dtheta) * cur.dv +
                                 (prev.dtheta.cross(cur.dv) + prev.dv.cross(cur.dtheta)) / 12.0;
  // The Earth at the step's midpoint, extrapolated with the start's velocity (ω_en^n of that
  // estimate is used only in the first pass).
  EarthRadii r0 = earth_radii(s.lat_rad);
  const double h_mid = options.hold_height_m ? s.h_m : s.h_m + 0.5 * s.v_n.z() * dt;
  const EarthPoint mid{earth_at(s.lat_rad + 0.5 * s.v_n.y() * dt / (r0.R_M + h_mid), h_mid)};
  const Eigen::Vector3d v_mid0 = s.v_n + 0.5 * delta_v(C_bn, dv_f_b, s.v_n, rates_at(mid, s.v_n), dt);
  InsState n = s;
  n.t_s = cur.t_s;
  n.v_n = s.v_n + delta_v(C_bn, dv_f_b, v_mid0, rates_at(mid, v_mid0), dt);
  if (options.hold_height_m) n.v_n.z() = 0;

  // Position: trapezoidal velocity; h, then L at the mean height, then λ at the mean L and h (the
  // midpoint's radii).
  const Eigen::Vector3d v_avg = 0.5 * (s.v_n + n.v_n);
  n.h_m = options.hold_height_m ? *options.hold_height_m : s.h_m + v_avg.z() * dt;
  const double h_avg = 0.5 * (s.h_m + n.h_m);
  n.lat_rad = s.lat_rad + v_avg.y() * dt / (mid.r.R_M + h_avg);
  const double L_avg = 0.5 * (s.lat_rad + n.lat_rad);
  // Wrapped to [−π, π]: a run round a parallel stays a longitude (exact for one already inside).
  n.lon_rad = std::remainder(s.lon_rad + v_avg.x() * dt / ((mid.r.R_N + h_avg) * std::cos(L_avg)), 2 * std::numbers::pi);

  // Attitude: the body's rotation (with coning) and the n-frame's over the interval, at the midpoint.
  const Eigen::Vector3d phi = cur.dtheta + prev.dtheta.cross(cur.dtheta) / 12.0;
  const Rates mid2 = rates_at(mid, v_avg);
  const Eigen::Vector3d zeta = (mid2.w_ie + mid2.w_en) * dt;
  n.q_bn = (quaternion_from_rotation_vector(-zeta) * s.q_bn * quaternion_from_rotation_vector(phi)).normalized();
  return n;
}

Eigen::Vector3d specific_force_n(const InsState& state, const ImuSample& cur, double dt_s) {
  return state.C_bn() * cur.dv / dt_s;
}

ImuSample compensate(const ImuSample& s, const Eigen::Vector3d& gyro_bias,
                     const Eigen::Vector3d& accel_bias, double dt_s) {
  return {s.t_s, s.dtheta - gyro_bias * dt_s, s.dv - accel_bias * dt_s};
}

bool in_ins_domain(const InsState& s) {
  return std::isfinite(s.lat_rad) && std::isfinite(s.lon_rad) && std::isfinite(s.h_m) && s.v_n.allFinite() &&
         s.q_bn.coeffs().allFinite() && std::abs(s.lat_rad) <= kInsMaxLatitudeDeg * std::numbers::pi / 180;
}

}  // namespace polrig
