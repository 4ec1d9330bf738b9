#include "polrig/source/traced_source.h"

#include <cmath>
#include <numbers>

#include "polrig/optics/lens.h"
#include "polrig/random.h"
#include "polrig/source/sphere_tracer.h"
#include "polrig/source/traced_port.h"

namespace polrig {

TracedSource::TracedSource(const SceneSpec& scene)
    : scene_(scene), tracer_(std::make_unique<SphereTracer>(scene_)) {}

TracedSource::~TracedSource() = default;

const SphereSolution& TracedSource::solution() const {
  std::call_once(solved_, [&] {
    solution_ = std::make_unique<SphereSolution>(tracer_->solve());
    // The port's mean radiance, seen from below its centre: E(0)/(g_up·F(0)).
    const TracedPort port(*tracer_, *solution_);
    const double h = scene_.sensor.L_o, a = scene_.port.radius();
    const double g_up = scene_.port.polarizer.g_up();
    L_ref_ = port.plane_irradiance(0, 0, h, 16384, 1).S0 / (g_up * disk_irradiance(1.0, a, h, 0));
  });
  return *solution_;
}

long long TracedSource::solve_rays() const { return solution().ledger.rays; }
double TracedSource::solve_seconds() const { return solution().seconds; }

namespace {
constexpr double kPi = std::numbers::pi;
// The R4 sequence (generalised golden ratio in 4-D): a rank-1 lattice for the lensed integral.
constexpr double kPhi4 = 1.1673039782614187;
}  // namespace

double TracedSource::lensed_irradiance(const Point2& p, double top, int shift) const {
  const SensorOpticsSpec& o = scene_.sensor;
  const PlanoConvexLens lens =
      PlanoConvexLens::from_focal_length(o.lens_focal_length, o.lens_thickness, o.lens_diameter, o.lens_index);
  const double zp = scene_.port_plane_z(), a = scene_.port.radius();
  const double z0 = zp - top - o.film_to_lens - o.lens_thickness;  // the lens's plane face
  const double a_lens = 0.5 * o.lens_diameter, size = o.photodiode_size;
  const double g_up = scene_.port.polarizer.g_up();
  const long long samples = scene_.trace.plane_samples;
  const SphereSolution& sol = solution();
  const int first = shift < 0 ? 0 : shift, last = shift < 0 ? shifts_ : shift + 1;
  double alpha[4];
  for (int k = 0; k < 4; ++k) alpha[k] = std::pow(1.0 / kPhi4, k + 1);
  double total = 0;
  for (int sh = first; sh < last; ++sh) {
    double start[4];
    for (int k = 0; k < 4; ++k) start[k] = uniform_unit(scene_.trace.seed, static_cast<std::uint64_t>(sh), 0x1E25, static_cast<std::uint64_t>(k));
    double e = 0;
    for (long long n = 0; n < samples; ++n) {
      double u[4];
      for (int k = 0; k < 4; ++k) u[k] = std::fmod(start[k] + alpha[k] * static_cast<double>(n + 1), 1.0);
      // A photodiode point and a point of the lens's plane face, in the channel's lens frame.
      const std::array<double, 3> s{(u[0] - 0.5) * size, (u[1] - 0.5) * size, -o.lens_to_photodiode};
      const double rho = a_lens * std::sqrt(u[2]), phi = 2 * kPi * u[3];
      const std::array<double, 3> q{rho * std::cos(phi), rho * std::sin(phi), 0.0};
      const std::array<double, 3> d{q[0] - s[0], q[1] - s[1], q[2] - s[2]};
      const double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], r = std::sqrt(r2);
      const auto out = trace_through(lens, LensRay{s, {d[0] / r, d[1] / r, d[2] / r}, 1.0});
      if (!out) continue;
      // Up to the port plane; light only comes through the port.
      const double t = (zp - (z0 + out->origin[2])) / out->direction[2];
      const Vec3 Q{p.x() + out->origin[0] + t * out->direction[0], p.y() + out->origin[1] + t * out->direction[1], zp};
      if (Q[0] * Q[0] + Q[1] * Q[1] > a * a) continue;
      const SphereTracer::Hit h = tracer_->first_hit(Q, {out->direction[0], out->direction[1], out->direction[2]}, 0.0);
      // cos θ_s · cos θ_q / r² (both faces parallel to the photodiode), per unit lens area.
      e += tracer_->radiance(sol, h) * out->transmittance * (d[2] * d[2]) / (r2 * r2);
    }
    total += e * kPi * a_lens * a_lens / static_cast<double>(samples);
  }
  return g_up * o.filter_transmittance * total / (last - first);
}

double TracedSource::photodiode_irradiance(const Point2& p, double L_o, int shift) const {
  if (scene_.sensor.geometry == "lensed") return lensed_irradiance(p, L_o, shift);
  // 2 × 2 Gauss–Legendre points over the square photodiode: exact for irradiance that varies as
  // a cubic across it.
  const double g = 0.5 * scene_.sensor.photodiode_size / std::sqrt(3.0);
  const TracedPort port(*tracer_, solution());
  const double L_ref = L_ref_;
  const long long samples = std::max<long long>(16, scene_.trace.plane_samples / 4);
  double e = 0;
  for (int k = 0; k < 4; ++k) {
    const double x = p.x() + ((k & 1) ? g : -g), y = p.y() + ((k & 2) ? g : -g);
    if (shift < 0) {
      for (int k = 0; k < shifts_; ++k)
        e += 0.25 / shifts_ * port.plane_irradiance_shift(x, y, L_o, samples, k, L_ref).S0;
    } else {
      e += 0.25 * port.plane_irradiance_shift(x, y, L_o, samples, shift, L_ref).S0;
    }
  }
  return e;
}

}  // namespace polrig
