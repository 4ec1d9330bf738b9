# -DPOLRIG_MPI=ON: polrig runs as the ranks of an MPI job when started by mpirun or srun
# (docs/scale.md). Debian OpenMPI (libopenmpi-dev); only MPI's C API is used, found through the CXX component (no C compiler
# needed) without the removed C++ bindings. OFF: nothing MPI
# is compiled or linked, and the run is this process alone (src/ranks_without_mpi.cpp).
option(POLRIG_MPI "Build polrig for MPI jobs (mpirun, srun; docs/scale.md)" OFF)

if(POLRIG_MPI)
  set(MPI_CXX_SKIP_MPICXX ON CACHE BOOL "MPI's C API only")
  find_package(MPI REQUIRED COMPONENTS CXX)
  target_sources(polrig_lib PRIVATE src/ranks_mpi.cpp)
  target_link_libraries(polrig_lib PRIVATE MPI::MPI_CXX)
  # MPI_Init_thread's MPI_THREAD_FUNNELED: only the main thread calls MPI, TBB's workers never do.
  find_program(POLRIG_MPIEXEC NAMES mpirun mpiexec HINTS ${MPIEXEC_EXECUTABLE})
  if(NOT POLRIG_MPIEXEC)
    message(FATAL_ERROR "POLRIG_MPI=ON: mpirun not found (Debian: apt-get install openmpi-bin)")
  endif()
else()
  target_sources(polrig_lib PRIVATE src/ranks_without_mpi.cpp)
endif()
