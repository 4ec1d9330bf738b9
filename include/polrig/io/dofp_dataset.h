#pragma once
// Reads a DoFP camera dataset (report/dofp_dataset.h writes it; docs/formats.md): the stops, the
// per-pixel truth, the intrinsics and, per stop, its frames. For `calibrate --method dofp` and
// `orient`.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "polrig/device/dofp_camera.h"

namespace polrig {

struct DofpDatasetStop {
  int stop = 0;
  double theta_R_deg = 0;
  double t_s = 0;
  std::string utc;                     // empty for a source without a clock (the sphere rig)
  double intensity = 1;
  bool polarized = true;
  std::optional<double> heading_deg;   // true heading of X_l (sky rigs), else none
  int frames = 1;
  std::string file;                    // relative to the dataset folder
};

struct DofpDataset {
  std::filesystem::path dir;
  int width = 0, height = 0;
  double f_c_px = 0;            // focal length in pixels
  int adc_bits = 0;             // the ADC's depth (truth.exr's adc_bits), 0 when not recorded
  double cx = 0, cy = 0;        // principal point (width/2, height/2); pixel (col, row)'s centre
                                // is at (col + 0.5, row + 0.5)
  DofpTruth truth;              // from truth.exr
  std::vector<DofpDatasetStop> stops;
};

// Throws std::runtime_error naming the file (and the line and column of stops.csv) for a
// missing or malformed file.
DofpDataset read_dofp_dataset(const std::filesystem::path& dir);

// The mean frame of a stop (DN, row-major, top row first): the mean of its frames, or raw_sum /
// frames. Throws naming the file.
std::vector<double> read_dofp_mean_frame(const DofpDataset& dataset, std::size_t stop_index);
// Every frame of a stop (a dataset written with every frame; throws for a sum-only one).
std::vector<std::vector<std::uint16_t>> read_dofp_frames(const DofpDataset& dataset, std::size_t stop_index);

// A calibration's per-pixel parameters (`polrig calibrate --method dofp`'s params.exr: channels K,
// b, k, eps_deg, as float) for the dataset's camera; alpha_deg is the dataset's mosaic. Throws
// std::runtime_error naming the file for a missing channel or another image size.
DofpTruth read_dofp_parameters(const std::filesystem::path& params_exr, const DofpDataset& dataset);

}  // namespace polrig
