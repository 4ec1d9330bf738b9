#pragma once
// Attitude of the body b (RFU: X right, Y forward, Z up) in n (ENU), as the direction cosine
// matrix C_b^n (v^n = C_b^n·v^b) or its quaternion, and the Euler angles polrig reports.
//
// Euler angles (the same convention as compass/heading.h's body_to_enu):
//   C_b^n = Rz(−yaw)·Rx(pitch)·Ry(roll)
// yaw = heading, clockwise from north seen from above (geographic, spec §0); pitch about X_b,
// nose up positive; roll about Y_b, right wing down positive. Rz, Rx, Ry are right-handed
// (anticlockwise) rotations of a vector. Range: yaw [0, 2π), pitch [−π/2, π/2], roll (−π, π].
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "polrig/vec3.h"

namespace polrig {

struct Euler {
  double roll_rad = 0;
  double pitch_rad = 0;
  double yaw_rad = 0;  // heading, clockwise from north
};

Eigen::Matrix3d C_bn_from_euler(const Euler& e);
Euler euler_from_C_bn(const Eigen::Matrix3d& C_bn);

// C_b^n by its columns (vec3.h's Axes3, the form compass/ takes attitudes in: compass/unit_array.h's
// body_axes_enu gives the same matrix for the same angles, tests/test_navigation.cpp).
Axes3 axes_of(const Eigen::Matrix3d& C);

// [v×]: the matrix of the cross product v × ·.
Eigen::Matrix3d skew(const Eigen::Vector3d& v);

// The rotation of rotation vector φ (angle |φ| about φ/|φ|) as a unit quaternion, exact at every
// angle (its Taylor series below 1e-2 rad, exact there to rounding).
Eigen::Quaterniond quaternion_from_rotation_vector(const Eigen::Vector3d& phi);

}  // namespace polrig
