#include "polrig/source/cos4_port.h"

#include <array>
#include <cmath>

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
// cos⁴φ of channel m over the turn: compiled twice, below, for baseline x86-64 and for AVX2, with
// the same operations in the same order (no FMA: this file is built with -ffp-contract=off and
// AVX2 alone brings none), so both give the same bits (test Cs.BaselineAndAvx2PathsGiveTheSameBits).
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
  (avx2_paths() ? falloffs_over_turn_avx2 : falloffs_over_turn_baseline)(
      rig.settings.cos4, turn.cos_theta(), turn.sin_theta(), p0, port, E.data(), turn.steps());
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

}  // namespace polrig
