#pragma once
// Reads a DoFP camera dataset (report/dofp_dataset.h writes it; docs/formats.md §6.14): the stops,
// the intrinsics and mosaic, the per-pixel truth when there is one and, per stop, its frames. For
// `calibrate --method dofp` and `orient`.
#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "polrig/device/dofp_camera.h"

namespace polrig {

// The most frames a stop may have: their raw_sum of 16-bit DN fits 32 bits.
inline constexpr int kMaxFramesPerStop = 65536;

struct DofpDatasetStop {
  int stop = 0;
  double theta_R_deg = 0;
  double t_s = 0;
  std::string utc;                     // empty for a source without a clock (the sphere rig)
  double intensity = 1;
  bool polarized = true;
  std::optional<double> heading_deg;   // true heading of X_l (sky rigs), else none
  int frames = 1;  // in [1, kMaxFramesPerStop]
  std::string file;                    // relative to the dataset folder
};

// A simulated dataset's camera comes from its truth.exr; a measured one (a researcher's own
// frames, no truth.exr) gives it in rig.yaml's device keys, read by the rig reader.
struct DofpDataset {
  std::filesystem::path dir;
  int width = 0, height = 0;
  double f_c_px = 0;            // focal length in pixels
  int adc_bits = 0;             // the ADC's depth (truth.exr's or rig.yaml's adc_bits), 0 when not recorded
  double cx = 0, cy = 0;        // principal point (width/2, height/2); pixel (col, row)'s centre
                                // is at (col + 0.5, row + 0.5)
  std::array<double, 4> mosaic_deg{};  // analyzer axes of a cell's TL, TR, BL, BR (image frame)
  std::optional<DofpTruth> truth;      // truth.exr; none for a measured dataset
  std::vector<DofpDatasetStop> stops;
};

// Reads DIR/stops.csv and the camera: from DIR/truth.exr when it exists, else from DIR/rig.yaml,
// which must then be a camera rig (device.kind dofp-camera) that gives device.width_px,
// height_px, pixel_um, focal_mm and mosaic_deg itself (a default is not the researcher's camera;
// device.adc_bits is used when given). Throws std::runtime_error (RigError for rig.yaml) naming
// the file (and the line and column of stops.csv, or the key) for a missing or malformed file.
DofpDataset read_dofp_dataset(const std::filesystem::path& dir);

// The mean frame of a stop (DN, row-major, top row first): the mean of its frames, or raw_sum /
// frames. Throws naming the file. These readers decompress on the calling thread
// (ExrThreads::ThisThread): read several stops side by side (side_by_side.h) to use more cores.
std::vector<double> read_dofp_mean_frame(const DofpDataset& dataset, std::size_t stop_index);
// Rows [first_row, first_row + rows) of a stop's mean frame, the same values as those rows of
// read_dofp_mean_frame (only those rows are decompressed). Throws naming the file.
std::vector<double> read_dofp_mean_rows(const DofpDataset& dataset, std::size_t stop_index, int first_row, int rows);
// Every frame of a stop (a dataset written with every frame; throws for a sum-only one).
std::vector<std::vector<std::uint16_t>> read_dofp_frames(const DofpDataset& dataset, std::size_t stop_index);

// A calibration's per-pixel parameters (`polrig calibrate --method dofp`'s params.exr: channels K,
// b, k, eps_deg, as float) for the dataset's camera; alpha_deg is the dataset's mosaic_deg. Throws
// std::runtime_error naming the file for a missing channel or another image size.
DofpTruth read_dofp_parameters(const std::filesystem::path& params_exr, const DofpDataset& dataset);

}  // namespace polrig
