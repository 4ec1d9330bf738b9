#pragma once
// Arithmetic on 3-vectors as plain arrays: the traced source's geometry and the optics' rays.
#include <array>
#include <cmath>

namespace polrig {

using Vec3 = std::array<double, 3>;
// A rotation C_a^b by its columns: frame a's X, Y and Z axes written in frame b (C_a^b·v_a = v_b).
using Axes3 = std::array<Vec3, 3>;

namespace vec3 {

inline Vec3 add(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline Vec3 sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
inline Vec3 mul(const Vec3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
inline double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec3 cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline double norm(const Vec3& a) { return std::sqrt(dot(a, a)); }
inline Vec3 unit(const Vec3& a) { return mul(a, 1.0 / norm(a)); }

// Two unit vectors t, b completing the unit vector n to a right-handed frame (t, b, n).
inline void basis_around(const Vec3& n, Vec3& t, Vec3& b) {
  t = unit(cross(std::abs(n[0]) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0}, n));
  b = cross(n, t);
}

// C·v: a vector of frame a written in frame b, for C = C_a^b given by its columns.
inline Vec3 apply(const Axes3& C, const Vec3& v) {
  return add(add(mul(C[0], v[0]), mul(C[1], v[1])), mul(C[2], v[2]));
}
// Cᵀ·v: a vector of frame b written in frame a.
inline Vec3 apply_transpose(const Axes3& C, const Vec3& v) { return {dot(C[0], v), dot(C[1], v), dot(C[2], v)}; }
// A·B, column by column (C_b^c·C_a^b = C_a^c).
inline Axes3 compose(const Axes3& A, const Axes3& B) { return {apply(A, B[0]), apply(A, B[1]), apply(A, B[2])}; }

}  // namespace vec3
}  // namespace polrig
