#include "polrig/optics/lens.h"

#include <cmath>

namespace polrig {
namespace {
using V = std::array<double, 3>;
V add(const V& a, const V& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
V sub(const V& a, const V& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
V mul(const V& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
double dot(const V& a, const V& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
V unit(const V& a) { return mul(a, 1.0 / std::sqrt(dot(a, a))); }

// Snell's law in vector form; n is the unit normal on the side the ray comes from.
std::optional<V> refract(const V& i, const V& n, double n1, double n2) {
  const double eta = n1 / n2, cos_i = -dot(n, i);
  const double k = 1 - eta * eta * (1 - cos_i * cos_i);
  if (k < 0) return std::nullopt;  // total internal reflection
  return unit(add(mul(i, eta), mul(n, eta * cos_i - std::sqrt(k))));
}
}  // namespace

double fresnel_transmittance(double n1, double n2, double cos_i) {
  const double sin_t2 = (n1 / n2) * (n1 / n2) * (1 - cos_i * cos_i);
  if (sin_t2 >= 1) return 0;
  const double cos_t = std::sqrt(1 - sin_t2);
  const double rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
  const double rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
  return 1 - 0.5 * (rs * rs + rp * rp);
}

PlanoConvexLens PlanoConvexLens::from_focal_length(double f, double t, double D, double n) {
  return {f * (n - 1), t, D, n};
}

double PlanoConvexLens::back_focal_length() const {
  const double f = radius_of_curvature / (index - 1);
  return f - thickness / index;
}

std::optional<LensRay> trace_through(const PlanoConvexLens& L, const LensRay& in) {
  const double R = L.radius_of_curvature, a = 0.5 * L.diameter;
  const V centre{0, 0, L.thickness - R};
  const auto on_sphere = [&](const V& o, const V& d, bool far) -> std::optional<V> {
    const V oc = sub(o, centre);
    const double b = dot(oc, d), c = dot(oc, oc) - R * R, disc = b * b - c;
    if (disc < 0) return std::nullopt;
    const double t = far ? -b + std::sqrt(disc) : -b - std::sqrt(disc);
    if (t <= 0) return std::nullopt;
    const V p = add(o, mul(d, t));
    if (p[0] * p[0] + p[1] * p[1] > a * a || p[2] < 0) return std::nullopt;
    return p;
  };
  const auto on_plane = [&](const V& o, const V& d) -> std::optional<V> {
    if (d[2] == 0) return std::nullopt;
    const double t = -o[2] / d[2];
    if (t <= 0) return std::nullopt;
    const V p = add(o, mul(d, t));
    if (p[0] * p[0] + p[1] * p[1] > a * a) return std::nullopt;
    return p;
  };
  // Refraction at one face, with its Fresnel loss; n faces the side the ray comes from.
  LensRay out = in;
  const auto cross = [&](const V& d, const V& n, double n1, double n2) -> std::optional<V> {
    const auto t = refract(d, n, n1, n2);
    if (t) out.transmittance *= fresnel_transmittance(n1, n2, -dot(n, d));
    return t;
  };
  const V& d = in.direction;
  std::optional<V> p1, d1, p2, d2;
  if (d[2] > 0) {
    // Upwards: the plane face, then the convex face from inside.
    if (!(p1 = on_plane(in.origin, d)) || !(d1 = cross(d, {0, 0, -1}, 1.0, L.index))) return std::nullopt;
    if (!(p2 = on_sphere(*p1, *d1, true))) return std::nullopt;
    d2 = cross(*d1, mul(unit(sub(*p2, centre)), -1.0), L.index, 1.0);
  } else {
    // Downwards: the convex face from outside, then the plane face.
    if (!(p1 = on_sphere(in.origin, d, false)) || !(d1 = cross(d, unit(sub(*p1, centre)), 1.0, L.index)))
      return std::nullopt;
    if (!(p2 = on_plane(*p1, *d1))) return std::nullopt;
    d2 = cross(*d1, {0, 0, 1}, L.index, 1.0);
  }
  if (!d2) return std::nullopt;
  out.origin = *p2;
  out.direction = *d2;
  return out;
}

}  // namespace polrig
