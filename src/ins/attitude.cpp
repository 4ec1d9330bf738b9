#include "polrig/ins/attitude.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace polrig {

Eigen::Matrix3d C_bn_from_euler(const Euler& e) {
  const Eigen::Matrix3d Rz = Eigen::AngleAxisd(-e.yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Matrix3d Rx = Eigen::AngleAxisd(e.pitch_rad, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Matrix3d Ry = Eigen::AngleAxisd(e.roll_rad, Eigen::Vector3d::UnitY()).toRotationMatrix();
  return Rz * Rx * Ry;
}

// With c = cos, s = sin: C(2,1) = s(pitch), C(2,0) = −c(pitch)·s(roll), C(2,2) = c(pitch)·c(roll),
// C(0,1) = s(yaw)·c(pitch), C(1,1) = c(yaw)·c(pitch).
Euler euler_from_C_bn(const Eigen::Matrix3d& C) {
  Euler e;
  e.pitch_rad = std::asin(std::clamp(C(2, 1), -1.0, 1.0));
  e.roll_rad = std::atan2(-C(2, 0), C(2, 2));
  double yaw = std::atan2(C(0, 1), C(1, 1));
  if (yaw < 0) yaw += 2 * std::numbers::pi;
  e.yaw_rad = yaw;
  return e;
}

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

Axes3 axes_of(const Eigen::Matrix3d& C) {
  return {Vec3{C(0, 0), C(1, 0), C(2, 0)}, Vec3{C(0, 1), C(1, 1), C(2, 1)}, Vec3{C(0, 2), C(1, 2), C(2, 2)}};
}

Eigen::Quaterniond quaternion_from_rotation_vector(const Eigen::Vector3d& phi) {
  const double a2 = phi.squaredNorm();
  double c, s;  // cos(|φ|/2) and sin(|φ|/2)/|φ|
  // The series to |φ|⁴ below |φ| = 0.01 rad: the first terms left out, |φ|⁶/46080 and |φ|⁶/645120,
  // are < 2.2e-17 there, below an ulp of 1 (an IMU's increments at 100 Hz are ~1e-4 rad).
  if (a2 < 1e-4) {
    c = 1 - a2 / 8 + a2 * a2 / 384;
    s = 0.5 - a2 / 48 + a2 * a2 / 3840;
  } else {
    const double a = std::sqrt(a2);
    c = std::cos(a / 2);
    s = std::sin(a / 2) / a;
  }
  return Eigen::Quaterniond(c, s * phi.x(), s * phi.y(), s * phi.z());
}

}  // namespace polrig
