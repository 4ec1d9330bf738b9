// make_instrument: the only place that names the instrument kinds (as source/factory.cpp the
// source models).
#include <array>
#include <stdexcept>
#include <string>

#include "polrig/instrument/instrument.h"

namespace polrig {

namespace {

// W19's six-photodiode sensor: its physics is device/sensor.h, its chain sim/simulate.h.
class SixPhotodiode final : public Instrument {
 public:
  std::string_view kind() const override { return "six-photodiode"; }
  unsigned flags() const override { return kPairVoltages; }
};

// H17's DoFP camera: device/dofp_camera.h.
class DofpCamera final : public Instrument {
 public:
  std::string_view kind() const override { return "dofp-camera"; }
  unsigned flags() const override { return kFrames | kMosaic; }
};

// W16's four-camera sensor: device/four_camera.h, sim/four_camera_frames.h.
class FourCamera final : public Instrument {
 public:
  std::string_view kind() const override { return "four-camera"; }
  unsigned flags() const override { return kFrames | kCameraArray; }
};

// Z21's unit-array compass: device/unit_array.h, calib/unit_array.h, compass/unit_array.h.
class UnitArray final : public Instrument {
 public:
  std::string_view kind() const override { return "unit-array"; }
  unsigned flags() const override { return kUnitArray; }
};

constexpr std::array<std::string_view, 4> kInstrumentKinds = {"six-photodiode", "dofp-camera", "four-camera", "unit-array"};

constexpr std::array<InstrumentFlagInfo, 5> kFlags = {{
    {Instrument::kPairVoltages, "pair_voltages", "pair voltages"},
    {Instrument::kFrames, "frames", "frames"},
    {Instrument::kMosaic, "mosaic", "a polarizer mosaic"},
    {Instrument::kCameraArray, "camera_array", "a camera array"},
    {Instrument::kUnitArray, "unit_array", "a unit array"},
}};

}  // namespace

std::span<const std::string_view> instrument_kinds() { return kInstrumentKinds; }

std::span<const InstrumentFlagInfo> instrument_flags() { return kFlags; }

std::string kinds_with(Instrument::Flag flag) {
  std::string out;
  for (std::string_view kind : kInstrumentKinds)
    if (make_instrument(kind)->has(flag)) {
      if (!out.empty()) out += ' ';
      out += kind;
    }
  return out;
}

std::shared_ptr<const Instrument> six_photodiode_instrument() {
  static const auto instrument = std::make_shared<const SixPhotodiode>();
  return instrument;
}

std::shared_ptr<const Instrument> make_instrument(std::string_view kind) {
  if (kind == "six-photodiode") return six_photodiode_instrument();
  if (kind == "dofp-camera") {
    static const auto camera = std::make_shared<const DofpCamera>();
    return camera;
  }
  if (kind == "four-camera") {
    static const auto cameras = std::make_shared<const FourCamera>();
    return cameras;
  }
  if (kind == "unit-array") {
    static const auto units = std::make_shared<const UnitArray>();
    return units;
  }
  throw std::invalid_argument("unknown instrument '" + std::string(kind) + "'");
}

}  // namespace polrig
