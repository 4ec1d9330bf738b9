#include "polrig/source/traced_port.h"

#include <cmath>
#include <numbers>

#include "polrig/random.h"
#include "polrig/units.h"

namespace polrig {

namespace {
constexpr double kPi = std::numbers::pi;
// The R2 sequence (a rank-1 lattice from the plastic number): low discrepancy in 2-D.
constexpr double kR2a = 0.7548776662466927, kR2b = 0.5698402909980532;
}  // namespace

double disk_irradiance(double L, double a, double h, double r) {
  const double s = h * h + r * r;
  return kPi * L * 0.5 * (1.0 - (s - a * a) / std::sqrt((s + a * a) * (s + a * a) - 4 * a * a * r * r));
}

TracedPort::TracedPort(const SphereTracer& tracer, const SphereSolution& solution)
    : tracer_(tracer), solution_(solution) {}

StokesIrradiance TracedPort::plane_irradiance(double x, double y, double L_o, long long samples,
                                              int shifts) const {
  const SceneSpec& sc = tracer_.scene();
  const double a = sc.port.radius(), zp = sc.port_plane_z();
  const Vec3 P{x, y, zp - L_o};
  const PolarizerFilm& film = sc.port.polarizer;
  const double g_up = 0.5 * (film.tau_M + film.tau_m), g_tp = 0.5 * (film.tau_M - film.tau_m);
  const double c2 = std::cos(2 * deg2rad(film.axis_deg)), s2 = std::sin(2 * deg2rad(film.axis_deg));
  const double area_m2 = kPi * a * a * 1e-6;

  double sum = 0, sum2 = 0;
  for (int k = 0; k < shifts; ++k) {
    const double du = uniform_unit(sc.trace.seed, static_cast<std::uint64_t>(k), 0x5041, 0);
    const double dv = uniform_unit(sc.trace.seed, static_cast<std::uint64_t>(k), 0x5041, 1);
    double e = 0;
    for (long long n = 0; n < samples; ++n) {
      double u = du + kR2a * static_cast<double>(n + 1), v = dv + kR2b * static_cast<double>(n + 1);
      u -= std::floor(u);
      v -= std::floor(v);
      const double rho = a * std::sqrt(u), phi = 2 * kPi * v;
      const Vec3 Q{rho * std::cos(phi), rho * std::sin(phi), zp};
      const Vec3 d{Q[0] - P[0], Q[1] - P[1], Q[2] - P[2]};
      const double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
      const double inv = 1.0 / std::sqrt(r2);
      const Vec3 dir{d[0] * inv, d[1] * inv, d[2] * inv};
      const SphereTracer::Hit h = tracer_.first_hit(Q, dir, 0.0);
      const double L = tracer_.radiance(solution_, h);
      // cos θ_P · cos θ_Q / r², with cos = Δz/r, per m² (lengths in mm).
      e += L * (d[2] * d[2]) / (r2 * r2) * 1e6;
    }
    e *= area_m2 / static_cast<double>(samples);
    sum += e;
    sum2 += e * e;
  }
  const double mean = sum / shifts;
  const double se = shifts > 1 ? std::sqrt(std::max(0.0, (sum2 / shifts - mean * mean) / (shifts - 1))) : 0.0;
  StokesIrradiance out;
  out.S0 = g_up * mean;
  out.S1 = g_tp * c2 * mean;
  out.S2 = g_tp * s2 * mean;
  out.S0_se = g_up * se;
  out.S1_se = std::abs(g_tp * c2) * se;
  out.S2_se = std::abs(g_tp * s2) * se;
  return out;
}

}  // namespace polrig
