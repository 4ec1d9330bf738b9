#!/usr/bin/env bash
# The first set-up command: install what is missing, build the polrig executable (only it: the
# tests, benchmarks and Python module are scripts/test.sh's and pip's), and run polrig's main job
# on the default rig. Results and PNG plots go to results/wang2019-indoor/ (or the folder given).
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-results/wang2019-indoor}"
bash scripts/setup-deps.sh
POLRIG_TARGET=polrig bash scripts/build.sh -DPOLRIG_MPI=OFF  # one process (docs/scale.md for MPI)
./build/polrig run rigs/wang2019-indoor.yaml -o "$out" --force
echo "results: $out (simulate/, calibration/, cs/, adc/)"
echo "polrig is build/polrig; to type just 'polrig':  export PATH=\"$PWD/build:\$PATH\""
