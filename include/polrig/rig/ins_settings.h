#pragma once
// A unit-array rig's motion, IMU and navigation filter, in the units a rig file gives them (the
// trajectory.*, imu.* and navigation.* keys; docs/formats.md §1.14). Plain numbers: study/navigation.h
// turns them into ins/'s TrajectorySpec, ImuErrorSpec and FilterSettings. The start of the run is
// the sky's site and first_stop_utc (sky.* keys).
#include <array>
#include <string>
#include <vector>

namespace polrig {

// The vehicle: its attitude and speed at the start, then segments of constant acceleration, turn
// rate or climb rate (at most one non-zero per segment; none: a static segment when at rest, a
// cruise at constant speed otherwise). Without segments the run is one segment of duration_s.
struct TrajectorySettings {
  double heading_deg = 0;  // yaw, clockwise from north (ins/attitude.h)
  double pitch_deg = 0;
  double roll_deg = 0;
  double speed_mps = 0;    // along the body's forward axis
  double duration_s = 1200;  // Z21's static test: 20 min
  std::vector<double> segment_s, segment_accel_mps2, segment_turn_deg_s, segment_climb_deg_s;
  double vibration_mps2 = 0;  // rms per axis while moving (ins/trajectory.h) [C: 0]
};

// One triad's errors per axis (x, y, z of b), in the units of its keys: the gyro's in °/h (bias,
// turn-on σ, bias instability σ), °/√h (ARW), °/h/√h (rate random walk); the accelerometer's in
// µg, µg/√Hz (VRW), µg/√s. Scale factors in ppm; misalignment σ in degrees.
struct TriadSettings {
  std::array<double, 3> bias{0, 0, 0};
  std::array<double, 3> turn_on_sigma{0, 0, 0};
  std::array<double, 3> bias_instability{0, 0, 0};
  std::array<double, 3> correlation_time_s{3600, 3600, 3600};
  std::array<double, 3> white_noise{0, 0, 0};
  std::array<double, 3> random_walk{0, 0, 0};
  std::array<double, 3> scale_factor_ppm{0, 0, 0};
  double misalignment_deg = 0;
};

// Defaults [C]: Z21's Table 1 as spec §4.1 reads it (ins/imu.h's z21_imu_errors): gyro turn-on bias
// 5°/h and ARW 0.5°/√h, accelerometer turn-on bias 50 µg and VRW 25 µg/√Hz, at 100 Hz.
inline TriadSettings turn_on_and_white(double sigma, double density) {
  TriadSettings t;
  t.turn_on_sigma = {sigma, sigma, sigma};
  t.white_noise = {density, density, density};
  return t;
}
struct ImuSettings {
  double rate_hz = 100;
  TriadSettings gyro = turn_on_and_white(5, 0.5);
  TriadSettings accel = turn_on_and_white(50, 25);
};

// The SINS/PNS filter (ins/filter.h) and the INS's start. The INS starts at the truth plus the
// initial errors (spec §4.7: a 5°/h gyro cannot gyrocompass, so Z21's heading came from elsewhere);
// P0 from the 1σ settings and, for the biases, the IMU's own turn-on and constant biases.
struct NavigationSettings {
  double sigma_H_deg = 0.1;       // the compass' elevation σ (Z21 Table 1)
  double sigma_A_deg = 0.0405;    // its azimuth σ in n (navigation.measurement azimuth, sun-vector)
  bool adaptive = true;           // Sage–Husa R
  double forgetting_factor = 0.98;  // Z21's b
  bool hold_height = true;        // Z21's barometer: h held at the start's height
  std::array<double, 3> initial_attitude_error_deg{0, 0, 0};  // roll, pitch, heading added to the truth
  // A simulated run's INS starts at the truth plus errors drawn from P0 with the rig's seed ("drawn")
  // or at the truth ("none"); a measured log's starts where its rig says [C: drawn].
  std::string initial_errors = "drawn";
  std::array<double, 3> attitude_sigma_deg{0.05, 0.05, 0.5};  // P0: φ_E, φ_N, φ_U
  double velocity_sigma_mps = 0.02;                          // P0: δV per axis
  double position_sigma_m = 200;                             // P0: north and east
  double pns_window_s = 300;      // PNS: the sun elevations of the last window fix the position
  // PNS's level (the elevation needs roll and pitch): "accelerometer", the mean specific force over
  // each reading's interval (a vehicle at rest or in straight, steady motion), or "sins", the free
  // INS's attitude (which drifts with the gyro biases) [C: accelerometer].
  std::string pns_level = "accelerometer";
  // What the integrated filter takes from the compass (ins/filter.h FilterSettings::SunMeasurement):
  // "elevation" (with the tilt columns) [C], "elevation-z21" (Z21's position-only H), "azimuth" (the
  // sun's azimuth: heading), "sun-vector" (both).
  std::string measurement = "elevation";
  // The integrated filter's level for H^n: "ins", its own attitude (Z21, spec §4.2), or
  // "accelerometer", as PNS's (unsteady readings give no update) [C: ins].
  std::string integrated_level = "ins";
  // Zero-velocity updates when the IMU says the vehicle is at rest (ins/zupt.h), each velocity
  // component with R = zupt_sigma_mps² [C: off, Z21 has none; 1 mm/s].
  bool zupt = false;
  double zupt_sigma_mps = 1e-3;
};

}  // namespace polrig
