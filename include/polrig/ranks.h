#pragma once
// The processes of one run: this process alone, or the ranks of an MPI job (built with
// -DPOLRIG_MPI=ON and started by mpirun or srun; docs/scale.md). Work is split into shards by
// index alone, each result is a pure function of its index, and rank 0 writes everything in
// index order, so a run's results do not depend on size().
#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace polrig {

class Ranks {
 public:
  virtual ~Ranks() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  bool is_root() const { return rank() == 0; }

  // Collective: every rank passes its bytes; rank 0 receives every rank's bytes concatenated in
  // rank order, the other ranks an empty vector.
  virtual std::vector<std::byte> gather(std::span<const std::byte> mine) const = 0;
  // Collective: rank 0's `bytes` replace every other rank's.
  virtual void broadcast(std::vector<std::byte>& bytes) const = 0;
  // Collective: every rank says whether it failed; every rank receives the message of the
  // lowest failing rank, or nothing when none failed.
  virtual std::optional<std::string> first_failure(const std::optional<std::string>& mine) const = 0;
};

// The run of this process alone: rank 0 of 1, every collective a copy.
const Ranks& this_process_only();

}  // namespace polrig
