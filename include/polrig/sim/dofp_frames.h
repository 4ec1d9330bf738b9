#pragma once
// The DoFP camera's frames over a rig's schedule (spec sky-and-compasses.md §2.3–2.5): per pixel
// its view, the light along it (Source::light_along_views), the E-vector's angle in the image,
// Eq. 18 with the pixel's truth, Poisson–Gaussian noise and the ADC. docs/physics.md §13.
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "polrig/device/dofp_camera.h"
#include "polrig/progress.h"
#include "polrig/rig/rig.h"

namespace polrig {

// One stop of a camera's schedule (geometry/schedule.h): first one per unpolarized level (the
// port polarizer out: d = 0; the table at start_deg), then every table angle at each polarized
// intensity, intensity-major. The stops' times: t_0 = 0, t_k = t_{k−1} + |θ_k − θ_{k−1}|/speed +
// dwell (Schedule::stop_times_s's rule over this sequence; the same times for a schedule without
// unpolarized levels and with one intensity).
struct DofpStop {
  int index = 0;
  bool polarized = true;
  double intensity = 1;   // relative to the source's own level
  double theta_R_deg = 0;
  double t_s = 0;
  int frames = 1;
};
std::vector<DofpStop> dofp_stops(const Schedule& schedule);

// What every camera simulator (DofpSimulator, FourCameraSimulator) needs of its rig's light: a
// source with light along views (Source::kStokesAlongViews), and no unpolarized levels under the
// sky. Throws std::invalid_argument naming the key.
void check_camera_light(const Rig& rig);

// How a pixel's AoP φ_pix (image frame, from X_l) follows from the E-vector e along its view v.
enum class DofpAnalyzer {
  // Spec §2.5: the analyzer in the image plane, a lens that keeps the meridional frame:
  // φ_pix = φ + α, φ the E-vector's angle in frame i (X_i the direction of increasing zenith
  // angle of the view, Y_i = Rz(α)·ŷ), α the view's azimuth (Eq. 9).
  ImagePlane,
  // Spec §2.5's alternative: the analyzer in front of the lens; φ_pix is the angle in the image
  // of the axis (cos φ_pix, sin φ_pix, 0) whose projection ⊥ v is along e.
  InFront,
};

// The truth of one frame, per pixel in the image frame (reference axis X_l), float, row-major:
// S0 = I (the intensity reaching the pixel), S1 = I·d·cos 2φ_pix, S2 = I·d·sin 2φ_pix,
// AoP = φ_pix in degrees [0°, 180°), DoP = d.
struct DofpTruthLayers {
  std::vector<float> S0, S1, S2, AoP, DoP;
};

// A camera rig's simulator: the pixel views and the truth, made once; frames on request.
class DofpSimulator {
 public:
  // Throws std::invalid_argument when the rig's instrument has no frames, its source gives no light
  // along views (kStokesAlongViews), or a sky source has unpolarized stops.
  explicit DofpSimulator(const Rig& rig, DofpAnalyzer analyzer = DofpAnalyzer::ImagePlane);
  const DofpTruth& truth() const { return truth_; }
  const std::vector<DofpStop>& stops() const { return stops_; }
  int width() const { return truth_.width; }
  int height() const { return truth_.height; }

  // The raw DN of frame `frame` at `stop` (row-major, top row first), its noise a pure function
  // of (rig seed, stop, frame, pixel): bit-identical for any number of threads (TBB over rows).
  // With `layers`, the frame's truth too. The same as frame(signal(stop, layers), frame).
  std::vector<std::uint16_t> frame(const DofpStop& stop, int frame, DofpTruthLayers* layers = nullptr) const;

  // What does not change between a stop's frames: the light along the views and Eq. 18 without
  // noise, f (DN) per pixel. Made once per stop; its frames then cost only the noise and the ADC.
  struct StopSignal {
    DofpStop stop;
    std::vector<double> f;
  };
  StopSignal signal(const DofpStop& stop, DofpTruthLayers* layers = nullptr) const;
  // Frame `frame` of the signal's stop: Poisson–Gaussian noise and the ADC on f.
  std::vector<std::uint16_t> frame(const StopSignal& signal, int frame) const;

 private:
  Rig rig_;
  DofpAnalyzer analyzer_;
  DofpTruth truth_;
  std::vector<DofpStop> stops_;
  // Per pixel, what the hot loop reads (32 bytes, half the former view + factors: memory traffic counts): 1/|a| of
  // a = (x_col, y_row, f_c), the unnormalised view (pixel_view: v = a·(1/|a|), bit for bit; the
  // constructor checks), and Eq. 18's factors A = K/2, B = (K/2)·k·cos 2(α − ε),
  // C = (K/2)·k·sin 2(α − ε): f = I·(A + d·(B·cos 2φ + C·sin 2φ)) + b (b from truth_).
  struct PixelConstants {
    double inv, A, B, C;
  };
  std::vector<double> view_x_, view_y_;  // x_col per column, y_row per row
  double view_f_ = 0;                    // f_c
  std::vector<PixelConstants> pixels_;
  // Eq. 18 without noise, row by row (TBB over rows): row_done(first pixel, the row's f) per row.
  void signal_rows(const DofpStop& stop, DofpTruthLayers* layers,
                   const std::function<void(std::size_t, std::span<const double>)>& row_done) const;
  std::uint64_t noise_seed_ = 0;
};

// The true heading of a camera's X_l at a stop under a sky rig: the geographic azimuth (from north
// towards east) of X_l's horizontal part, [0°, 360°); none for a source without a sky.
std::optional<double> dofp_true_heading_deg(const Rig& rig, const DofpStop& stop);

}  // namespace polrig
