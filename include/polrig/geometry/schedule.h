#pragma once
// The rotary table's schedule: where it stops and how many samples each stop records.
#include <vector>

namespace polrig {

struct Schedule {
  // Stops at start, start+step, … up to and including stop (the paper's 0°:10°:360°, 37 stops),
  // unless an explicit list of angles is given.
  double start_deg = 0.0;
  double step_deg = 10.0;
  double stop_deg = 360.0;
  std::vector<double> angles_deg;  // explicit stops; when non-empty it replaces start/step/stop
  // When > 0 (and no explicit list): `count` stops start + k·step, k < count, replacing stop_deg;
  // step may be 0 (a static time series at one table angle).
  int count = 0;
  int samples_per_stop = 40;
  // The table's timing, for sources that change during a run (the sky): it turns at speed_deg_s
  // between stops and dwells dwell_s at each (spec sky-and-compasses.md §1.4: the paper's 10°
  // steps take 3 s per stop).
  double speed_deg_s = 5.0;
  double dwell_s = 1.0;

  // A camera's stops (device.kind dofp-camera; H17 §4.1, spec sky-and-compasses.md §2.4): first
  // one stop per unpolarized level (the polarizer out, the table at start_deg: step 1's uniform
  // frames), then every table angle at each polarized intensity, intensity-major (step 2).
  // Intensities are relative to the source's own level (cos4's E_0, the sky's radiance).
  std::vector<double> unpolarized_levels;  // step 1's levels; none: no unpolarized stops
  std::vector<double> intensities = {1.0};  // step 2's intensities
  int frames_per_stop = 1;                  // frames exposed at each stop

  std::vector<double> table_angles_deg() const;
  // Time of each stop since the first: t_k = Σ_{i=1..k} |θ_i − θ_{i−1}|/speed + k·dwell
  // (t_0 = 0), one per table_angles_deg().
  std::vector<double> stop_times_s() const;
};

}  // namespace polrig
