#pragma once
// The measurement chain for one rig: table pose → light at each channel (source model) →
// device (films, log amplifiers) → noise → ADC, for every stop of the schedule.
#include <array>
#include <vector>

#include "polrig/progress.h"
#include "polrig/rig/rig.h"
#include "polrig/source/traced_source.h"

namespace polrig {

// The light reaching the six channels at one table pose.
struct PoseLight {
  std::array<double, 6> E_Wm2;  // irradiance at each photodiode position
  double theta_deg;             // polarization angle in the sensor frame, [0°, 180°)
  double d;                     // degree of linear polarization
};

// The light at each photodiode. For a traced source E_Wm2 is an effective irradiance (the mean
// of traced_effective_irradiance over its shifts).
PoseLight light_at_pose(const Rig& rig, double theta_R_deg);

// The rig with port and sensor on the table's axis (L_IS = L_S = 0).
Rig coaxial(const Rig& rig);

// The irradiances of the ideal, eccentricity-free measurement that V_ideal and ΔV refer to: the
// uniform E_0 of the cos⁴ model; for a traced source, the coaxial rig's effective irradiances
// at the same pose (its optics, obliquity and port pattern included, which calibration absorbs,
// and no eccentricity).
std::array<double, 6> ideal_irradiance(const Rig& rig, double theta_R_deg);

// A traced source's effective irradiance at channel m, one value per shift: the channel's traced
// signal through its films and optics (TracedSource::channel_signal) divided by Eq. 15's
// normal-incidence bracket for the pose's (θ, d), so that the device model, which applies the
// bracket, reproduces the traced signal, obliquity effects included. The channel's analyzer is
// the film its truth α_m and kd_m stand for, turned with the table.
std::vector<double> traced_effective_irradiance(const Rig& rig, double theta_R_deg, int m);

// What traced_effective_irradiance computes channel m's signal from: the photodiode (or lens
// axis) in the scene frame, the analyzer film turned with the table, and Eq. 15's bracket.
struct TracedChannel {
  Point2 p_scene;
  AnalyzerFilm film;
  double bracket = 1;
};
TracedChannel traced_channel(const Rig& rig, double theta_R_deg, int m);

struct Stop {
  double theta_R_deg;
  PoseLight light;
  std::array<double, 3> V_ideal;  // the rig's device without eccentricity (ideal_irradiance)
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
// A traced rig reports the sphere solve and the stops to `progress`.
Simulation simulate(const Rig& rig, bool keep_samples = false, const Progress& progress = {});

}  // namespace polrig
