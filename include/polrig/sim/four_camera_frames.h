#pragma once
// The four-camera sensor's frames over a rig's schedule (spec sky-and-compasses.md §3.1–3.2,
// docs/physics.md §16): per camera and pixel its view through its lens and R_j1 into the rig
// frame, the light along it (Source::light_along_views, as the DoFP camera), the E-vector's
// image-plane angle φ in camera j's frame, Eq. 1 with the camera's K_j, b_j, φ_j + ε_j, then
// Poisson–Gaussian noise and the ADC (DofpExposure). The fused image follows by
// device/four_camera.h's FourCameraFusion.
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "polrig/device/four_camera.h"
#include "polrig/rig/rig.h"
#include "polrig/sim/dofp_frames.h"

namespace polrig {

// One stop's noise-free signal: f_j (DN) per camera, row-major, top row first.
struct FourCameraSignal {
  DofpStop stop;
  std::array<std::vector<double>, kFourCameras> f;
};

// What the sky (or the port) gives along the virtual camera 1's views (its undistorted pinhole
// grid; compass/orientation.h's camera), double, row-major: S0, S1 = S0·d·cos 2φ, S2 = S0·d·sin 2φ,
// AoP φ in [0°, 180°) from camera 1's X towards Y (the image-plane angle), DoP d.
struct FourCameraTruthLayers {
  std::vector<double> S0, S1, S2, AoP, DoP;
};

class FourCameraSimulator {
 public:
  // Throws std::invalid_argument when the rig's instrument is not a camera array
  // (Instrument::kCameraArray), its source gives no light along views, a sky source has
  // unpolarized stops, or the spec's geometry cannot be simulated (four_camera_truth).
  explicit FourCameraSimulator(const Rig& rig);
  const FourCameraModel& truth() const { return truth_; }
  const std::vector<DofpStop>& stops() const { return stops_; }
  const FourCameraFusion& fusion() const { return *fusion_; }
  int width() const { return truth_.width; }
  int height() const { return truth_.height; }

  // Eq. 1 without noise at the stop, every camera (TBB over rows).
  FourCameraSignal signal(const DofpStop& stop) const;
  // Frame `frame` of every camera: noise (seed, stop, 4·frame + j, pixel) and the ADC;
  // bit-identical for any number of threads.
  std::array<std::vector<std::uint16_t>, kFourCameras> frames(const FourCameraSignal& signal, int frame = 0) const;
  // The fused image of frames (raw DN) or of a noise-free signal.
  FusedImage fuse(const std::array<std::vector<std::uint16_t>, kFourCameras>& raw) const;
  FusedImage fuse(const FourCameraSignal& signal) const;
  // The light along the virtual camera 1's views at the stop (the truth the fused image estimates).
  FourCameraTruthLayers truth_on_grid(const DofpStop& stop) const;
  // The sun in camera 1's frame at the stop (unit; sky rigs), else none.
  std::optional<Vec3> sun_in_camera1(const DofpStop& stop) const;

 private:
  Rig rig_;
  FourCameraModel truth_;
  std::vector<DofpStop> stops_;
  std::shared_ptr<const FourCameraFusion> fusion_;
  // Per camera and pixel: the view v_j in camera j's frame.
  std::array<std::vector<Vec3>, kFourCameras> views_;
  std::uint64_t noise_seed_ = 0;
};

}  // namespace polrig
