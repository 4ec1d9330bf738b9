#!/usr/bin/env bash
# Configures and builds polrig (Release) two jobs at a time. Extra arguments go to the CMake
# configure step (e.g. -DPOLRIG_WERROR=ON); ccache is used when installed.
#   POLRIG_BUILD_DIR  the build folder (default build/)
#   POLRIG_TARGET     build only this target (e.g. polrig: the executable without the tests,
#                     benchmarks and Python module); default: everything
set -euo pipefail
cd "$(dirname "$0")/.."
dir="${POLRIG_BUILD_DIR:-build}"
launcher=()
if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
target=()
if [ -n "${POLRIG_TARGET:-}" ]; then target=(--target "$POLRIG_TARGET"); fi
cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" "$@" >/dev/null
cmake --build "$dir" -j2 "${target[@]}"
