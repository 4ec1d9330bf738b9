#pragma once
// The DoFP camera's dataset (docs/formats.md "Camera dataset"): what `polrig simulate` writes for
// a rig whose instrument takes frames (Instrument::kFrames), and Python's Rig.simulate_dofp.
//   DIR/frames/stop_NNNN.exr  the stop's raw DN (UINT channels, ZIP: lossless) and, on request,
//                             its truth layers S0, S1, S2, AoP, DoP (float); header attributes
//   DIR/truth.exr             per-pixel K, b, k, eps_deg, alpha_deg (float); the intrinsics
//   DIR/stops.csv             one row per stop
//   DIR/previews/             with DofpDatasetOptions::previews: the first and last stops' AoP, DoP
//                             and S0 (report/dataset_previews.h)
//   DIR/manifest.yaml, DIR/rig.yaml
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "polrig/io/manifest.h"
#include "polrig/progress.h"
#include "polrig/sim/dofp_frames.h"

namespace polrig {

// What a stop's raw channels hold.
enum class DofpFrameStorage {
  Every,  // every frame: channels raw.000, raw.001, … (DN)
  Sum,    // the per-stop mean, stored exactly as the sum of the frames' DN in one channel raw_sum
          // (the mean is raw_sum / frames; a float mean would round)
};

struct DofpDatasetOptions {
  DofpFrameStorage storage = DofpFrameStorage::Every;
  bool truth_layers = false;  // S0, S1, S2, AoP, DoP in every stop's EXR
  DofpAnalyzer analyzer = DofpAnalyzer::ImagePlane;
  // The first and the last stop's AoP, DoP and S0 as PNGs in DIR/previews/ (gnuplot): each 2 × 2
  // cell's polarization (calib/dofp_polarization.h, the nominal parameters) in the stop's mean frame.
  bool previews = false;
};

// Writes the dataset's files but the manifest into `dir` (an existing, empty staging folder),
// reporting "simulate: frames" to `progress`; returns the files for the manifest. Throws
// std::invalid_argument for a rig DofpSimulator refuses (before anything is written).
std::vector<DatasetFile> report_dofp_dataset(const std::filesystem::path& dir, const Rig& rig,
                                             const DofpDatasetOptions& options, const Progress& progress = {});

// The whole dataset in a new folder `destination` (io/output_dir: whole or not at all; an
// existing folder is replaced only with `replace`), with its manifest naming `command`.
void write_dofp_dataset(const LoadedRig& rig, const std::filesystem::path& destination,
                        const DofpDatasetOptions& options, const std::string& command, bool replace,
                        const Progress& progress = {});

}  // namespace polrig
