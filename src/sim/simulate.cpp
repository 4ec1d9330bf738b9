#include "polrig/sim/simulate.h"

#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include <tbb/parallel_for.h>

#include "polrig/device/sensor.h"
#include "polrig/source/traced_source.h"

namespace polrig {

PoseLight light_at_pose(const Rig& rig, double theta_R_deg) {
  PoseLight light;
  const Point2 port = port_centre(rig.eccentricity);
  const auto p = photodiode_positions(rig.device.ring, rig.eccentricity, theta_R_deg);
  if (const TracedSource* traced = rig.source.traced.get()) {
    // The traced port: d and the angle from its film; each channel's signal traced.
    light.theta_deg = sensor_polarization_angle_deg(theta_R_deg, traced->polarizer_axis_rig_deg());
    light.d = traced->degree_of_polarization();
    for (int m = 0; m < 6; ++m) {
      const std::vector<double> e = traced_effective_irradiance(rig, theta_R_deg, m);
      double sum = 0;
      for (double x : e) sum += x;
      light.E_Wm2[m] = sum / static_cast<double>(e.size());
    }
    return light;
  }
  for (int m = 0; m < 6; ++m) light.E_Wm2[m] = rig.source.cos4.irradiance(p[m], port);
  light.theta_deg = sensor_polarization_angle_deg(theta_R_deg, rig.source.polarizer_deg);
  light.d = rig.device.d;
  return light;
}

Rig coaxial(const Rig& rig) {
  Rig c = rig;
  c.eccentricity.L_IS = 0;
  c.eccentricity.L_S = 0;
  return c;
}

std::array<double, 6> ideal_irradiance(const Rig& rig, double theta_R_deg) {
  if (rig.source.traced) return light_at_pose(coaxial(rig), theta_R_deg).E_Wm2;
  const double E0 = rig.source.cos4.E_0;
  return {E0, E0, E0, E0, E0, E0};
}

TracedChannel traced_channel(const Rig& rig, double theta_R_deg, int m) {
  const TracedSource& traced = *rig.source.traced;
  const Point2 p = photodiode_positions(rig.device.ring, rig.eccentricity, theta_R_deg)[static_cast<std::size_t>(m)] -
                   port_centre(rig.eccentricity);
  const CalibrationParams& truth = rig.device.truth;
  // The sensor frame is the scene frame turned by −θ_R (both seen from above; the table turns
  // anticlockwise seen from below): a sensor-frame angle φ is at φ − θ_R in the scene.
  const AnalyzerFilm film{film_axis_from_alpha_deg(truth, m) - theta_R_deg, 1.0 + truth.kd[static_cast<std::size_t>(m)]};
  const double theta = sensor_polarization_angle_deg(theta_R_deg, traced.polarizer_axis_rig_deg());
  return {to_scene(p), film, channel_response(truth, m, theta, traced.degree_of_polarization())};
}

std::vector<double> traced_effective_irradiance(const Rig& rig, double theta_R_deg, int m) {
  const TracedChannel c = traced_channel(rig, theta_R_deg, m);
  std::vector<double> e = rig.source.traced->channel_signal(c.p_scene, rig.source.cos4.L_o, c.film);
  for (double& x : e) x /= c.bracket;
  return e;
}

namespace {

Stop simulate_stop(const Rig& rig, std::size_t index, double theta_R_deg,
                   std::array<double, 3>* samples_out) {
  Stop s;
  s.theta_R_deg = theta_R_deg;
  s.light = light_at_pose(rig, theta_R_deg);
  const CalibrationParams& truth = rig.device.truth;
  const Electronics& el = rig.electronics;
  s.V_ideal = pair_voltages(truth, el, ideal_irradiance(rig, theta_R_deg), s.light.theta_deg, s.light.d);
  s.V_ecc = pair_voltages(truth, el, s.light.E_Wm2, s.light.theta_deg, s.light.d);
  // The keys' ranges keep these finite; should a combination of values escape them, say where,
  // rather than let the ADC refuse an anonymous voltage.
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(s.V_ecc[i]) || !std::isfinite(s.V_ideal[i]))
      throw std::domain_error(fmt::format(
          "stop {} (θ_R = {}°): pair {}'s voltage is not finite (V_ecc = {}, V_ideal = {}, "
          "irradiances E{} = {} and E{} = {} W/m²); the rig's values are beyond what the model "
          "represents", index, theta_R_deg, i + 1, s.V_ecc[i], s.V_ideal[i], pair_j(i) + 1,
          s.light.E_Wm2[static_cast<std::size_t>(pair_j(i))], pair_h(i) + 1,
          s.light.E_Wm2[static_cast<std::size_t>(pair_h(i))]));

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

Simulation simulate(const Rig& rig, bool keep_samples, const Progress& progress) {
  const std::vector<double> angles = rig.schedule.table_angles_deg();
  Simulation sim;
  sim.samples_per_stop = rig.schedule.samples_per_stop;
  sim.stops.resize(angles.size());
  if (keep_samples) sim.samples.resize(angles.size() * static_cast<std::size_t>(sim.samples_per_stop));
  if (rig.source.traced) rig.source.traced->solve(progress);
  progress.begin("simulate: stops", static_cast<long long>(angles.size()));
  tbb::parallel_for(std::size_t{0}, angles.size(), [&](std::size_t s) {
    std::array<double, 3>* out =
        keep_samples ? &sim.samples[s * static_cast<std::size_t>(sim.samples_per_stop)] : nullptr;
    sim.stops[s] = simulate_stop(rig, s, angles[s], out);
    progress.advance();
  });
  progress.finish();
  return sim;
}

}  // namespace polrig
