#!/usr/bin/env bash
# The MPI build (docs/scale.md): install what is missing, then build build-mpi/polrig with
# OpenMPI, so `mpirun -np N build-mpi/polrig sweep …` shares a sweep between processes.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup-deps.sh
POLRIG_BUILD_DIR=build-mpi POLRIG_TARGET=polrig bash scripts/build.sh -DPOLRIG_MPI=ON
echo "built build-mpi/polrig (run it under mpirun -np N; as root add --allow-run-as-root)"
