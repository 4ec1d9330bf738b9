#!/usr/bin/env bash
# Configures and builds polrig (Release) into build/, two jobs at a time. Extra arguments go to
# the CMake configure step (e.g. -DPOLRIG_WERROR=ON); ccache is used when installed.
set -euo pipefail
cd "$(dirname "$0")/.."
launcher=()
if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" "$@" >/dev/null
cmake --build build -j2
