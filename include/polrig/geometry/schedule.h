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
  int samples_per_stop = 40;

  std::vector<double> table_angles_deg() const;
};

}  // namespace polrig
