#!/usr/bin/env bash
# Strong scaling of the MPI build (docs/scale.md): each job as one process and under
# `mpirun -np 2`, ranks of --threads 1, wall clock from process start to files on disk; prints
# the rows of docs/scale.md's table: wall time (CPU time of all processes) per rank count, and
# the speed-up of the last over the first. ONLY=REGEX runs only the jobs whose name matches. Usage: bash bench/scale_mpi.sh [BUILD_DIR] (default build-mpi,
# configured with -DPOLRIG_MPI=ON). RANKS="1 2 4" for other rank counts (1 = no launcher).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
exe=$(cd "${1:-$root/build-mpi}" && pwd)/polrig
ranks=(${RANKS:-1 2})
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
# The traced rig with a quick scene (20,000 photons), as tests/mpi_cli.sh makes it.
sed -e 's/photons: 2000000/photons: 20000/' -e 's/batches: 16/batches: 4/' \
  -e 's/wall_bins_theta: 90/wall_bins_theta: 18/' -e 's/wall_bins_phi: 180/wall_bins_phi: 36/' \
  -e 's/plane_samples: 4096/plane_samples: 256/' "$root/scenes/jf500.yaml" >scene.yaml
sed 's#scene: ../scenes/jf500.yaml#scene: scene.yaml#' "$root/rigs/wang2019-indoor-traced.yaml" >traced.yaml

jobs=(
  "10⁶-point cos⁴ sweep|sweep $root/rigs/wang2019-indoor.yaml --grid eccentricity.L_IS=0.001:1:1000 --grid eccentricity.alpha_S=0:359:1000"
  "traced sweep, quick scene, 256 points, --steps 8|sweep traced.yaml --grid eccentricity.L_IS=0:0.2:16 --grid eccentricity.alpha_S=0:337.5:16 --steps 8"
  "study calibration --trials 4000|study calibration $root/rigs/wang2019-indoor.yaml --trials 4000"
)
for job in "${jobs[@]}"; do
  name=${job%%|*}
  [[ "$name" =~ ${ONLY:-.} ]] || continue  # ONLY=REGEX: the jobs whose name matches
  read -r -a args <<<"${job#*|}"
  row="| $name"
  first=""
  for n in "${ranks[@]}"; do
    rm -rf out
    launcher=()
    if [ "$n" != 1 ]; then launcher=(mpirun -np "$n" --oversubscribe); fi
    # Wall clock, and the CPU time (user + system) of every process of the run.
    TIMEFORMAT='%R %U %S'
    read -r t user sys < <({ time "${launcher[@]}" "$exe" "${args[@]}" --threads 1 --quiet -o out >/dev/null; } 2>&1)
    first=${first:-$t}
    row+=$(awk -v t="$t" -v u="$user" -v s="$sys" 'BEGIN { printf " | %.1f s (CPU %.1f s)", t, u + s }')
  done
  row+=$(awk -v a="$first" -v b="$t" 'BEGIN { printf " | %.2f× |", a / b }')
  echo "$row"
done
