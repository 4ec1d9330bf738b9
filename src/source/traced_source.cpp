#include "polrig/source/traced_source.h"

#include <cmath>
#include <numbers>

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
    const double g_up = 0.5 * (scene_.port.polarizer.tau_M + scene_.port.polarizer.tau_m);
    L_ref_ = port.plane_irradiance(0, 0, h, 16384, 1).S0 / (g_up * disk_irradiance(1.0, a, h, 0));
  });
  return *solution_;
}

long long TracedSource::solve_rays() const { return solution().ledger.rays; }
double TracedSource::solve_seconds() const { return solution().seconds; }

double TracedSource::photodiode_irradiance(const Point2& p, double L_o, int shift) const {
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
