#!/usr/bin/env bash
# The second set-up command (CI runs exactly this): install what is missing, then
#   1. build once with clang, AddressSanitizer + UndefinedBehaviorSanitizer and libFuzzer's coverage
#      (build-san/: the library, the executable, the tests and the fuzzers; without OpenCV,
#      -DPOLRIG_OPENCV=OFF, so CI compiles both configurations of the geometric calibration) and
#      run the fast tests (CTest label "fast") under the sanitizers;
#   2. run each fuzzer of that build for a fixed number of inputs: a crash, a hang (> 1 s per
#      input) or a leak fails;
#   3. build normally (build/, g++, warnings as errors, with MPI: -DPOLRIG_MPI=ON, with OpenCV) and
#      run every test, the slow physics checks (CTest label "slow", the full-size geometric
#      calibration among them) and the runs under `mpirun -np 2` (label "mpi") included. The
#      README's build (scripts/run.sh) stays without MPI.
# One sanitizer build, not two (a g++ one for the tests and a clang one for the fuzzers): compiling
# is most of CI's time on a 2-core machine, and the fuzzers need clang anyway.
# The full ctest runs last, so the output ends with its summary (after the timing summary).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup-deps.sh

# Inputs per fuzzer: a smoke test of the readers on every change, about 2.5 min for all four on an
# idle 2-core machine (200000 took 4.8 min: rig_yaml alone 126 s); longer runs by hand
# (docs/architecture.md).
FUZZ_RUNS="${POLRIG_FUZZ_RUNS:-100000}"

launcher=()
if command -v ccache >/dev/null; then launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache); fi
timings=()
stage() {  # stage NAME COMMAND…: runs the command and records its wall time
  local name=$1 t0=$SECONDS
  shift
  echo "== ${name}"
  "$@"
  timings+=("$(printf '%-34s %5d s' "$name" $((SECONDS - t0)))")
}

# Sanitizer findings end the program with a non-zero status (-fno-sanitize-recover=all).
# LeakSanitizer suppressions cover third-party libraries only (scripts/lsan.supp).
export ASAN_OPTIONS="detect_leaks=1:check_initialization_order=1:strict_init_order=1:detect_stack_use_after_return=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
export LSAN_OPTIONS="suppressions=$PWD/scripts/lsan.supp:print_suppressions=0"

# The sanitizer build compiles file by file, without the batches and the precompiled header of
# the normal build (docs/architecture.md "Build options"): one file a translation unit, as the
# sanitizers and the fuzzers were proven with, and a check that no file leans on another's includes.
san_build() {
  cmake -S . -B build-san -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
    -DPOLRIG_FUZZ=ON -DPOLRIG_SANITIZERS='address;undefined' -DPOLRIG_BUILD_BENCH=OFF \
    -DPOLRIG_OPENCV=OFF -DPOLRIG_UNITY_BUILD=OFF -DCMAKE_DISABLE_PRECOMPILE_HEADERS=ON "${launcher[@]}" >/dev/null
  cmake --build build-san -j2
}
san_tests() { ctest --test-dir build-san -L fast --output-on-failure -j2; }

fuzz_run() {  # fuzz_run TARGET SEED_DIR…: new inputs go to a scratch folder, never to the repository
  local target=$1 work=build-san/run/$1
  local exe=build-san/fuzz/fuzz_$1
  shift
  rm -rf "$work" && mkdir -p "$work/corpus"
  if "$exe" -runs="$FUZZ_RUNS" -timeout=1 -detect_leaks=1 -seed=1 -rss_limit_mb=2048 \
      -artifact_prefix="$work/" "$work/corpus" "$@" 2>"$work/log"; then
    grep -E "^Done [0-9]+ runs" "$work/log" | sed "s/^/fuzz_${target}: /"
    return 0
  fi
  tail -n 60 "$work/log"
  # libFuzzer's timeout is wall-clock time, so a machine too busy to schedule the fuzzer can look
  # like a hang. A real hang repeats: an input that times out is run alone three more times, and
  # only a timeout that does not repeat is reported as a warning instead of a failure.
  local input
  input=$(find "$work" -maxdepth 1 -name 'timeout-*' | head -n 1)
  if [ -n "$input" ] && [ -z "$(find "$work" -maxdepth 1 \( -name 'crash-*' -o -name 'leak-*' -o -name 'oom-*' \))" ] &&
      "$exe" -timeout=1 "$input" "$input" "$input" >>"$work/log.repeat" 2>&1; then
    echo "fuzz_${target}: WARNING: $input timed out once but runs in < 1 s alone (a busy machine, not a hang)"
    return 0
  fi
  echo "fuzz_${target}: failed (log: $work/log, inputs: $work/)"
  return 1
}

stage "sanitizer build (clang)" san_build
stage "ASan+UBSan fast tests" san_tests
stage "fuzz rig_yaml" fuzz_run rig_yaml fuzz/corpus/rig_yaml rigs
stage "fuzz scene_yaml" fuzz_run scene_yaml fuzz/corpus/scene_yaml scenes
stage "fuzz measured_csv" fuzz_run measured_csv fuzz/corpus/measured_csv
stage "fuzz params_yaml" fuzz_run params_yaml fuzz/corpus/params_yaml
stage "build" bash scripts/build.sh -DPOLRIG_WERROR=ON -DPOLRIG_MPI=ON -DPOLRIG_OPENCV=ON
ctest_log=build/ctest-full.log
stage "full ctest" bash -c "set -o pipefail; ctest --test-dir build --output-on-failure -j2 | tee $ctest_log"

echo "== timing (wall clock)"
printf '%s\n' "${timings[@]}"
printf '%-34s %5d s\n' "total" "$SECONDS"
echo "== ctest (full suite)"
grep -E "tests passed|Total Test time" "$ctest_log"
