#pragma once
// The four-camera sensor's dataset (docs/formats.md "Four-camera dataset"): what `polrig simulate`
// writes for a rig whose instrument is a camera array (Instrument::kCameraArray), and Python's
// Rig.simulate_four_camera.
//   DIR/frames/stop_NNNN.exr  per stop: each camera's raw DN (UINT channels cam1 … cam4, ZIP:
//                             lossless), the fused S0, S1, S2, AoP, DoP (float) on the virtual
//                             camera 1 grid and `valid` (UINT 0/1); header attributes
//   DIR/truth.yaml            the cameras' truth (gains, offsets, polarizer axes and errors,
//                             intrinsics, distortion, R_j1, positions) and the virtual camera
//   DIR/stops.csv             one row per stop: time, table angle, true heading, the sun in camera 1
//   DIR/previews/             with FourCameraDatasetOptions::previews: the first and last stops'
//                             fused AoP, DoP and S0 (report/dataset_previews.h)
//   DIR/manifest.yaml, DIR/rig.yaml
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "polrig/io/manifest.h"
#include "polrig/progress.h"
#include "polrig/sim/four_camera_frames.h"

namespace polrig {

// Which layers each stop's EXR holds.
enum class FourCameraLayers {
  All,    // the four raw frames and the fused layers
  Fused,  // the fused S0, S1, S2, AoP, DoP and valid
  Aop,    // the fused AoP, DoP and valid (what `locate` reads)
};
std::string_view four_camera_layers_name(FourCameraLayers layers);  // "all", "fused", "aop"
std::optional<FourCameraLayers> parse_four_camera_layers(std::string_view name);
// The layers a rig's dataset holds unless told (the CLI's and Python's default): All for a
// calibration's dataset (unpolarized levels or checkerboard views: `calibrate --method
// four-camera` reads the raw frames), else Aop (what `locate` reads).
FourCameraLayers default_four_camera_layers(const Rig& rig);

struct FourCameraDatasetOptions {
  // At W16's size a stop is 6.2 MB and ≈ 0.5 core-seconds with Aop, 15.4 MB and ≈ 0.75 with the
  // fused Stokes layers, 21 MB with the raw frames (docs/cli.md, "simulate");
  // default_four_camera_layers is the rig's choice.
  FourCameraLayers layers = FourCameraLayers::Aop;
  // The first and the last stop's fused AoP, DoP and S0 as PNGs in DIR/previews/ (gnuplot;
  // report/dataset_previews.h), whichever layers the EXRs keep.
  bool previews = false;
};

// The truth as YAML text (truth.yaml).
std::string four_camera_truth_yaml(const FourCameraSpec& spec, const FourCameraModel& truth,
                                   const VirtualCamera& grid);

// Writes the dataset's files but the manifest into `dir` (an existing, empty staging folder),
// reporting "simulate: stops" to `progress`; returns the files for the manifest. Throws
// std::invalid_argument for a rig FourCameraSimulator refuses (before anything is written).
std::vector<DatasetFile> report_four_camera_dataset(const std::filesystem::path& dir, const Rig& rig,
                                                    const FourCameraDatasetOptions& options,
                                                    const Progress& progress = {});

// The whole dataset in a new folder `destination` (whole or not at all; an existing folder is
// replaced only with `replace`), with its manifest naming `command`.
void write_four_camera_dataset(const LoadedRig& rig, const std::filesystem::path& destination,
                               const FourCameraDatasetOptions& options, const std::string& command, bool replace,
                               const Progress& progress = {});

}  // namespace polrig
