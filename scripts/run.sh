#!/usr/bin/env bash
# The first set-up command: install what is missing, build, and run polrig's main job on the
# default rig. Results and PNG plots go to results/wang2019-indoor/ (or the folder given).
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-results/wang2019-indoor}"
bash scripts/setup-deps.sh
bash scripts/build.sh -DPOLRIG_MPI=OFF  # the one-process build (CI's test.sh builds build/ with MPI)
./build/polrig run rigs/wang2019-indoor.yaml -o "$out" --force
echo "results: $out (simulate/, calibration/, cs/, adc/)"
