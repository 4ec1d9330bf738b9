#include "polrig/source/cos4_port.h"

#include <array>
#include <cmath>

#include "polrig/units.h"
#include "polrig/vector_log.h"

namespace polrig {

Polarization Cos4PortSource::polarization(const SourceView& rig, const SourcePose& pose) const {
  return {sensor_polarization_angle_deg(pose.theta_R_deg, rig.settings.polarizer_deg), rig.sensor.d};
}

void Cos4PortSource::irradiance(const SourceView& rig, const SourcePose& pose, std::span<double> E) const {
  const Point2 port = port_centre(rig.eccentricity);
  const auto p = photodiode_positions(rig.sensor.ring, rig.eccentricity, pose.theta_R_deg);
  for (std::size_t m = 0; m < 6; ++m) E[m] = rig.settings.cos4.irradiance(p[m], port);
}

std::array<double, 6> Cos4PortSource::ideal_irradiance(const SourceView& rig, const SourcePose&) const {
  const double E0 = rig.settings.cos4.E_0;
  return {E0, E0, E0, E0, E0, E0};
}

namespace {
// cos⁴φ of channel m over the turn: compiled three times, below, for baseline x86-64, AVX2 and
// AVX-512, with the same operations in the same order (no FMA: this file is built with
// -ffp-contract=off and the target attributes name no FMA), so all give the same bits (test
// Cs.EveryCodePathGivesTheSameBits).
[[gnu::always_inline]] inline void falloffs_over_turn(const Cos4Source& source, const double* c, const double* s,
                                                      const std::array<Point2, 6>& p0, const Point2& port,
                                                      double* E, int n) {
  const double px = port.x(), py = port.y();
  for (int m = 0; m < 6; ++m) {
    const double qx = p0[static_cast<std::size_t>(m)].x(), qy = p0[static_cast<std::size_t>(m)].y();
    double* Em = E + m * n;
    for (int k = 0; k < n; ++k) {
      const double x = c[k] * qx - s[k] * qy - px;  // P_m(θ_R) − O_IS
      const double y = s[k] * qx + c[k] * qy - py;
      Em[k] = source.falloff(x * x + y * y);
    }
  }
}

// The widest of three compilations of one loop that this CPU runs (vector_log.h's simd_paths):
// each does the same operations in the same order.
template <class F>
F widest(F avx512, F avx2, F baseline) {
  return avx512_paths() ? avx512 : avx2_paths() ? avx2 : baseline;
}

__attribute__((target("avx512f"))) void falloffs_over_turn_avx512(const Cos4Source& source, const double* c,
                                                                  const double* s, const std::array<Point2, 6>& p0,
                                                                  const Point2& port, double* E, int n) {
  falloffs_over_turn(source, c, s, p0, port, E, n);
}
__attribute__((target("avx2"))) void falloffs_over_turn_avx2(const Cos4Source& source, const double* c,
                                                             const double* s, const std::array<Point2, 6>& p0,
                                                             const Point2& port, double* E, int n) {
  falloffs_over_turn(source, c, s, p0, port, E, n);
}
void falloffs_over_turn_baseline(const Cos4Source& source, const double* c, const double* s,
                                 const std::array<Point2, 6>& p0, const Point2& port, double* E, int n) {
  falloffs_over_turn(source, c, s, p0, port, E, n);
}
}  // namespace

void Cos4PortSource::irradiance_over_turn(const SourceView& rig, const CsTurn& turn, std::span<double> E,
                                          const Progress&) const {
  const Point2 port = port_centre(rig.eccentricity);
  const auto p0 = photodiode_positions(rig.sensor.ring, rig.eccentricity, 0.0);
  widest(falloffs_over_turn_avx512, falloffs_over_turn_avx2, falloffs_over_turn_baseline)(
      rig.settings.cos4, turn.cos_theta(), turn.sin_theta(), p0, port, E.data(), turn.steps());
}

namespace {
// Eq. 5's logarithm from the cos⁴ law in closed form. E_m ∝ (L_o²/D_m)², D_m = L_o² + L_m² and
// L_m = |P_m(θ_R) − O_IS| (source/cos4.h), so E_j/E_h = (D_h/D_j)² and
//   ln(E_j/E_h) = 2·ln(D_h/D_j)                                       (docs/physics.md, Eq. 5)
// one division per value where the irradiances took three (two falloffs and their ratio), and a
// value at least as exact: D_m are the falloffs' own denominators, computed with the same
// operations, and one rounding (the quotient) replaces seven; ×2 is exact.
// Here the quotients D_h/D_j of the three pairs into out[i·n + k]; compiled three times, below,
// for baseline x86-64, AVX2 and AVX-512 with the same operations in the same order (no FMA): the
// same bits (tests Cs.Cos4LogRatiosGiveTheSameBitsOnEveryPath, Cs.EveryCodePathGivesTheSameBits).
[[gnu::always_inline]] inline void distance_ratios_over_turn(double L_o2, const double* c, const double* s,
                                                             const std::array<Point2, 6>& p0, const Point2& port,
                                                             double* out, int n) {
  const double px = port.x(), py = port.y();
  for (int i = 0; i < 3; ++i) {
    const Point2& pj = p0[static_cast<std::size_t>(pair_j(i))];
    const Point2& ph = p0[static_cast<std::size_t>(pair_h(i))];
    const double jx = pj.x(), jy = pj.y(), hx = ph.x(), hy = ph.y();
    double* r = out + i * n;
    for (int k = 0; k < n; ++k) {
      const double xj = c[k] * jx - s[k] * jy - px;  // P_j(θ_R) − O_IS
      const double yj = s[k] * jx + c[k] * jy - py;
      const double xh = c[k] * hx - s[k] * hy - px;
      const double yh = s[k] * hx + c[k] * hy - py;
      r[k] = (L_o2 + (xh * xh + yh * yh)) / (L_o2 + (xj * xj + yj * yj));
    }
  }
}

// ×2, exact (the 2 of 2·ln(D_h/D_j)), compiled three times for the same reason.
[[gnu::always_inline]] inline void doubled(double* v, std::size_t n) {
  for (std::size_t k = 0; k < n; ++k) v[k] += v[k];
}
__attribute__((target("avx512f"))) void doubled_avx512(double* v, std::size_t n) { doubled(v, n); }
__attribute__((target("avx2"))) void doubled_avx2(double* v, std::size_t n) { doubled(v, n); }
void doubled_baseline(double* v, std::size_t n) { doubled(v, n); }

__attribute__((target("avx512f"))) void distance_ratios_over_turn_avx512(double L_o2, const double* c,
                                                                        const double* s, const std::array<Point2, 6>& p0,
                                                                        const Point2& port, double* out, int n) {
  distance_ratios_over_turn(L_o2, c, s, p0, port, out, n);
}
__attribute__((target("avx2"))) void distance_ratios_over_turn_avx2(double L_o2, const double* c, const double* s,
                                                                    const std::array<Point2, 6>& p0,
                                                                    const Point2& port, double* out, int n) {
  distance_ratios_over_turn(L_o2, c, s, p0, port, out, n);
}
void distance_ratios_over_turn_baseline(double L_o2, const double* c, const double* s,
                                        const std::array<Point2, 6>& p0, const Point2& port, double* out, int n) {
  distance_ratios_over_turn(L_o2, c, s, p0, port, out, n);
}
}  // namespace

void Cos4PortSource::log_ratio_over_turn(const SourceView& rig, const CsTurn& turn, std::span<double> out) const {
  const int n = turn.steps();
  const Point2 port = port_centre(rig.eccentricity);
  const auto p0 = photodiode_positions(rig.sensor.ring, rig.eccentricity, 0.0);
  const double L_o2 = rig.settings.cos4.L_o * rig.settings.cos4.L_o;
  widest(distance_ratios_over_turn_avx512, distance_ratios_over_turn_avx2, distance_ratios_over_turn_baseline)(
      L_o2, turn.cos_theta(), turn.sin_theta(), p0, port, out.data(), n);
  const std::size_t values = static_cast<std::size_t>(3 * n);
  log_array(out.data(), out.data(), values);
  widest(doubled_avx512, doubled_avx2, doubled_baseline)(out.data(), values);
}

namespace {
double eq6_log_ratio_at(const SourceView& rig, const std::array<Point2, 6>& p0, int pair) {
  const double L_o2 = rig.settings.cos4.L_o * rig.settings.cos4.L_o;
  const double L_IS2 = rig.eccentricity.L_IS * rig.eccentricity.L_IS;
  const double L_Rj2 = p0[pair_j(pair)].squaredNorm();
  const double L_Rh2 = p0[pair_h(pair)].squaredNorm();
  return std::log10((L_o2 + L_Rh2 + L_IS2) / (L_o2 + L_Rj2 + L_IS2));
}
}  // namespace

double Cos4PortSource::eq6_log_ratio(const SourceView& rig, int pair) const {
  return eq6_log_ratio_at(rig, photodiode_positions(rig.sensor.ring, rig.eccentricity, 0.0), pair);
}

std::array<double, 3> Cos4PortSource::eq6_log_ratios(const SourceView& rig) const {
  const auto p0 = photodiode_positions(rig.sensor.ring, rig.eccentricity, 0.0);
  return {eq6_log_ratio_at(rig, p0, 0), eq6_log_ratio_at(rig, p0, 1), eq6_log_ratio_at(rig, p0, 2)};
}

namespace {
class Cos4PortViews final : public LightAlongViews {
 public:
  Cos4PortViews(double S0, double polarizer_deg, double d) : S0_(S0), d_(d) {
    p_ = {std::cos(deg2rad(polarizer_deg)), std::sin(deg2rad(polarizer_deg)), 0.0};
  }
  void along(std::span<const Vec3> views, std::span<ViewLight> out) const override {
    (avx2_paths() ? along_avx2 : along_baseline)(*this, views.data(), out.data(), views.size());
  }

 private:
  // Without branches, so that the compiler vectorises it (every lane computed, then chosen): the
  // same operations as e = p − v·(p·v), unit(e) per view looking up into the port, so the same
  // bits; views not looking up (v_z ≥ 0) give no light.
  static inline __attribute__((always_inline)) void along_in(const Cos4PortViews& l, const Vec3* views,
                                                             ViewLight* out, std::size_t n) {
    const Vec3 p = l.p_;
    const double S0 = l.S0_, d = l.d_;
    const bool polarized = d > 0;
    for (std::size_t i = 0; i < n; ++i) {
      const Vec3& v = views[i];
      const bool up = v[2] < 0;  // looking up into the port
      const Vec3 e = vec3::sub(p, vec3::mul(v, vec3::dot(p, v)));  // |e| ≥ |v_z| > 0 when up
      const double r = 1.0 / std::sqrt(vec3::dot(e, e));            // vec3::unit's factor
      const bool lit = up && polarized;
      out[i].S0 = up ? S0 : 0.0;
      out[i].e = {lit ? e[0] * r : 0.0, lit ? e[1] * r : 0.0, lit ? e[2] * r : 0.0};
      out[i].d = up ? d : 0.0;
    }
  }
  __attribute__((target("avx2"))) static void along_avx2(const Cos4PortViews& l, const Vec3* views, ViewLight* out,
                                                         std::size_t n) {
    along_in(l, views, out, n);
  }
  static void along_baseline(const Cos4PortViews& l, const Vec3* views, ViewLight* out, std::size_t n) {
    along_in(l, views, out, n);
  }

  double S0_, d_;
  Vec3 p_;
};
}  // namespace

std::unique_ptr<const LightAlongViews> Cos4PortSource::light_along_views(const SourceView& rig,
                                                                         const SourcePose& pose) const {
  auto light = std::make_unique<Cos4PortViews>(rig.settings.cos4.E_0, rig.settings.polarizer_deg, rig.sensor.d);
  const double c = std::cos(deg2rad(pose.theta_R_deg)), s = std::sin(deg2rad(pose.theta_R_deg));
  light->axes = {{c, s, 0}, {s, -c, 0}, {0, 0, -1}};
  return light;
}

}  // namespace polrig
