#include "polrig/source/traced_port.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include "polrig/optics/polarized_ray.h"
#include "polrig/quadrature.h"
#include "polrig/random.h"
#include "polrig/vec3.h"
#include "polrig/statistics.h"
#include "polrig/units.h"

namespace polrig {

namespace {
// The R2 sequence (a rank-1 lattice from the plastic number): low discrepancy in 2-D.
constexpr double kR2a = 0.7548776662466927, kR2b = 0.5698402909980532;

using namespace vec3;

const QuadratureRule& port_radial_rule() {
  static const QuadratureRule r = gauss_legendre_01(48);
  return r;
}
const QuadratureRule& occluder_radial_rule() {
  static const QuadratureRule r = gauss_legendre_01(12);
  return r;
}
constexpr int kPortAzimuths = 96, kOccluderAzimuths = 32;

// cos θ_P · cos θ_Q / |Q − P|² for a ray from P to Q (lengths in mm, the ratio dimensionless).
double plane_to_plane(const Vec3& d) {
  const double r2 = dot(d, d);
  return d[2] * d[2] / (r2 * r2);
}
// Port point n of one shift: a randomly shifted R2 lattice, area-uniform over the port.
struct PortLattice {
  double du, dv, a, zp;
  PortLattice(std::uint64_t seed, int shift, double a_, double zp_)
      : du(uniform_unit(seed, static_cast<std::uint64_t>(shift), 0x5041, 0)),
        dv(uniform_unit(seed, static_cast<std::uint64_t>(shift), 0x5041, 1)), a(a_), zp(zp_) {}
  Vec3 operator()(long long n) const {
    double u = du + kR2a * static_cast<double>(n + 1), v = dv + kR2b * static_cast<double>(n + 1);
    u -= std::floor(u);
    v -= std::floor(v);
    const double rho = a * std::sqrt(u), phi = 2 * kPi * v;
    return {rho * std::cos(phi), rho * std::sin(phi), zp};
  }
};

// The points of one shift are the same for every P, so each thread keeps the last sets it made
// (up to kCachedPoints points each); null when there are more.
constexpr long long kCachedPoints = 65536;
const std::vector<Vec3>* cached_port_points(std::uint64_t seed, int shift, long long samples, double a, double zp) {
  if (samples > kCachedPoints) return nullptr;
  struct Set {
    std::uint64_t seed;
    int shift;
    long long samples;
    double a, zp;
    std::vector<Vec3> Q;
  };
  constexpr std::size_t kKept = 16;
  thread_local std::vector<Set> kept;
  for (const Set& s : kept)
    if (s.seed == seed && s.shift == shift && s.samples == samples && s.a == a && s.zp == zp) return &s.Q;
  if (kept.size() == kKept) kept.erase(kept.begin());
  Set& s = kept.emplace_back(Set{seed, shift, samples, a, zp, {}});
  const PortLattice lattice(seed, shift, a, zp);
  s.Q.reserve(static_cast<std::size_t>(samples));
  for (long long n = 0; n < samples; ++n) s.Q.push_back(lattice(n));
  return &s.Q;
}
}  // namespace

double disk_irradiance(double L, double a, double h, double r) {
  const double s = h * h + r * r;
  return kPi * L * 0.5 * (1.0 - (s - a * a) / std::sqrt((s + a * a) * (s + a * a) - 4 * a * a * r * r));
}

double mean_port_radiance(const SphereTracer& tracer, const SphereSolution& solution, double h) {
  const TracedPort port(tracer, solution);
  const std::vector<double> e = port.irradiance(0, 0, h, [](const Vec3&) { return 1.0; }, 16384, 1);
  return e[0] / disk_irradiance(1.0, tracer.scene().port.radius(), h, 0);
}

TracedPort::TracedPort(const SphereTracer& tracer, const SphereSolution& solution, double L_ref)
    : tracer_(tracer), solution_(solution), L_ref_(L_ref) {}

double TracedPort::wall_radiance_along(const Vec3& Q, const Vec3& up) const {
  // The far root of the sphere from a point inside it: the wall, whatever stands in between.
  const double R = tracer_.scene().sphere.radius();
  const double b = dot(Q, up), c = dot(Q, Q) - R * R;
  SphereTracer::Hit h;
  h.kind = SphereTracer::Hit::Wall;
  h.point = add(Q, mul(up, -b + std::sqrt(b * b - c)));
  return tracer_.radiance(solution_, h);
}

double TracedPort::uniform_part(const Vec3& P, const RayTransmission& T) const {
  return uniform_parts(P, {T})[0];
}

std::vector<double> TracedPort::uniform_parts(const Vec3& P, const std::vector<RayTransmission>& Ts) const {
  std::vector<double> e(Ts.size(), 0.0);
  if (L_ref_ == 0) return e;
  const double a = tracer_.scene().port.radius(), zp = tracer_.scene().port_plane_z();
  const QuadratureRule& rule = port_radial_rule();
  // The azimuths' cosines and sines, the same for every P.
  static const std::array<std::array<double, 2>, kPortAzimuths> turn = [] {
    std::array<std::array<double, 2>, kPortAzimuths> t{};
    for (int j = 0; j < kPortAzimuths; ++j) {
      const double phi = 2 * kPi * (j + 0.5) / kPortAzimuths;
      t[static_cast<std::size_t>(j)] = {std::cos(phi), std::sin(phi)};
    }
    return t;
  }();
  std::vector<double> ring(Ts.size());
  for (std::size_t i = 0; i < rule.x.size(); ++i) {
    // Area-uniform radius ρ = a·√s: dA = (a²/2)·ds·dφ.
    const double rho = a * std::sqrt(rule.x[i]);
    std::fill(ring.begin(), ring.end(), 0.0);
    for (const auto& [c, s] : turn) {
      const Vec3 d = sub({rho * c, rho * s, zp}, P);
      const Vec3 k = mul(unit(d), -1.0);
      const double G = plane_to_plane(d);
      for (std::size_t f = 0; f < Ts.size(); ++f) ring[f] += Ts[f](k) * G;
    }
    for (std::size_t f = 0; f < Ts.size(); ++f) e[f] += rule.w[i] * ring[f];
  }
  for (double& x : e) x = L_ref_ * x * 0.5 * a * a * (2 * kPi / kPortAzimuths);
  return e;
}

double TracedPort::sampled_part(const Vec3& P, const RayTransmission& T, long long samples,
                                int shift) const {
  return sampled_parts(P, {T}, samples, shift)[0];
}

std::vector<double> TracedPort::sampled_parts(const Vec3& P, const std::vector<RayTransmission>& Ts,
                                              long long samples, int shift) const {
  const SceneSpec& sc = tracer_.scene();
  const double a = sc.port.radius(), zp = sc.port_plane_z();
  const std::vector<Vec3>* cached = cached_port_points(sc.trace.seed, shift, samples, a, zp);
  const PortLattice lattice(sc.trace.seed, shift, a, zp);
  std::vector<double> e(Ts.size(), 0.0);
  for (long long n = 0; n < samples; ++n) {
    const Vec3 Q = cached ? (*cached)[static_cast<std::size_t>(n)] : lattice(n);
    const Vec3 d = sub(Q, P);
    const Vec3 up = unit(d);
    const double L = wall_radiance_along(Q, up) - L_ref_, G = plane_to_plane(d);
    const Vec3 k = mul(up, -1.0);
    for (std::size_t f = 0; f < Ts.size(); ++f) e[f] += L * Ts[f](k) * G;
  }
  for (double& x : e) x = x * kPi * a * a / static_cast<double>(samples);
  return e;
}

double TracedPort::occluder_part(const Vec3& P, const RayTransmission& T) const {
  return occluder_parts(P, {T})[0];
}

std::vector<double> TracedPort::occluder_parts(const Vec3& P, const std::vector<RayTransmission>& Ts) const {
  const SceneSpec& sc = tracer_.scene();
  const double a = sc.port.radius(), zp = sc.port_plane_z();
  const QuadratureRule& rule = occluder_radial_rule();
  // The radiance difference along one ray from P: where `index` of `kind` is the first surface
  // seen through the port, its radiance replaces the wall's (0 where it is not seen).
  const auto difference = [&](const Vec3& up, SphereTracer::Hit::Kind kind, int index) {
    if (up[2] <= 0) return 0.0;
    const Vec3 Q = add(P, mul(up, (zp - P[2]) / up[2]));
    if (Q[0] * Q[0] + Q[1] * Q[1] > a * a) return 0.0;  // outside the port's view
    const SphereTracer::Hit h = tracer_.first_hit(Q, up, 0.0);
    if (h.kind != kind || h.index != index) return 0.0;
    return tracer_.radiance(solution_, h) - wall_radiance_along(Q, up);
  };
  std::vector<double> e(Ts.size(), 0.0);
  for (std::size_t b = 0; b < sc.baffles.size(); ++b) {
    const BaffleSpec& bf = sc.baffles[b];
    const Vec3 n = unit(bf.normal);
    Vec3 t, s;
    basis_around(n, t, s);
    for (std::size_t i = 0; i < rule.x.size(); ++i) {
      const double r = bf.radius * std::sqrt(rule.x[i]);
      const double w = 0.5 * bf.radius * bf.radius * rule.w[i] * (2 * kPi / kOccluderAzimuths);
      for (int j = 0; j < kOccluderAzimuths; ++j) {
        const double phi = 2 * kPi * (j + 0.5) / kOccluderAzimuths;
        const Vec3 d = sub(add(bf.centre, add(mul(t, r * std::cos(phi)), mul(s, r * std::sin(phi)))), P);
        const double d2 = dot(d, d), dist = std::sqrt(d2);
        const Vec3 up = mul(d, 1.0 / dist);
        // dω = |cos θ_B|·dA/d²; times cos θ_P.
        const double dL = difference(up, SphereTracer::Hit::Baffle, static_cast<int>(b));
        if (dL == 0) continue;  // adds nothing to any transmission
        const Vec3 k = mul(up, -1.0);
        for (std::size_t f = 0; f < Ts.size(); ++f) e[f] += w * (dL * Ts[f](k)) * up[2] * std::abs(dot(n, up)) / d2;
      }
    }
  }
  for (std::size_t l = 0; l < sc.lamps.size(); ++l) {
    const LampSpec& lamp = sc.lamps[l];
    if (lamp.radius <= 0) continue;
    const Vec3 to = sub(lamp.position, P);
    const double D = std::sqrt(dot(to, to));
    const Vec3 axis = mul(to, 1.0 / D);
    Vec3 t, s;
    basis_around(axis, t, s);
    const double cos_max = std::sqrt(std::max(0.0, 1 - (lamp.radius / D) * (lamp.radius / D)));
    for (std::size_t i = 0; i < rule.x.size(); ++i) {
      const double cb = cos_max + (1 - cos_max) * rule.x[i], sb = std::sqrt(std::max(0.0, 1 - cb * cb));
      const double w = (1 - cos_max) * rule.w[i] * (2 * kPi / kOccluderAzimuths);
      for (int j = 0; j < kOccluderAzimuths; ++j) {
        const double phi = 2 * kPi * (j + 0.5) / kOccluderAzimuths;
        const Vec3 up = unit(add(mul(axis, cb), add(mul(t, sb * std::cos(phi)), mul(s, sb * std::sin(phi)))));
        const double dL = difference(up, SphereTracer::Hit::Lamp, static_cast<int>(l));
        if (dL == 0) continue;
        const Vec3 k = mul(up, -1.0);
        for (std::size_t f = 0; f < Ts.size(); ++f) e[f] += w * (dL * Ts[f](k)) * up[2];
      }
    }
  }
  return e;
}

std::vector<double> TracedPort::irradiance(double x, double y, double h, const RayTransmission& T,
                                           long long samples, int shifts) const {
  return irradiance(x, y, h, std::vector<RayTransmission>{T}, samples, shifts)[0];
}

std::vector<std::vector<double>> TracedPort::irradiance(double x, double y, double h,
                                                        const std::vector<RayTransmission>& Ts,
                                                        long long samples, int shifts) const {
  const Vec3 P{x, y, tracer_.scene().port_plane_z() - h};
  std::vector<std::vector<double>> e(Ts.size(), std::vector<double>(static_cast<std::size_t>(shifts)));
  std::vector<double> fixed(Ts.size());
  const std::vector<double> uniform = uniform_parts(P, Ts), occluders = occluder_parts(P, Ts);
  for (std::size_t f = 0; f < Ts.size(); ++f) fixed[f] = uniform[f] + occluders[f];
  for (int k = 0; k < shifts; ++k) {
    const std::vector<double> s = sampled_parts(P, Ts, samples, k);
    for (std::size_t f = 0; f < Ts.size(); ++f) e[f][static_cast<std::size_t>(k)] = fixed[f] + s[f];
  }
  return e;
}

StokesIrradiance TracedPort::plane_stokes(double x, double y, double h, long long samples,
                                          int shifts) const {
  const PolarizerFilm& film = tracer_.scene().port.polarizer;
  const double psi = deg2rad(film.axis_deg);
  const Vec3 z{0, 0, 1}, port_axis{std::cos(psi), std::sin(psi), 0};
  // Through the port film alone, and then an ideal analyzer at β lying in the plane.
  const RayTransmission through_film = [&](const Vec3&) { return film.g_up(); };
  const auto analyzer = [&](double beta_deg) -> RayTransmission {
    const Vec3 axis{std::cos(deg2rad(beta_deg)), std::sin(deg2rad(beta_deg)), 0};
    const SheetPolarizerPair films(z, port_axis, film.tau_M, film.tau_m, axis, 1.0, 0.0);
    return [films](const Vec3& k) { return films.transmittance(k); };
  };
  const std::vector<double> s0 = irradiance(x, y, h, through_film, samples, shifts);
  std::vector<double> s1 = irradiance(x, y, h, analyzer(0), samples, shifts), s2 = irradiance(x, y, h, analyzer(45), samples, shifts);
  const std::vector<double> s1b = irradiance(x, y, h, analyzer(90), samples, shifts), s2b = irradiance(x, y, h, analyzer(135), samples, shifts);
  for (std::size_t k = 0; k < s1.size(); ++k) {
    s1[k] -= s1b[k];
    s2[k] -= s2b[k];
  }
  StokesIrradiance out;
  const MeanAndSpread m0 = mean_and_standard_error(s0), m1 = mean_and_standard_error(s1),
                      m2 = mean_and_standard_error(s2);
  out.S0 = m0.mean;
  out.S0_se = m0.sd;
  out.S1 = m1.mean;
  out.S1_se = m1.sd;
  out.S2 = m2.mean;
  out.S2_se = m2.sd;
  return out;
}

}  // namespace polrig
