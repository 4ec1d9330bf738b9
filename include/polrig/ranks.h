#pragma once
// The processes of one run: this process alone, or the ranks of an MPI job (built with
// -DPOLRIG_MPI=ON and started by mpirun or srun; docs/scale.md). Work is split into shards by
// index alone, each result is a pure function of its index, and rank 0 writes everything in
// index order, so a run's results do not depend on size().
#include <cstddef>
#include <memory>
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

// How the environment says this process was started: by an MPI launcher (OpenMPI's mpirun sets
// OMPI_COMM_WORLD_SIZE, PMIx launchers such as `srun --mpi=pmix` set PMIX_RANK, MPICH's and
// `srun --mpi=pmi2` set PMI_RANK/PMI_SIZE), as which rank of how many processes (0: unknown).
struct Launch {
  bool by_mpi_launcher = false;
  int rank = 0;
  int processes = 1;
};
Launch launch_from_environment();

// True when polrig was built with -DPOLRIG_MPI=ON.
bool built_with_mpi();

// The MPI job this process was started in: MPI is initialised here (MPI_Init_thread, FUNNELED:
// only the calling thread uses MPI, TBB's workers never do) and finalized when the returned
// Ranks is destroyed. Null when no MPI launcher started this process (a plain `polrig …` pays
// no MPI start-up), and in a build without MPI started as one process. Throws
// std::runtime_error when a build without MPI was started as one of several processes (each
// would run the whole command alone).
std::unique_ptr<Ranks> join_mpi_job(int& argc, char**& argv);

}  // namespace polrig
