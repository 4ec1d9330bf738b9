#pragma once
// The measurement chain for one rig: table pose → light at each channel (source model) →
// device (films, log amplifiers) → noise → ADC, for every stop of the schedule.
#include <array>
#include <vector>

#include "polrig/progress.h"
#include "polrig/rig/rig.h"

namespace polrig {

// The light reaching the six channels at one table pose.
struct PoseLight {
  std::array<double, 6> E_Wm2;  // irradiance at each photodiode position
  double theta_deg;             // polarization angle in the sensor frame, [0°, 180°)
  double d;                     // degree of linear polarization
};

// The light at each photodiode, from the rig's source at table angle θ_R and t_s seconds after
// the first stop. A source with several shifts gives the mean of its per-shift (effective)
// irradiances (Source::irradiance).
PoseLight light_at_pose(const Rig& rig, double theta_R_deg, double t_s = 0);

// The rig with port and sensor on the table's axis (L_IS = L_S = 0).
Rig coaxial(const Rig& rig);

// The irradiances of the ideal, eccentricity-free measurement that V_ideal and ΔV refer to
// (Source::ideal_irradiance): the uniform E_0 of the cos⁴ model; for a source without a uniform
// reference, the coaxial rig's irradiances at the same pose (its optics, obliquity and port
// pattern included, which calibration absorbs, and no eccentricity).
std::array<double, 6> ideal_irradiance(const Rig& rig, double theta_R_deg, double t_s = 0);

struct Stop {
  double theta_R_deg;
  double t_s = 0;                 // time since the first stop (Schedule::stop_times_s)
  PoseLight light;
  std::array<double, 3> V_ideal;  // the rig's device without eccentricity (ideal_irradiance)
  std::array<double, 3> V_ecc;    // with the pose's irradiances, before noise and ADC
  std::array<double, 3> V_mean;   // mean of the noisy, ADC-quantized samples
  std::array<double, 3> V_std;    // their sample standard deviation (n − 1); 0 for one sample
};

struct Simulation {
  std::vector<Stop> stops;
  int samples_per_stop = 0;
  bool time_dependent = false;  // the source's light changes during the run (stops.csv gets t_s)
  // Every quantized sample, stop-major (stop s, sample n at s·samples_per_stop + n);
  // empty unless asked for.
  std::vector<std::array<double, 3>> samples;
};

// Runs every stop in parallel (TBB); the result does not depend on the thread count, since
// each noise value is a pure function of (seed, stop, channel, sample).
// Reports the source's preparation (a traced sphere solve) and the stops to `progress`.
Simulation simulate(const Rig& rig, bool keep_samples = false, const Progress& progress = {});

}  // namespace polrig
