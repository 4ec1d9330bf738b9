#include "polrig/source/wall_field.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <tbb/parallel_for.h>

#include "polrig/quadrature.h"
#include "polrig/source/sphere_tracer.h"
#include "polrig/vec3.h"
#include "polrig/units.h"

namespace polrig {
namespace {

using namespace vec3;

// A radiance that depends linearly on the unknown constant C: a + b·C (W/m²/sr).
struct Linear {
  double a = 0, b = 0;
  Linear operator-(const Linear& o) const { return {a - o.a, b - o.b}; }
};

// The field's integrals at one wall point.
class OccluderIntegrals {
 public:
  OccluderIntegrals(const SphereTracer& tracer, const SphereSolution& solution)
      : tracer_(tracer), solution_(solution), scene_(tracer.scene()),
        radial_(gauss_legendre_01(kRadialNodes)) {}

  // δ(W) = a + b·C.
  Linear delta(const Vec3& W) const {
    const Vec3 n_W = mul(unit(W), -1.0);
    Linear sum;
    for (std::size_t i = 0; i < scene_.baffles.size(); ++i) accumulate(sum, baffle(W, n_W, static_cast<int>(i)));
    for (std::size_t i = 0; i < scene_.lamps.size(); ++i)
      if (scene_.lamps[i].radius > 0) accumulate(sum, lamp(W, n_W, static_cast<int>(i)));
    return sum;
  }

 private:
  static constexpr int kRadialNodes = 6, kAngularNodes = 16;
  static void accumulate(Linear& s, const Linear& x) {
    s.a += x.a;
    s.b += x.b;
  }

  // The radiance of the surface a ray hits, as a + b·C.
  Linear radiance_of(const SphereTracer::Hit& h) const {
    switch (h.kind) {
      case SphereTracer::Hit::Wall: {
        const double k = scene_.sphere.reflectance / kPi;
        return {k * tracer_.direct_irradiance(h.point), k};
      }
      case SphereTracer::Hit::Baffle: {
        const BaffleSpec& b = scene_.baffles[static_cast<std::size_t>(h.index)];
        return {b.reflectance * solution_.baffle_E[static_cast<std::size_t>(h.index)][h.front ? 0 : 1] / kPi, 0};
      }
      case SphereTracer::Hit::Lamp:
        return {0, scene_.lamps[static_cast<std::size_t>(h.index)].reflectance / kPi};
      case SphereTracer::Hit::None: break;
    }
    return {};
  }

  // ∫ over the baffle's disk of (L_baffle − L_behind)·cos θ_W·cos θ_B/d² dA.
  Linear baffle(const Vec3& W, const Vec3& n_W, int index) const {
    const BaffleSpec& bf = scene_.baffles[static_cast<std::size_t>(index)];
    Linear sum;
    if (dot(n_W, sub(bf.centre, W)) < -bf.radius) return sum;  // below W's horizon
    const Vec3 n_b = unit(bf.normal);
    Vec3 t, b;
    basis_around(n_b, t, b);
    for (int i = 0; i < kRadialNodes; ++i) {
      // Area-uniform radius r = a·√s, dA = (a²/2)·ds·dφ.
      const double r = bf.radius * std::sqrt(radial_.x[static_cast<std::size_t>(i)]);
      const double w_area = 0.5 * bf.radius * bf.radius * radial_.w[static_cast<std::size_t>(i)] * (2 * kPi / kAngularNodes);
      for (int j = 0; j < kAngularNodes; ++j) {
        const double phi = 2 * kPi * (j + 0.5) / kAngularNodes;
        const Vec3 B = add(bf.centre, add(mul(t, r * std::cos(phi)), mul(b, r * std::sin(phi))));
        const Vec3 to = sub(B, W);
        const double d2 = dot(to, to), d = std::sqrt(d2);
        const Vec3 dir = mul(to, 1.0 / d);
        const double cos_W = dot(n_W, dir);
        if (cos_W <= 0) continue;
        const SphereTracer::Hit seen = tracer_.first_hit(W, dir);
        if (seen.kind != SphereTracer::Hit::Baffle || seen.index != index) continue;  // hidden
        const SphereTracer::Hit behind = tracer_.first_hit(seen.point, dir);
        const double weight = w_area * cos_W * std::abs(dot(n_b, dir)) / d2;
        const Linear diff = radiance_of(seen) - radiance_of(behind);
        sum.a += weight * diff.a;
        sum.b += weight * diff.b;
      }
    }
    return sum;
  }

  // ∫ over the cone of directions in which W sees the lamp of (L_lamp − L_behind)·cos θ_W dω.
  Linear lamp(const Vec3& W, const Vec3& n_W, int index) const {
    const LampSpec& l = scene_.lamps[static_cast<std::size_t>(index)];
    Linear sum;
    const Vec3 to = sub(l.position, W);
    const double D = std::sqrt(dot(to, to));
    if (dot(n_W, to) < -l.radius) return sum;
    const Vec3 axis = mul(to, 1.0 / D);
    Vec3 t, b;
    basis_around(axis, t, b);
    const double cos_max = std::sqrt(std::max(0.0, 1 - (l.radius / D) * (l.radius / D)));
    for (int i = 0; i < kRadialNodes; ++i) {
      // dω = d(cos β)·dφ over cos β in [cos β_max, 1].
      const double cb = cos_max + (1 - cos_max) * radial_.x[static_cast<std::size_t>(i)];
      const double sb = std::sqrt(std::max(0.0, 1 - cb * cb));
      const double w_omega = (1 - cos_max) * radial_.w[static_cast<std::size_t>(i)] * (2 * kPi / kAngularNodes);
      for (int j = 0; j < kAngularNodes; ++j) {
        const double phi = 2 * kPi * (j + 0.5) / kAngularNodes;
        const Vec3 dir = unit(add(mul(axis, cb), add(mul(t, sb * std::cos(phi)), mul(b, sb * std::sin(phi)))));
        const double cos_W = dot(n_W, dir);
        if (cos_W <= 0) continue;
        const SphereTracer::Hit seen = tracer_.first_hit(W, dir);
        if (seen.kind != SphereTracer::Hit::Lamp || seen.index != index) continue;
        // Leave the lamp at its far side, then look on.
        const Vec3 oc = sub(seen.point, l.position);
        const double far = -2 * dot(oc, dir);
        const SphereTracer::Hit behind = tracer_.first_hit(add(seen.point, mul(dir, std::max(far, 0.0))), dir);
        const Linear diff = radiance_of(seen) - radiance_of(behind);
        sum.a += w_omega * cos_W * diff.a;
        sum.b += w_omega * cos_W * diff.b;
      }
    }
    return sum;
  }

  const SphereTracer& tracer_;
  const SphereSolution& solution_;
  const SceneSpec& scene_;
  QuadratureRule radial_;
};

Vec3 node_point(double R, double theta, double phi) {
  return {R * std::sin(theta) * std::cos(phi), R * std::sin(theta) * std::sin(phi), R * std::cos(theta)};
}

// Catmull–Rom weights for a point at fraction f between nodes 1 and 2 of four.
void catmull_rom(double f, double w[4]) {
  const double f2 = f * f, f3 = f2 * f;
  w[0] = 0.5 * (-f3 + 2 * f2 - f);
  w[1] = 0.5 * (3 * f3 - 5 * f2 + 2);
  w[2] = 0.5 * (-3 * f3 + 4 * f2 + f);
  w[3] = 0.5 * (f3 - f2);
}

}  // namespace

double WallField::after_first_strike(const Vec3& p) const {
  const double theta = std::acos(std::clamp(p[2] / R, -1.0, 1.0));
  double phi = std::atan2(p[1], p[0]);
  if (phi < 0) phi += 2 * kPi;
  if (phi >= 2 * kPi) phi = 0;  // atan2 of y = −tiny rounds up to 2π exactly
  const double dt = kPi / (n_theta - 1), dp = 2 * kPi / n_phi;
  const int it = std::min(static_cast<int>(theta / dt), n_theta - 2);
  const int ip = static_cast<int>(phi / dp) % n_phi;
  double wt[4], wp[4];
  catmull_rom(theta / dt - it, wt);
  catmull_rom(phi / dp - ip, wp);
  // Rows beyond a pole continue over it on the opposite meridian (θ → −θ, φ → φ + π).
  double d = 0;
  for (int a = 0; a < 4; ++a) {
    int i = it - 1 + a, turn = 0;
    if (i < 0) {
      i = -i;
      turn = n_phi / 2;
    } else if (i > n_theta - 1) {
      i = 2 * (n_theta - 1) - i;
      turn = n_phi / 2;
    }
    const double* row = delta.data() + static_cast<std::size_t>(i) * static_cast<std::size_t>(n_phi);
    for (int b = 0; b < 4; ++b) {
      int j = ip - 1 + b + turn;  // ≥ −1
      if (j < 0) j += n_phi;
      while (j >= n_phi) j -= n_phi;
      d += wt[a] * wp[b] * row[j];
    }
  }
  return C + d;
}

WallField compute_wall_field(const SphereTracer& tracer, const SphereSolution& solution, int n_theta,
                             int n_phi, const Progress& progress) {
  const SceneSpec& scene = tracer.scene();
  WallField f;
  f.R = scene.sphere.radius();
  f.n_theta = n_theta;
  f.n_phi = n_phi + (n_phi % 2);  // even, so that the meridian over a pole is a node
  const std::size_t nodes = static_cast<std::size_t>(f.n_theta) * static_cast<std::size_t>(f.n_phi);
  std::vector<Linear> delta(nodes);
  const OccluderIntegrals integrals(tracer, solution);
  progress.begin("sphere solve: wall field", f.n_theta);
  tbb::parallel_for(0, f.n_theta, [&](int i) {
    const double theta = kPi * i / (f.n_theta - 1);
    const bool pole = i == 0 || i == f.n_theta - 1;
    for (int j = 0; j < f.n_phi; ++j) {
      const std::size_t k = static_cast<std::size_t>(i * f.n_phi + j);
      delta[k] = pole && j > 0 ? delta[k - static_cast<std::size_t>(j)]
                               : integrals.delta(node_point(f.R, theta, 2 * kPi * j / f.n_phi));
    }
    progress.advance();
  });
  progress.finish();

  // C from energy: the wall's mean of C + δ = the photon solve's mean after the first strike.
  // Wall means by the midpoint rule over the grid's cells, the port cap left out.
  const double port_z = scene.port_plane_z();
  double area = 0, mean_a = 0, mean_b = 0;
  for (int i = 0; i + 1 < f.n_theta; ++i) {
    const double t0 = kPi * i / (f.n_theta - 1), t1 = kPi * (i + 1) / (f.n_theta - 1);
    if (f.R * std::cos(0.5 * (t0 + t1)) < port_z) continue;
    const double band = std::cos(t0) - std::cos(t1);
    for (int j = 0; j < f.n_phi; ++j) {
      const int j1 = (j + 1) % f.n_phi;
      const auto at = [&](int ii, int jj) { return delta[static_cast<std::size_t>(ii * f.n_phi + jj)]; };
      const Linear c[4] = {at(i, j), at(i, j1), at(i + 1, j), at(i + 1, j1)};
      for (const Linear& x : c) {
        mean_a += 0.25 * band * x.a;
        mean_b += 0.25 * band * x.b;
      }
      area += band;
    }
  }
  mean_a /= area;
  mean_b /= area;
  const double R = f.R, a = scene.port.radius();
  const double wall_m2 = (4 * kPi * R * R - 2 * kPi * R * (R - std::sqrt(R * R - a * a))) * 1e-6;
  double after_W = 0;
  for (double w : solution.batch_indirect_W) after_W += w / static_cast<double>(solution.batch_indirect_W.size());
  const double E_after = after_W / wall_m2;
  f.C = (E_after - mean_a) / (1 + mean_b);
  f.delta.resize(nodes);
  for (std::size_t k = 0; k < nodes; ++k) f.delta[k] = delta[k].a + delta[k].b * f.C;
  return f;
}

}  // namespace polrig
