#include "polrig/optics/lens.h"

#include <cmath>
#include <stdexcept>

#include "polrig/optics/polarized_ray.h"
#include "ray_math.h"

namespace polrig {

using namespace optics_detail;

double fresnel_transmittance(double n1, double n2, double cos_i) {
  const FresnelR r = fresnel_r(n1, n2, cos_i);
  return 1 - 0.5 * (r.s * r.s + r.p * r.p);
}

PlanoConvexLens PlanoConvexLens::from_focal_length(double f, double t, double D, double n) {
  return {f * (n - 1), t, D, n};
}

double PlanoConvexLens::back_focal_length() const {
  const double f = radius_of_curvature / (index - 1);
  return f - thickness / index;
}

std::optional<LensRay> trace_through(const PlanoConvexLens& L, const LensRay& in) {
  return trace_through(L, in, nullptr);
}

std::optional<LensRay> trace_through(const PlanoConvexLens& L, const LensRay& in,
                                     PolarizedRay* polarization) {
  using V = Vec3;
  std::optional<PolarizedRay> pol;
  if (polarization) {
    if (norm(sub(polarization->k, in.direction)) > 1e-9)
      throw std::invalid_argument("trace_through: polarization->k differs from in.direction");
    pol = *polarization;
    pol->k = in.direction;
    pol->x_hat = unit(reject(pol->x_hat, pol->k));
  }
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
  const auto through_face = [&](const V& d, const V& n, double n1, double n2) -> std::optional<V> {
    const auto t = snell(d, n, n1, n2);
    if (t) {
      out.transmittance *= fresnel_transmittance(n1, n2, -dot(n, d));
      if (pol) refract(*pol, n, n1, n2);  // same Snell call on the same d: pol->k == *t
    }
    return t;
  };
  const V& d = in.direction;
  std::optional<V> p1, d1, p2, d2;
  if (d[2] > 0) {
    // Upwards: the plane face, then the convex face from inside.
    if (!(p1 = on_plane(in.origin, d)) || !(d1 = through_face(d, {0, 0, -1}, 1.0, L.index))) return std::nullopt;
    if (!(p2 = on_sphere(*p1, *d1, true))) return std::nullopt;
    d2 = through_face(*d1, mul(unit(sub(*p2, centre)), -1.0), L.index, 1.0);
  } else {
    // Downwards: the convex face from outside, then the plane face.
    if (!(p1 = on_sphere(in.origin, d, false)) || !(d1 = through_face(d, unit(sub(*p1, centre)), 1.0, L.index)))
      return std::nullopt;
    if (!(p2 = on_plane(*p1, *d1))) return std::nullopt;
    d2 = through_face(*d1, {0, 0, 1}, L.index, 1.0);
  }
  if (!d2) return std::nullopt;
  out.origin = *p2;
  out.direction = *d2;
  if (pol) *polarization = *pol;
  return out;
}

}  // namespace polrig
