#!/usr/bin/env bash
# The second set-up command: install what is missing, build, and run every test, the slow
# physics checks (CTest label "slow") included.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup-deps.sh
bash scripts/build.sh
ctest --test-dir build --output-on-failure -j2
