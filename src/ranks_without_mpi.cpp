// The ranks of a build without MPI (-DPOLRIG_MPI=OFF): this process alone.
#include <stdexcept>
#include <string>

#include "polrig/ranks.h"

namespace polrig {

bool built_with_mpi() { return false; }

std::unique_ptr<Ranks> join_mpi_job(int&, char**&) {
  const Launch launch = launch_from_environment();
  if (launch.by_mpi_launcher && (launch.processes != 1 || launch.rank != 0))
    throw std::runtime_error(
        "started by an MPI launcher as one of " +
        (launch.processes > 0 ? std::to_string(launch.processes) : std::string("several")) +
        " processes, but this polrig was built without MPI: every process would run the whole "
        "command alone. Build with -DPOLRIG_MPI=ON (docs/scale.md), or run polrig without mpirun/srun");
  return nullptr;
}

}  // namespace polrig
