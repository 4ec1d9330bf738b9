#!/usr/bin/env bash
# Runs every command of the README's "Using it" block, made smaller, as a user would after the two
# set-up commands (issue 23 §1; CTest label "slow"):
#   bash tests/readme_commands.sh POLRIG_EXE SOURCE_DIR
# 1. The ```sh block under "## Using it" is read from SOURCE_DIR/README.md: backslash-continued
#    lines are joined, trailing "# comments" (a # after white space: the block has no # inside
#    quotes) and comment-only lines dropped.
# 2. Every line runs, in order, in one fresh scratch folder laid out like the repository's: rigs/,
#    scenes/ and data/ are symlinks to SOURCE_DIR's, and build/polrig is a symlink to POLRIG_EXE,
#    so the block's own first line (export PATH="$PWD/build:$PATH") is what puts `polrig` on PATH
#    (checked), the README's relative paths work and out/… lands in the scratch folder. The lines
#    run in this script's shell (eval), so an `export` holds for the lines after it.
# 3. A line is made smaller by the one table below (SHRINK), keyed by a distinctive piece of it;
#    a line without an entry runs exactly as written. Two lines are special:
#    - `bash scripts/build-mpi.sh` is not run: the test uses the build it was given;
#    - the `mpirun … build-mpi/polrig …` line runs with POLRIG_EXE for build-mpi/polrig, only when
#      POLRIG_EXE was built with MPI (it links libmpi) and mpirun is found; else it says it skipped
#      it. It runs as written otherwise: as root too (the README's line has --allow-run-as-root).
#    The files a user is expected to bring are made before the first line that names them
#    (make_user_file below): my_measurements.csv and more_voltages.csv from out/sim's outputs,
#    points.csv and ins_log.csv written literally.
# 4. One line per command with its time; a command that exits non-zero is a failure, printed with
#    its stderr; the last line is "readme: N passed, M failed" (and skipped ones); exit 1 on any
#    failure. The scratch folder is removed on success (kept with POLRIG_README_KEEP=1, to look at
#    the plots) and kept (its path printed) on failure.
# It takes about a minute on the 2-core development machine shared with three builds (load ≈ 10);
# the largest part is `polrig trace` (≈ 13 s, its 61 × 61 plane map whatever the scene's samples).
set -uo pipefail

if [ $# -ne 2 ]; then
  echo "usage: bash tests/readme_commands.sh POLRIG_EXE SOURCE_DIR" >&2
  exit 2
fi
exe=$(realpath "$1") src=$(realpath "$2")
[ -x "$exe" ] || { echo "readme: $1 is not an executable" >&2; exit 2; }
[ -f "$src/README.md" ] || { echo "readme: $2 has no README.md" >&2; exit 2; }

# SHRINK: one entry a line, "KEY || EDIT || EDIT …". KEY is a piece of exactly one README line
# (after joining and dropping its comment). An EDIT is either "+ ARGS", ARGS appended to the line,
# or "OLD => NEW", the text OLD (which must be in the line) replaced by NEW: only where an option
# the line already has must change (a grid's count, --trials). Every KEY must match a line.
# An entry may go on over lines that begin with white space; lines starting with # are comments.
# shrunk/jf500.yaml is scenes/jf500.yaml with a small trace: block (shrink_scene below).
SHRINK=$(cat <<'EOF'
# the sweep's 100 × 100 grid runs as written (about 1 s)
build-mpi/polrig sweep      || 0.001:1:2000 => 0.001:1:20 || 0:359:360 => 0:359:12
study calibration           || --trials 1000 => --trials 50
polrig trace scenes/jf500.yaml
                            || scenes/jf500.yaml => shrunk/jf500.yaml
study cs rigs/wang2019-indoor-traced.yaml
                            || + --steps 4 --set source.scene=shrunk/jf500.yaml
polrig sky rigs/            || + --size 128
study heading               || --trials 10000 => --trials 200
simulate rigs/han2017-indoor.yaml
                            || + --set device.width_px=64 --set device.height_px=48
                               --set schedule.frames_per_stop=1 --set 'schedule.intensities=[1, 0.5]'
simulate rigs/han2017-outdoor.yaml
                            || + --set device.width_px=160 --set device.height_px=120
study positioning           || + --set schedule.count=61 --set schedule.dwell_s=60 --trials 10
study navigation            || --trials 20 => --trials 2
# W16's cameras at a quarter of their resolution, as docs/cli.md's "practical runs" (every size
# and intrinsic divided by 4); the calibration's fisheye fit needs about 10 checkerboard views there
simulate rigs/wang2016-rotation.yaml
                            || + --set device.cameras.width_px=258 --set device.cameras.height_px=194
                               --set 'device.cameras.fx_px=[192.5, 192.8, 192.225, 192.65]'
                               --set 'device.cameras.fy_px=[192.5, 192.8, 192.225, 192.65]'
                               --set 'device.cameras.cx_px=[129, 129.6, 128.925, 129.475]'
                               --set 'device.cameras.cy_px=[97, 96.95, 97.575, 97.15]'
simulate rigs/wang2016-calibration.yaml
                            || + --set device.cameras.width_px=258 --set device.cameras.height_px=194
                               --set 'device.cameras.fx_px=[192.5, 192.8, 192.225, 192.65]'
                               --set 'device.cameras.fy_px=[192.5, 192.8, 192.225, 192.65]'
                               --set 'device.cameras.cx_px=[129, 129.6, 128.925, 129.475]'
                               --set 'device.cameras.cy_px=[97, 96.95, 97.575, 97.15]'
                               --set checkerboard.views=10
EOF
)

# shrink_scene SCENE OUT: SCENE with a small trace: block (16,000 photons, a 10° wall field, an
# 18 × 36 wall map, 256 plane samples): about 1 s to solve instead of JF-500's tens of seconds.
shrink_scene() {
  sed -E -e 's/^(  photons:) [0-9]+/\1 16000/' -e 's/^(  field_step_deg:) [0-9.]+/\1 10/' \
         -e 's/^(  wall_bins_theta:) [0-9]+/\1 18/' -e 's/^(  wall_bins_phi:) [0-9]+/\1 36/' \
         -e 's/^(  plane_samples:) [0-9]+/\1 256/' "$1" >"$2"
  if [ "$(diff "$1" "$2" | grep -c '^>')" -ne 5 ]; then
    echo "readme: $1's trace: block is not as shrink_scene expects (photons, field_step_deg," \
      "wall_bins_theta, wall_bins_phi, plane_samples)" >&2
    return 1
  fi
}

# The files a user is expected to have, made just before the first line that names them.
make_user_file() {
  case $1 in
    my_measurements.csv)  # measured voltages: out/sim's stops, columns theta_R_deg,V1,V2,V3
      columns out/sim/stops.csv theta_R_deg,V1,V2,V3 >"$1" ;;
    more_voltages.csv)    # field voltages without angles: out/sim's samples, columns V1,V2,V3
      columns out/sim/samples.csv V1,V2,V3 >"$1" ;;
    points.csv)           # written literally: W19's roof at Outdoor1's first stop, three views
      cat >"$1" <<'EOF'
utc,lat_deg,lon_deg,view_az_deg,view_el_deg
2018-11-16T08:09:40Z,38.879167,121.543889,0,90
2018-11-16T08:09:40Z,38.879167,121.543889,90,45
2019-07-01T11:01:00Z,38.879167,121.543889,180,30
EOF
      ;;
    ins_log.csv)          # written literally: docs/cli.md's two readings of W19's dynamic run
                          # (polrig heading) and a third one 30 s later
      cat >"$1" <<'EOF'
utc,roll_deg,pitch_deg,aop_deg
2019-07-01T11:01:00Z,0,0,30
2019-07-01T11:01:00Z,2,-3,120.5
2019-07-01T11:01:30Z,-1,1.5,75
EOF
      ;;
    *) return 1 ;;
  esac
}
user_files="my_measurements.csv more_voltages.csv points.csv ins_log.csv"

# columns CSV NAME,NAME…: those columns of CSV (by header name), in that order.
columns() {
  awk -F, -v want="$2" '
    NR == 1 { n = split(want, w, ","); for (i = 1; i <= NF; i++) at[$i] = i
              for (j = 1; j <= n; j++) if (!(w[j] in at)) { print FILENAME ": no column " w[j] > "/dev/stderr"; exit 1 } }
    { line = ""; for (j = 1; j <= n; j++) line = line (j > 1 ? "," : "") $(at[w[j]]); print line }' "$1"
}

# The block's commands, one a line.
readme_lines() {
  awk '
    /^## / { inside = ($0 == "## Using it") ; next }
    inside && !block && /^```sh[[:space:]]*$/ { block = 1; next }
    block && /^```[[:space:]]*$/ { exit }
    block { print }' "$src/README.md" |
    awk '{ if (sub(/\\[[:space:]]*$/, "")) { held = held $0; next }
           print held $0; held = "" }' |
    sed -E 's/(^|[[:space:]]+)#.*$//; s/[[:space:]]+$//; s/^[[:space:]]+//; s/[[:space:]]+/ /g' |
    grep -v '^$'
}
mapfile -t lines < <(readme_lines)
if [ ${#lines[@]} -eq 0 ]; then
  echo "readme: no commands found under '## Using it' in $src/README.md" >&2
  exit 1
fi

# Every table entry must name exactly one line.
mapfile -t table < <(printf '%s\n' "$SHRINK" | grep -v -e '^[[:space:]]*$' -e '^#' |
  awk '/^[[:space:]]/ { sub(/^[[:space:]]+/, " "); held = held $0; next }
       { if (held != "") print held; held = $0 } END { if (held != "") print held }')
entry_key() { local k=${1%%||*}; k=${k%"${k##*[![:space:]]}"}; printf '%s' "$k"; }
problems=0
for entry in "${table[@]}"; do
  key=$(entry_key "$entry") n=0
  for l in "${lines[@]}"; do [[ $l == *"$key"* ]] && n=$((n + 1)); done
  if [ $n -ne 1 ]; then
    echo "readme: the shrink entry '$key' matches $n README lines, not 1" >&2
    problems=1
  fi
done
[ $problems -eq 0 ] || exit 1

# shrink LINE: the line with its table entry's edits applied.
shrink() {
  local line=$1 entry key rest edit old new
  for entry in "${table[@]}"; do
    key=$(entry_key "$entry")
    [[ $line == *"$key"* ]] || continue
    rest=${entry#*||}
    while [ -n "$rest" ]; do
      edit=${rest%%||*}
      if [[ $rest == *"||"* ]]; then rest=${rest#*||}; else rest=; fi
      edit=$(sed -E 's/^[[:space:]]+//; s/[[:space:]]+$//' <<<"$edit")
      if [[ $edit == "+ "* ]]; then
        line="$line ${edit#+ }"
      elif [[ $edit == *" => "* ]]; then
        old=${edit%% => *} new=${edit#* => }
        if [[ $line != *"$old"* ]]; then
          echo "readme: the shrink edit '$edit' does not apply: '$old' is not in: $line" >&2
          return 1
        fi
        line=${line/"$old"/"$new"}
      else
        echo "readme: bad shrink edit '$edit' (expected '+ ARGS' or 'OLD => NEW')" >&2
        return 1
      fi
    done
  done
  printf '%s\n' "$line"
}

scratch=$(mktemp -d "${TMPDIR:-/tmp}/polrig-readme.XXXXXX")
logs=$(mktemp -d "${TMPDIR:-/tmp}/polrig-readme-logs.XXXXXX")
for d in rigs scenes data; do ln -s "$src/$d" "$scratch/$d"; done
mkdir "$scratch/build" && ln -s "$exe" "$scratch/build/polrig"
mkdir "$scratch/shrunk" && shrink_scene "$src/scenes/jf500.yaml" "$scratch/shrunk/jf500.yaml" || exit 1
cd "$scratch" || exit 1

mpi_build=no
case $(ldd "$exe" 2>/dev/null) in *libmpi*) mpi_build=yes ;; esac  # no grep -q: pipefail + SIGPIPE

passed=0 failed=0 skipped=0 i=0
now() { printf '%s' "${EPOCHREALTIME/,/.}"; }
report() {  # report STATUS SECONDS LINE
  printf 'readme: %-4s %7.2f s  %s\n' "$1" "$2" "$3"
}
for line in "${lines[@]}"; do
  i=$((i + 1))
  if [ "$line" = "bash scripts/build-mpi.sh" ]; then
    report skip 0 "$line  (the test uses the build it was given)"
    skipped=$((skipped + 1))
    continue
  fi
  if ! cmd=$(shrink "$line"); then
    report FAIL 0 "$line  (its shrink entry does not apply)"
    failed=$((failed + 1))
    continue
  fi
  if [[ $cmd == mpirun* ]]; then
    why=
    if [ $mpi_build = no ]; then why="$exe was built without MPI (it links no libmpi)"
    elif ! command -v mpirun >/dev/null; then why="there is no mpirun on PATH"; fi
    if [ -n "$why" ]; then
      report skip 0 "$line  (skipped: $why)"
      skipped=$((skipped + 1))
      continue
    fi
    cmd=${cmd//build-mpi\/polrig/\"$exe\"}
  fi
  # A file a user is expected to have, named by this line and not made yet.
  made=yes
  for f in $user_files; do
    if [[ " $cmd " == *" $f "* ]] && [ ! -e "$f" ] && ! make_user_file "$f" 2>"$logs/$i.err"; then
      rm -f "$f"
      made=no
    fi
  done
  if [ $made = no ]; then
    report FAIL 0 "$cmd"
    echo "  could not make the input file it names:" >&2
    sed 's/^/  | /' "$logs/$i.err" >&2
    failed=$((failed + 1))
    continue
  fi
  # Every `polrig` must be the build under test, put on PATH by the block itself.
  if [[ $cmd == polrig* ]] && [ "$(command -v polrig)" != "$scratch/build/polrig" ]; then
    report FAIL 0 "$cmd"
    echo "  polrig on PATH is '$(command -v polrig)', not the block's build/polrig ($exe)" >&2
    failed=$((failed + 1))
    continue
  fi
  t0=$(now)
  eval "$cmd" </dev/null >"$logs/$i.out" 2>"$logs/$i.err"
  rc=$?
  t=$(awk -v a="$t0" -v b="$(now)" 'BEGIN { printf "%.2f", b - a }')
  if [ $rc -eq 0 ]; then
    report ok "$t" "$cmd"
    passed=$((passed + 1))
  else
    report FAIL "$t" "$cmd"
    echo "  exit status $rc; stderr:" >&2
    sed 's/^/  | /' "$logs/$i.err" >&2
    failed=$((failed + 1))
  fi
done

echo "readme: $passed passed, $failed failed, $skipped skipped"
if [ $failed -gt 0 ]; then
  echo "readme: the scratch folder is kept: $scratch (logs: $logs)" >&2
  exit 1
fi
if [ -n "${POLRIG_README_KEEP:-}" ]; then  # to look at what the commands wrote
  echo "readme: the scratch folder is kept (POLRIG_README_KEEP): $scratch" >&2
  exit 0
fi
cd / && rm -rf "$scratch" "$logs"
