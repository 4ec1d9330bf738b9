#!/usr/bin/env bash
# The polrig command under MPI (CTest label "mpi", -DPOLRIG_MPI=ON), one case per call:
#   bash tests/mpi_cli.sh CASE POLRIG_EXE SOURCE_DIR WORK_DIR MPIRUN [MPIRUN_ARGS…]
# A run under 1 process (plain, no launcher) and under `mpirun -np 2` with the same argv, from
# the same folder, must write the same folder byte for byte (every file, manifest.yaml
# included) and the same standard output; a failure must be said once, by rank 0, with the
# same exit code on every rank, and write nothing.
set -euo pipefail
case_name=$1 exe=$2 src=$3 work=$4
shift 4
mpirun=("$@")
rm -rf "$work" && mkdir -p "$work" && cd "$work"
fail() { echo "FAIL ($case_name): $*" >&2; exit 1; }

# same_under_1_and_2 ARGS…: runs polrig ARGS -o out as one process then as 2 ranks, keeps the
# first folder as one/ and compares.
same_under_1_and_2() {
  "$exe" "$@" -o out --quiet >stdout.1
  mv out one
  "${mpirun[@]}" -np 2 "$exe" "$@" -o out --quiet >stdout.2
  diff -r one out || fail "the folders of 1 and 2 ranks differ"
  diff stdout.1 stdout.2 || fail "the standard output of 1 and 2 ranks differs"
  [ -n "$(ls out)" ] || fail "nothing written"
  echo "same under 1 and 2 ranks: $(cd out && echo *)"
}

# fails_once CODE MESSAGE ARGS…: polrig ARGS under 2 ranks exits CODE on every rank, prints
# "polrig: error: MESSAGE…" once (and the same as one process does), and leaves the folder empty.
fails_once() {
  local code=$1 message=$2
  shift 2
  set +e
  "$exe" "$@" 2>stderr.1 >/dev/null
  local alone=$?
  # Each rank records its exit code and ends with 0, so that mpirun, which stops the job when
  # one process ends with another code, lets every rank finish on its own.
  "${mpirun[@]}" -np 2 bash -c '"$@"; echo $? >"rc.${OMPI_COMM_WORLD_RANK}"' rank "$exe" "$@" \
    2>stderr.2 >/dev/null
  set -e
  [ "$alone" = "$code" ] || fail "one process exited $alone, expected $code"
  for r in 0 1; do
    [ "$(cat "rc.$r")" = "$code" ] || fail "rank $r exited $(cat "rc.$r"), expected $code"
  done
  local said
  said=$(grep -c '^polrig: error: ' stderr.2 || true)
  [ "$said" = 1 ] || { cat stderr.2 >&2; fail "the error was said $said times"; }
  grep -F "polrig: error: $message" stderr.2 >/dev/null || { cat stderr.2 >&2; fail "not the expected message"; }
  [ "$(grep '^polrig: error: ' stderr.1)" = "$(grep '^polrig: error: ' stderr.2)" ] ||
    fail "1 and 2 ranks say different things: $(cat stderr.1) / $(grep '^polrig: error: ' stderr.2)"
  rm -f rc.* stderr.*
  [ -z "$(ls -A | grep -v -x -e pre-existing)" ] || fail "something was written: $(ls -A)"
  echo "failed once with exit $code: $message"
}

rig=$src/rigs/wang2019-indoor.yaml
case $case_name in
  sweep)  # 12,000 points: blocks of 4096, 4096 and 3808, each shared by both ranks
    same_under_1_and_2 sweep "$rig" --grid eccentricity.L_IS=0.001:1:120 --grid eccentricity.alpha_S=0:359:100
    ;;
  traced-sweep)  # the traced rig with a quick scene (few photons); every rank solves the sphere
    sed -e 's/photons: 2000000/photons: 20000/' -e 's/batches: 16/batches: 4/' \
      -e 's/wall_bins_theta: 90/wall_bins_theta: 18/' -e 's/wall_bins_phi: 180/wall_bins_phi: 36/' \
      -e 's/plane_samples: 4096/plane_samples: 256/' "$src/scenes/jf500.yaml" >scene.yaml
    sed 's#scene: ../scenes/jf500.yaml#scene: scene.yaml#' "$src/rigs/wang2019-indoor-traced.yaml" >rig.yaml
    grep -q 'photons: 20000$' scene.yaml && grep -q 'scene: scene.yaml' rig.yaml || fail "the quick scene was not made"
    same_under_1_and_2 sweep rig.yaml --grid eccentricity.L_IS=0:0.2:3 --grid eccentricity.alpha_S=0:90:2 --steps 8
    ;;
  study-calibration)  # 13 trials: shards of 6 and 7
    same_under_1_and_2 study calibration "$rig" --trials 13
    ;;
  bad-grid)
    fails_once 2 "--grid eccentricity.L_IS=-1:1:10: key 'eccentricity.L_IS'" \
      sweep "$rig" --grid eccentricity.L_IS=-1:1:10 -o out
    ;;
  rank-1-fails)  # 13 axes (no corner checks): the first bad point, 2048, is in rank 1's shard
    grid=(--grid eccentricity.alpha_S=0:1:2 --grid schedule.start_deg=0:400:2)
    for _ in 1 2 3 4 5 6 7 8 9 10 11; do grid+=(--grid eccentricity.alpha_S=0:1:2); done
    fails_once 2 "--grid point (eccentricity.alpha_S=0, schedule.start_deg=400," sweep "$rig" "${grid[@]}" -o out
    ;;
  output-exists)  # rank 0 alone opens the output
    mkdir pre-existing
    fails_once 1 "-o/--out pre-existing: " sweep "$rig" --grid eccentricity.L_IS=0:1:5 -o pre-existing
    ;;
  one-process-commands)
    set +e
    "${mpirun[@]}" -np 2 "$exe" study cs "$rig" -o out 2>stderr >/dev/null
    code=$?
    set -e
    [ "$code" = 2 ] || fail "study cs under 2 ranks exited $code, expected 2"
    [ "$(grep -c '^polrig: error: polrig study cs runs as one process' stderr)" = 1 ] || { cat stderr >&2; fail "not said once"; }
    [ ! -e out ] || fail "out was written"
    # One rank is one process: every command runs.
    "${mpirun[@]}" -np 1 "$exe" study cs "$rig" -o out --steps 8 --no-plots --quiet >/dev/null
    [ -f out/summary.csv ] || fail "study cs under 1 rank wrote no summary.csv"
    echo "study cs refused under 2 ranks, runs under 1"
    ;;
  *) fail "unknown case" ;;
esac
