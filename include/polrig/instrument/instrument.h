#pragma once
// The one seam between a rig and what measures its light, beside the source seam
// (source/source.h): a rig is a source, a mount (table, eccentricity, tilt, time) and an
// instrument. As pbrt-v4 separates cameras from lights and integrators, the simulation, the
// studies, calibrate, the manifests and the Python module reach an instrument through this
// interface, ask what it can do (flags()) and never which kind it is. make_instrument
// (instrument/factory.cpp) is the only place that names the kinds.
#include <memory>
#include <span>
#include <string>
#include <string_view>

namespace polrig {

class Instrument {
 public:
  enum Flag : unsigned {
    // Three log-amplifier pair voltages per stop (W19's six-photodiode sensor): simulate's
    // Simulation, the CS study and sweeps, study adc, calibrate's Eq. 15 methods.
    kPairVoltages = 1u << 0,
    // A pixel array: frames of raw DN per stop (H17's DoFP camera): simulate writes frames,
    // calibrate --method dofp, orient.
    kFrames = 1u << 1,
    // A polarizer mosaic on one sensor (H17's DoFP camera): the 2 × 2 cells that calibrate
    // --method dofp and orient read. A camera array has frames but no mosaic.
    kMosaic = 1u << 2,
    // Several cameras, one polarizer each, co-registered into one Stokes image (W16's four-camera
    // sensor, device/four_camera.h).
    kCameraArray = 1u << 3,
    // Several six-photodiode units, each looking along its own axis and reporting an AoP and a
    // DoP in its own frame (Z21's nine-unit compass, device/unit_array.h, calib/unit_array.h): the
    // sun vector from two units (compass/unit_array.h). No pair voltages of one turntable sensor.
    kUnitArray = 1u << 4,
  };

  virtual ~Instrument() = default;
  // The kind, as the rig key device.kind names it (for manifests and messages, never to branch on).
  virtual std::string_view kind() const = 0;
  virtual unsigned flags() const = 0;
  bool has(Flag f) const { return (flags() & f) != 0; }
};

// The instrument of `kind` (device.kind): "six-photodiode" (the default), "dofp-camera",
// "four-camera" or "unit-array".
// Throws std::invalid_argument for another kind.
std::shared_ptr<const Instrument> make_instrument(std::string_view kind);
// The kinds make_instrument knows, for the device.kind key's check and its documentation.
std::span<const std::string_view> instrument_kinds();
// The six-photodiode sensor (shared; it holds nothing): a default Rig's.
std::shared_ptr<const Instrument> six_photodiode_instrument();

// Every flag, with its name (an identifier: Python's Rig.can("frames")) and what it gives, as
// messages say it ("pair voltages").
struct InstrumentFlagInfo {
  Instrument::Flag flag;
  std::string_view name;
  std::string_view text;
};
std::span<const InstrumentFlagInfo> instrument_flags();
// The kinds that have `flag`, space-separated ("six-photodiode"), for messages.
std::string kinds_with(Instrument::Flag flag);

}  // namespace polrig
