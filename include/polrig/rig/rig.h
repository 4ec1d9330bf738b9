#pragma once
// A calibration rig: the sensor on the rotary table under the integrating sphere's port.
// A default-constructed Rig is the seed paper's indoor rig (rigs/wang2019-indoor.yaml).
#include <cstdint>
#include <memory>
#include <string>

#include "polrig/device/electronics.h"
#include "polrig/device/sensor.h"
#include "polrig/geometry/geometry.h"
#include "polrig/geometry/schedule.h"
#include "polrig/source/cos4.h"
#include "polrig/source/traced_source.h"

namespace polrig {

struct SourceSpec {
  std::string model = "cos4";  // "cos4" (analytic) or "traced" (Embree, from `scene`)
  Cos4Source cos4;             // L_o (both models), E_0 (cos4)
  double polarizer_deg = 0.0;  // port polarizer axis in the rig frame (cos4)
  std::string scene;           // traced: the scene file, an absolute path once loaded
  // traced: the source itself, shared by copies of the rig (sweeps); made when the rig loads,
  // its sphere solved on first use.
  std::shared_ptr<const TracedSource> traced;
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
