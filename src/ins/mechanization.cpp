#include "polrig/ins/mechanization.h"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "polrig/ins/earth.h"

namespace polrig {
namespace {

struct Rates {
  Eigen::Vector3d w_ie, w_en, g;
};

Rates rates_at(double L, double h, const Eigen::Vector3d& v) {
  return {omega_ie_n(L), omega_en_n(v, L, h), gravity_n(L, h)};
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

  // Velocity: a first pass at the start's rates gives the midpoint, the second uses the midpoint's.
  // The rotation compensation as half-angle rotations in b and in n (not I ± ½[·×]): for a static
  // IMU they cancel exactly, where the first-order forms leave ¼[ζ×]²g·Δt per step.
  const Eigen::Vector3d dv_f_b = quaternion_from_rotation_vector(0.5 * cur.dtheta) * cur.dv +
                                 (prev.dtheta.cross(cur.dv) + prev.dv.cross(cur.dtheta)) / 12.0;
  const Eigen::Vector3d v_mid0 = s.v_n + 0.5 * delta_v(C_bn, dv_f_b, s.v_n, rates_at(s.lat_rad, s.h_m, s.v_n), dt);
  EarthRadii r0 = earth_radii(s.lat_rad);
  const double h_mid = s.h_m + 0.5 * v_mid0.z() * dt;
  const double L_mid = s.lat_rad + 0.5 * v_mid0.y() * dt / (r0.R_M + h_mid);
  const Rates mid = rates_at(L_mid, h_mid, v_mid0);
  InsState n = s;
  n.t_s = cur.t_s;
  n.v_n = s.v_n + delta_v(C_bn, dv_f_b, v_mid0, mid, dt);
  if (options.hold_height_m) n.v_n.z() = 0;

  // Position: trapezoidal velocity; h, then L at the mean height, then λ at the mean L and h.
  const Eigen::Vector3d v_avg = 0.5 * (s.v_n + n.v_n);
  n.h_m = options.hold_height_m ? *options.hold_height_m : s.h_m + v_avg.z() * dt;
  const double h_avg = 0.5 * (s.h_m + n.h_m);
  n.lat_rad = s.lat_rad + v_avg.y() * dt / (earth_radii(s.lat_rad).R_M + h_avg);
  const double L_avg = 0.5 * (s.lat_rad + n.lat_rad);
  n.lon_rad = s.lon_rad + v_avg.x() * dt / ((earth_radii(L_avg).R_N + h_avg) * std::cos(L_avg));

  // Attitude: the body's rotation (with coning) and the n-frame's over the interval, at the midpoint.
  const Eigen::Vector3d phi = cur.dtheta + prev.dtheta.cross(cur.dtheta) / 12.0;
  const Rates mid2 = rates_at(L_avg, h_avg, v_avg);
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

}  // namespace polrig
