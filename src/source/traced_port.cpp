#include "polrig/source/traced_port.h"

#include <cmath>
#include <vector>
#include <numbers>

#include "polrig/random.h"
#include "polrig/statistics.h"
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

StokesIrradiance TracedPort::plane_irradiance_shift(double x, double y, double L_o,
                                                    long long samples, int shift,
                                                    double L_ref) const {
  const SceneSpec& sc = tracer_.scene();
  const double a = sc.port.radius(), zp = sc.port_plane_z();
  const Vec3 P{x, y, zp - L_o};
  const double du = uniform_unit(sc.trace.seed, static_cast<std::uint64_t>(shift), 0x5041, 0);
  const double dv = uniform_unit(sc.trace.seed, static_cast<std::uint64_t>(shift), 0x5041, 1);
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
    // cos θ_P · cos θ_Q / r², with cos = Δz/r (lengths in mm, the ratio is dimensionless).
    e += (tracer_.radiance(solution_, h) - L_ref) * (d[2] * d[2]) / (r2 * r2);
  }
  e *= kPi * a * a / static_cast<double>(samples);
  if (L_ref != 0) e += disk_irradiance(L_ref, a, L_o, std::hypot(x, y));
  const PolarizerFilm& film = sc.port.polarizer;
  const double g_up = film.g_up(), g_tp = film.g_tp();
  StokesIrradiance out;
  out.S0 = g_up * e;
  out.S1 = g_tp * std::cos(2 * deg2rad(film.axis_deg)) * e;
  out.S2 = g_tp * std::sin(2 * deg2rad(film.axis_deg)) * e;
  return out;
}

StokesIrradiance TracedPort::plane_irradiance(double x, double y, double L_o, long long samples,
                                              int shifts) const {
  std::vector<double> s0(static_cast<std::size_t>(shifts));
  StokesIrradiance out;
  for (int k = 0; k < shifts; ++k) {
    const StokesIrradiance e = plane_irradiance_shift(x, y, L_o, samples, k);
    s0[static_cast<std::size_t>(k)] = e.S0;
    out.S1 += e.S1 / shifts;
    out.S2 += e.S2 / shifts;
  }
  const MeanAndSpread m = mean_and_standard_error(s0);
  out.S0 = m.mean;
  out.S0_se = m.sd;
  // The film scales S1, S2 by fixed factors of S0: their errors follow.
  if (out.S0 > 0) {
    out.S1_se = std::abs(out.S1 / out.S0) * out.S0_se;
    out.S2_se = std::abs(out.S2 / out.S0) * out.S0_se;
  }
  return out;
}

}  // namespace polrig
