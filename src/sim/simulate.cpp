#include "polrig/sim/simulate.h"

#include <cmath>
#include <exception>
#include <stdexcept>

#include <fmt/format.h>

#include <tbb/parallel_for.h>

#include "polrig/device/sensor.h"

namespace polrig {

PoseLight light_at_pose(const Rig& rig, double theta_R_deg, double t_s) {
  require_instrument(rig, Instrument::kPairVoltages, "the light at the photodiodes");
  const Source& source = *rig.light;
  const SourceView view = rig.source_view();
  const SourcePose pose{theta_R_deg, t_s};
  PoseLight light;
  const int S = source.shifts();
  if (S == 1) {
    source.irradiance(view, pose, light.E_Wm2);
  } else {  // the mean over the shifts
    std::vector<double> e(static_cast<std::size_t>(6 * S));
    source.irradiance(view, pose, e);
    for (std::size_t m = 0; m < 6; ++m) {
      double sum = 0;
      for (int k = 0; k < S; ++k) sum += e[static_cast<std::size_t>(k) * 6 + m];
      light.E_Wm2[m] = sum / static_cast<double>(S);
    }
  }
  const Polarization p = source.polarization(view, pose);
  light.theta_deg = p.theta_deg;
  light.d = p.d;
  return light;
}

Rig coaxial(const Rig& rig) {
  Rig c = rig;
  c.eccentricity.L_IS = 0;
  c.eccentricity.L_S = 0;
  return c;
}

std::array<double, 6> ideal_irradiance(const Rig& rig, double theta_R_deg, double t_s) {
  return rig.light->ideal_irradiance(rig.source_view(), {theta_R_deg, t_s});
}

namespace {

Stop simulate_stop(const Rig& rig, std::size_t index, double theta_R_deg, double t_s,
                   std::array<double, 3>* samples_out) {
  Stop s;
  s.theta_R_deg = theta_R_deg;
  s.t_s = t_s;
  s.light = light_at_pose(rig, theta_R_deg, t_s);
  const CalibrationParams& truth = rig.device.truth;
  const Electronics& el = rig.electronics;
  s.V_ideal = pair_voltages(truth, el, ideal_irradiance(rig, theta_R_deg, t_s), s.light.theta_deg, s.light.d);
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
  require_instrument(rig, Instrument::kPairVoltages, "simulate");
  const std::vector<double> angles = rig.schedule.table_angles_deg();
  const std::vector<double> times = rig.schedule.stop_times_s();
  Simulation sim;
  sim.samples_per_stop = rig.schedule.samples_per_stop;
  sim.time_dependent = rig.light->has(Source::kTimeDependent);
  sim.stops.resize(angles.size());
  if (keep_samples) sim.samples.resize(angles.size() * static_cast<std::size_t>(sim.samples_per_stop));
  rig.light->prepare(progress);
  progress.begin("simulate: stops", static_cast<long long>(angles.size()));
  // A stop's error is kept in its own slot and the first stop's is rethrown, so that which
  // error a user sees does not depend on the thread schedule.
  std::vector<std::exception_ptr> failure(angles.size());
  tbb::parallel_for(std::size_t{0}, angles.size(), [&](std::size_t s) {
    std::array<double, 3>* out =
        keep_samples ? &sim.samples[s * static_cast<std::size_t>(sim.samples_per_stop)] : nullptr;
    try {
      sim.stops[s] = simulate_stop(rig, s, angles[s], times[s], out);
    } catch (...) {
      failure[s] = std::current_exception();
    }
    progress.advance();
  });
  for (const std::exception_ptr& e : failure)
    if (e) std::rethrow_exception(e);
  progress.finish();
  return sim;
}

}  // namespace polrig
