#pragma once
// A calibration rig: the sensor on the rotary table under the integrating sphere's port.
// A default-constructed Rig is the seed paper's indoor rig (rigs/wang2019-indoor.yaml).
#include <cstdint>
#include <string>

#include "polrig/device/electronics.h"
#include "polrig/device/sensor.h"
#include "polrig/rig/geometry.h"
#include "polrig/rig/schedule.h"
#include "polrig/source/cos4.h"

namespace polrig {

struct SourceSpec {
  std::string model = "cos4";  // the analytic source; "traced" is a planned second model
  Cos4Source cos4;             // L_o, E_0
  double polarizer_deg = 0.0;  // port polarizer axis in the rig frame
};

struct Rig {
  SensorSpec device;
  SourceSpec source;
  Eccentricity eccentricity;
  Schedule schedule;
  Electronics electronics;
  std::uint64_t seed = 20190806;
};

}  // namespace polrig
