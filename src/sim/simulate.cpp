#include "polrig/sim/simulate.h"

#include <cmath>

#include <tbb/parallel_for.h>

#include "polrig/device/sensor.h"

namespace polrig {

PoseLight light_at_pose(const Rig& rig, double theta_R_deg) {
  PoseLight light;
  const Point2 port = port_centre(rig.eccentricity);
  const auto p = photodiode_positions(rig.device.ring, rig.eccentricity, theta_R_deg);
  if (const TracedSource* traced = rig.source.traced.get()) {
    // The traced port: irradiance from the sphere solve; d and the angle from its film.
    for (int m = 0; m < 6; ++m)
      light.E_Wm2[m] = traced->photodiode_irradiance(to_scene(p[m] - port), rig.source.cos4.L_o);
    light.theta_deg = sensor_polarization_angle_deg(theta_R_deg, traced->polarizer_axis_rig_deg());
    light.d = traced->degree_of_polarization();
    return light;
  }
  for (int m = 0; m < 6; ++m) light.E_Wm2[m] = rig.source.cos4.irradiance(p[m], port);
  light.theta_deg = sensor_polarization_angle_deg(theta_R_deg, rig.source.polarizer_deg);
  light.d = rig.device.d;
  return light;
}

namespace {

Stop simulate_stop(const Rig& rig, std::size_t index, double theta_R_deg,
                   std::array<double, 3>* samples_out) {
  Stop s;
  s.theta_R_deg = theta_R_deg;
  s.light = light_at_pose(rig, theta_R_deg);
  const CalibrationParams& truth = rig.device.truth;
  const Electronics& el = rig.electronics;
  const double E0 = rig.source.cos4.E_0;
  const std::array<double, 6> uniform{E0, E0, E0, E0, E0, E0};
  s.V_ideal = pair_voltages(truth, el, uniform, s.light.theta_deg, s.light.d);
  s.V_ecc = pair_voltages(truth, el, s.light.E_Wm2, s.light.theta_deg, s.light.d);

  const int n = rig.schedule.samples_per_stop;
  for (int i = 0; i < 3; ++i) {
    double sum = 0.0;
    double first = 0.0, sum_sq = 0.0;  // shifted sums: exact for identical samples
    for (int k = 0; k < n; ++k) {
      const double noise =
          el.noise_sigma_V * standard_normal(rig.seed, index, static_cast<std::uint64_t>(i),
                                             static_cast<std::uint64_t>(k));
      const double v = adc_quantize(s.V_ecc[i] + noise, el);
      if (samples_out) samples_out[k][i] = v;
      if (k == 0) first = v;
      sum += v - first;
      sum_sq += (v - first) * (v - first);
    }
    const double mean_shift = sum / n;
    s.V_mean[i] = first + mean_shift;
    s.V_std[i] = n > 1 ? std::sqrt(std::max(0.0, (sum_sq - n * mean_shift * mean_shift) / (n - 1)))
                       : 0.0;
  }
  return s;
}

}  // namespace

Simulation simulate(const Rig& rig, bool keep_samples) {
  const std::vector<double> angles = rig.schedule.table_angles_deg();
  Simulation sim;
  sim.samples_per_stop = rig.schedule.samples_per_stop;
  sim.stops.resize(angles.size());
  if (keep_samples) sim.samples.resize(angles.size() * static_cast<std::size_t>(sim.samples_per_stop));
  tbb::parallel_for(std::size_t{0}, angles.size(), [&](std::size_t s) {
    std::array<double, 3>* out =
        keep_samples ? &sim.samples[s * static_cast<std::size_t>(sim.samples_per_stop)] : nullptr;
    sim.stops[s] = simulate_stop(rig, s, angles[s], out);
  });
  return sim;
}

}  // namespace polrig
