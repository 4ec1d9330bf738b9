#pragma once
// The progress record of a resumable sweep (docs/formats.md), kept in its staging folder and
// rewritten after each checkpoint: how many points are on disk, the CSV's length then, the
// original command, and the inputs that determine the output, to refuse resuming with others.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace polrig {

inline constexpr const char* kSweepStateFile = "resume-state.yaml";

struct SweepState {
  std::size_t points_done = 0;   // points [0, points_done) are written and synced
  std::uint64_t csv_bytes = 0;   // sweep.csv's length then (0 without --csv)
  std::string command, working_directory;  // the original run's, for its manifest
  std::vector<std::pair<std::string, std::string>> inputs;  // name, value
  // Fingerprints of what the files held then, checked before resuming: sweep.h5's values of
  // points [0, points_done) and sweep.csv's first csv_bytes bytes ("" without --csv).
  std::string h5_fingerprint, csv_fingerprint;
};

// Null when `dir` holds no record. Throws std::runtime_error naming the file if it is unreadable.
std::optional<SweepState> read_sweep_state(const std::filesystem::path& dir);
// Atomic and durable: written to a temporary file, synced, renamed over the record, and the
// folder synced. Throws std::runtime_error naming the file.
void write_sweep_state(const std::filesystem::path& dir, const SweepState& state);
// The names of the inputs whose values differ between a record and this run, in `now`'s order
// (a name missing on either side counts).
std::vector<std::string> differing_inputs(const SweepState& saved,
                                          const std::vector<std::pair<std::string, std::string>>& now);
// fsync of a file or folder; throws std::runtime_error naming it.
void sync_to_disk(const std::filesystem::path& path);

}  // namespace polrig
