#include "polrig/source/cos4_port.h"

#include <cmath>

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

void Cos4PortSource::irradiance_over_turn(const SourceView& rig, const CsTurn& turn, std::span<double> E,
                                          const Progress&) const {
  const int n = turn.steps();
  const double* c = turn.cos_theta();
  const double* s = turn.sin_theta();
  const Point2 port = port_centre(rig.eccentricity);
  const auto p0 = photodiode_positions(rig.sensor.ring, rig.eccentricity, 0.0);
  const Cos4Source& source = rig.settings.cos4;
  for (int m = 0; m < 6; ++m) {
    const double qx = p0[m].x(), qy = p0[m].y();
    double* Em = E.data() + m * n;
    for (int k = 0; k < n; ++k) {
      const double x = c[k] * qx - s[k] * qy - port.x();  // P_m(θ_R) − O_IS
      const double y = s[k] * qx + c[k] * qy - port.y();
      Em[k] = source.falloff(x * x + y * y);
    }
  }
}

double Cos4PortSource::eq6_log_ratio(const SourceView& rig, int pair) const {
  const auto p0 = photodiode_positions(rig.sensor.ring, rig.eccentricity, 0.0);
  const double L_o2 = rig.settings.cos4.L_o * rig.settings.cos4.L_o;
  const double L_IS2 = rig.eccentricity.L_IS * rig.eccentricity.L_IS;
  const double L_Rj2 = p0[pair_j(pair)].squaredNorm();
  const double L_Rh2 = p0[pair_h(pair)].squaredNorm();
  return std::log10((L_o2 + L_Rh2 + L_IS2) / (L_o2 + L_Rj2 + L_IS2));
}

}  // namespace polrig
