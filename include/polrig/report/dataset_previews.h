#pragma once
// The preview PNGs of a camera dataset (issue 23 §4): the AoP, DoP and S0 of a stop, each a PNG
// drawn by gnuplot from a CSV beside it whose columns the plots read by name. The DoFP camera's
// dataset previews its cells' polarization (report/dofp_dataset.h), the four cameras' dataset its
// fused image (report/four_camera_dataset.h).
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "polrig/io/manifest.h"

namespace polrig {

// One stop's layers on a regular grid of `cols` × `rows` samples (row-major, top row first): a
// sample (i, j) covers `pixels` × `pixels` image pixels whose top-left pixel is (i, j)·pixels (2
// for a DoFP cell, 1 for a fused pixel). aop_deg in [0°, 180°); NaN (or valid = 0) where the
// sample measures none: drawn as the background.
struct PreviewStop {
  std::string stem;    // "stop_0000": the files previews/stop_0000.csv, previews/stop_0000_aop.png, …
  std::string title;   // the stop, its table angle and time, as the plots' titles say it
  int cols = 0, rows = 0, pixels = 1;
  std::vector<double> aop_deg, dop, S0;
  std::vector<std::uint8_t> valid;  // empty: every sample valid
};

// What a camera dataset's writer collects of each stop, in stop order (side_by_side.h): its
// stops.csv row and, for the stops previewed, its layers.
struct DatasetStopRow {
  std::string csv;
  std::optional<PreviewStop> preview;
};

struct PreviewOptions {
  std::string grid_columns[2] = {"col", "row"};  // the CSV's names of the sample's indices
  std::string grid_text;                         // "cell" or "pixel", in the descriptions
  std::string s0_label;                          // the S0 colour bar's label (its unit)
  std::string frame_text;                        // the AoP's reference, for its colour bar
  int max_samples = 320;                         // samples across at most: every ceil(cols/320)-th
};

// Writes DIR/previews/ (created): per stop STEM.csv (columns x_px, y_px: the sample's centre in
// image pixels, the top-left pixel's corner at 0; the indices; aop_deg, dop, S0; only every
// ceil(cols / max_samples)-th sample in each direction, nearest, so that AoP is never averaged
// across its 0/180 seam), STEM_aop.png (a cyclic palette), STEM_dop.png (0 to 1), STEM_s0.png, and
// previews.gp, their gnuplot script; returns the files for the manifest.
std::vector<DatasetFile> report_stop_previews(const std::filesystem::path& dir, const std::vector<PreviewStop>& stops,
                                              const PreviewOptions& options);

}  // namespace polrig
