#pragma once
// What a sweep writes into its folder (docs/formats.md §6.3): sweep.h5 always, sweep.csv when
// asked, both streamed a block at a time, and plots drawn from small binned data files; and the
// one function `polrig sweep` and Python's Rig.sweep(out=...) both run, resumable.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "polrig/io/csv.h"
#include "polrig/io/manifest.h"
#include "polrig/fnv.h"
#include "polrig/io/sweep_h5.h"
#include "polrig/progress.h"
#include "polrig/ranks.h"
#include "polrig/study/sweep.h"

namespace polrig {

// sweep.h5's datasets and attributes for this grid; `eq6`: the rig's source has Eq. 6 in
// closed form (else the eq6 columns are NaN).
SweepH5Layout sweep_h5_layout(const std::vector<GridAxis>& axes, bool eq6,
                              std::vector<std::pair<std::string, std::string>> attributes);

// Writes a sweep's files as it runs (a SweepSink): memory does not grow with the grid.
class SweepReport {
 public:
  struct Resume {
    std::size_t points_done = 0;
    std::uint64_t csv_bytes = 0;
    std::string h5_fingerprint, csv_fingerprint;  // SweepState's
  };
  // Creates sweep.h5 (and sweep.csv with `csv`) in `dir`; with `resume`, continues the files of
  // an interrupted run after its last checkpoint, once the files are checked against it (a
  // sweep.h5 or sweep.csv of another checkpoint, or a record changed by hand, is refused:
  // std::runtime_error naming the file).
  SweepReport(const std::filesystem::path& dir, std::vector<GridAxis> axes, bool eq6, bool csv,
              const std::vector<std::pair<std::string, std::string>>& attributes,
              std::optional<Resume> resume = std::nullopt);
  void write(std::size_t first, std::span<const CsSummary> block);
  // Makes everything written durable; returns the checkpoint (points written, CSV length and
  // the files' fingerprints).
  Resume sync();
  // The plots' titles name these (the rig's values held fixed: "eccentricity.alpha_S = 240 deg").
  void set_fixed_keys(std::string text) { fixed_ = std::move(text); }
  // Closes the files and draws the plots (one or two axes) from sweep.h5.
  std::vector<DatasetFile> finish(bool plots);

 private:
  std::filesystem::path dir_;
  std::vector<GridAxis> axes_;
  std::string fixed_;
  SweepH5Layout layout_;
  std::optional<SweepH5Writer> h5_;
  std::optional<CsvTable> table_;
  std::unique_ptr<TextFileWriter> csv_;
  std::vector<double> columns_;  // one block, column after column
  std::size_t points_ = 0;
  // 64-bit FNV-1a of the values written to sweep.h5 (point after point, each point's columns in
  // order) and of the bytes written to sweep.csv.
  FnvWords h5_hash_, csv_hash_;  // the files' fingerprints so far (polrig/fnv.h)
  std::vector<std::string> csv_parts_;  // sweep.csv's lines of a block, formatted in parallel chunks
  std::vector<std::vector<std::string>> csv_axis_text_;  // each axis value as sweep.csv writes it

  void check_resume(const Resume& resume, bool csv);
};

struct SweepFolder {
  std::filesystem::path out;
  bool force = false;   // replace `out`; without `resume`, also discard an interrupted run
  bool csv = false;     // also write sweep.csv
  bool plots = true;
  bool resume = false;  // continue the interrupted run of the same sweep into `out`
  std::string command;  // the manifest's (a resumed run keeps its first's)
  std::string argument; // how the user named `out` ("-o/--out OUT", "out=OUT"): folder errors start with it
  // The processes sharing the sweep (MPI; null: this one alone). Rank 0 opens, writes and
  // commits the folder; the others compute their blocks and return an empty path.
  const Ranks* ranks = nullptr;
};

// The whole `polrig sweep`: opens the folder (resumable staging), runs the sweep into
// SweepReport with a durable checkpoint after the first block and then at most every second,
// writes the manifest and moves the folder into place. A resumed run refuses other inputs
// (rig, grid, steps, files asked for, program version), naming them. Returns the destination.
// Collective when `folder.ranks` has several: an error opening the folder stops every rank.
std::filesystem::path sweep_to_folder(const LoadedRig& rig, const std::vector<GridAxis>& axes,
                                      int steps, const SweepFolder& folder, const Progress& progress);

}  // namespace polrig
