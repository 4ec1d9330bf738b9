#pragma once
// The measurement chain for one rig: table pose → light at each channel (source model) →
// device (films, log amplifiers) → noise → ADC, for every stop of the schedule.
#include <array>
#include <vector>

#include "polrig/rig/rig.h"

namespace polrig {

// The light reaching the six channels at one table pose.
struct PoseLight {
  std::array<double, 6> E_Wm2;  // irradiance at each photodiode position
  double theta_deg;             // polarization angle in the sensor frame, [0°, 180°)
  double d;                     // degree of linear polarization
};

PoseLight light_at_pose(const Rig& rig, double theta_R_deg);

struct Stop {
  double theta_R_deg;
  PoseLight light;
  std::array<double, 3> V_ideal;  // the rig's device under uniform light E_0: no eccentricity
  std::array<double, 3> V_ecc;    // with the pose's irradiances, before noise and ADC
  std::array<double, 3> V_mean;   // mean of the noisy, ADC-quantized samples
  std::array<double, 3> V_std;    // their sample standard deviation (n − 1); 0 for one sample
};

struct Simulation {
  std::vector<Stop> stops;
  int samples_per_stop = 0;
  // Every quantized sample, stop-major (stop s, sample n at s·samples_per_stop + n);
  // empty unless asked for.
  std::vector<std::array<double, 3>> samples;
};

// Runs every stop in parallel (TBB); the result does not depend on the thread count, since
// each noise value is a pure function of (seed, stop, channel, sample).
Simulation simulate(const Rig& rig, bool keep_samples = false);

}  // namespace polrig
