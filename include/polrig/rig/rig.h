#pragma once
// A calibration rig: the sensor on the rotary table under the integrating sphere's port.
// A default-constructed Rig is the seed paper's indoor rig (rigs/wang2019-indoor.yaml).
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "polrig/device/dofp_camera.h"
#include "polrig/device/electronics.h"
#include "polrig/device/four_camera.h"
#include "polrig/device/sensor.h"
#include "polrig/device/unit_array.h"
#include "polrig/geometry/checkerboard.h"
#include "polrig/geometry/geometry.h"
#include "polrig/geometry/schedule.h"
#include "polrig/instrument/instrument.h"
#include "polrig/rig/ins_settings.h"
#include "polrig/source/source.h"

namespace polrig {

struct Rig {
  // The instrument: device.kind names it, and instrument() is make_instrument's of that kind, so
  // the two cannot disagree (instruments hold no state; a rig built in code sets device_kind
  // only). Callers ask it what it can do (Instrument::flags), never which kind it is.
  std::string device_kind = "six-photodiode";
  // The six-photodiode sensor's settings (device.* keys), and device.d: the degree of linear
  // polarization of the light at the instrument, whichever it is.
  SensorSpec device;
  DofpCameraSpec camera;  // the DoFP camera's settings (device.* keys of device.kind dofp-camera)
  FourCameraSpec four_camera;  // W16's four cameras (device.* keys of device.kind four-camera)
  // Z21's unit-array compass (device.units.* keys of device.kind unit-array); each unit is a
  // six-photodiode sensor with `device`'s true parameters and the rig's `electronics`.
  UnitArraySpec units;
  // The unit array's vehicle, IMU and navigation filter (trajectory.*, imu.*, navigation.* keys).
  TrajectorySettings trajectory;
  ImuSettings imu;
  NavigationSettings navigation;
  CheckerboardSpec checkerboard;  // the four cameras' calibration target (checkerboard.* keys)
  SourceSpec source;  // the source.* keys' settings
  // The light, made by make_source from `source` when the rig loads (cos⁴ by default) and shared
  // by copies of the rig (sweeps): a traced sphere is solved once. Callers ask it what it can do
  // (Source::flags), never which model it is.
  std::shared_ptr<const Source> light = cos4_source();
  Eccentricity eccentricity;
  Schedule schedule;
  Electronics electronics;
  std::uint64_t seed = 20190806;

  // make_instrument(device_kind): throws std::invalid_argument for a kind it does not know (a
  // loaded rig's kind was checked when it loaded).
  const Instrument& instrument() const { return *make_instrument(device_kind); }

  // What the light reads of the rig at a pose.
  SourceView source_view() const { return {device, eccentricity, source}; }
};

// The sky of a rig whose light is a sky (source.model sky: its sky block resolved), else nothing.
std::optional<Sky> rig_sky(const Rig& rig);
// Why a rig without a sky cannot give one: "ORIGIN: source.model cos4 has no sky (expected
// source.model sky)" (`polrig sky RIG`, polrig.Sky.from_rig).
std::string no_sky_message(const Rig& rig, std::string_view origin);

// Why `what` (a command or study: "study cs") cannot run on the rig's instrument, or nothing when
// it can, asked of its flags (never its kind): "ORIGIN: study cs needs pair voltages (device.kind
// six-photodiode); device.kind dofp-camera has none" ("ORIGIN: " only with an origin). Commands
// and Python ask it with the rig's origin before anything is written; the library's studies ask
// it too, so every caller gets the same message.
std::optional<std::string> instrument_problem(const Rig& rig, Instrument::Flag needs,
                                              std::string_view what, std::string_view origin = {});
// Throws RigError with instrument_problem's message when there is one.
void require_instrument(const Rig& rig, Instrument::Flag needs, std::string_view what,
                        std::string_view origin = {});

}  // namespace polrig
