#!/usr/bin/env bash
# kill -9 during `vkloc simulate`, `vkloc track` and `vkloc keyframes build`: every output is
# either absent, or complete and loadable, or a "<name>.partial" of whole lines (a run in
# progress; `vkloc track` renames it when the run is complete). Each command runs once to the end
# to time it, then is killed with SIGKILL at several points spread over that time.
# Temporaries of an atomic write ("<name>.tmp-<pid>-<n>") that a kill interrupts are allowed and
# counted: they never replace the output they were for; the same command run again into that
# folder removes them (their process no longer runs) and completes every output.
# Usage: cli_kill_test.sh <vkloc> <work dir>
set -euo pipefail
VKLOC=$1
WORK=$2
rm -rf "$WORK"
mkdir -p "$WORK"
failures=0
temporaries=0
checked=0

fail() {
  echo "FAIL: $*" >&2
  failures=$((failures + 1))
}

# A text file of whole lines: empty, or ending in a line break.
whole_lines() {
  [ ! -s "$1" ] || [ "$(tail -c 1 "$1" | od -An -c | tr -d ' ')" = '\n' ]
}

# A CSV log: a header (EuRoC's starts with '#'), then rows of the header's field count.
check_csv() {
  local f=$1
  whole_lines "$f" || { fail "$f: ends inside a line"; return; }
  [ -s "$f" ] || return 0
  awk -F, 'NR == 1 { n = NF; if ($1 !~ /^#?[A-Za-z_]/) exit 1; next } NF != n { exit 1 }' "$f" ||
    fail "$f: a row with another field count than the header, or no header"
}

# A TUM trajectory (comments, then 't tx ty tz qx qy qz qw' rows).
check_tum() {
  local f=$1
  whole_lines "$f" || { fail "$f: ends inside a line"; return; }
  awk '/^#/ { next } NF != 8 { exit 1 }' "$f" || fail "$f: a row without 8 fields"
}

# PNG ends with its IEND chunk, JPEG with its EOI marker.
check_image() {
  local f=$1 tail_hex
  case "$f" in
    *.png) tail_hex=$(tail -c 8 "$f" | od -An -tx1 | tr -d ' \n'); [ "$tail_hex" = "49454e44ae426082" ] ;;
    *.jpg) tail_hex=$(tail -c 2 "$f" | od -An -tx1 | tr -d ' \n'); [ "$tail_hex" = "ffd9" ] ;;
    *) false ;;
  esac || fail "$f: truncated image"
}

# Every file under an output folder: complete, a whole-line .partial, or an atomic write's
# temporary. $2: sequence folder that track outputs are evaluated against.
check_outputs() {
  local dir=$1 seq=${2:-}
  [ -e "$dir" ] || return 0
  while IFS= read -r -d '' f; do
    checked=$((checked + 1))
    case "$f" in
      *.tmp-[0-9]*-[0-9]*) temporaries=$((temporaries + 1)) ;;
      *.csv.partial | *.csv) check_csv "$f" ;;
      *traj.txt.partial | *traj.txt | *traj_visual.txt.partial | *traj_visual.txt | */groundtruth.txt) check_tum "$f" ;;
      *.partial) whole_lines "$f" || fail "$f: ends inside a line" ;;
      *.png | *.jpg) check_image "$f" ;;
      *.glb) "$VKLOC" info --model "$f" >/dev/null 2>&1 || fail "$f: model does not load" ;;
      *.kdb) "$VKLOC" keyframes info "$f" >/dev/null 2>&1 || fail "$f: keyframe database does not load" ;;
      *.json) [ "$(tail -c 2 "$f" | od -An -c | tr -d ' ')" = '}\n' ] || fail "$f: incomplete JSON" ;;
      *.html) grep -q '</html>' "$f" || fail "$f: incomplete HTML" ;;
      *.yaml | *.txt) whole_lines "$f" || fail "$f: ends inside a line" ;;
      *) fail "$f: unexpected output" ;;
    esac
  done < <(find "$dir" -type f -print0)
  # Files that belong together load together.
  if [ -f "$dir/sequence.yaml" ] && [ -f "$dir/camera.yaml" ] && [ -f "$dir/images.txt" ] &&
    [ -f "$dir/groundtruth.txt" ]; then
    "$VKLOC" eval --estimate "$dir/groundtruth.txt" --sequence "$dir" >/dev/null 2>&1 ||
      fail "$dir: the sequence does not load"
  fi
  if [ -n "$seq" ] && [ -f "$dir/traj.txt" ]; then
    "$VKLOC" eval --estimate "$dir/traj.txt" --sequence "$seq" >/dev/null 2>&1 ||
      fail "$dir/traj.txt: does not evaluate against $seq"
  fi
}

# Temporaries of atomic writes under a folder.
count_temporaries() {
  find "$1" -type f -name '*.tmp-[0-9]*-[0-9]*' 2>/dev/null | wc -l
}

# The command "${@:2}" run again to the end into the killed folder $1: no temporary stays.
rerun_clears() {
  local dir=$1
  shift
  [ "$(count_temporaries "$dir")" -gt 0 ] || return 0
  "$@" >/dev/null 2>&1 || { fail "$* failed after a kill"; return; }
  local left
  left=$(count_temporaries "$dir")
  [ "$left" -eq 0 ] || fail "$dir: ${left} temporaries of a killed run left after running again"
  reruns=$((reruns + 1))
}
reruns=0

# Runs "$@" to the end; prints its wall time in milliseconds.
timed() {
  local t0 t1
  t0=$(date +%s%N)
  "$@" >/dev/null 2>&1 || { fail "$* failed"; return 0; }
  t1=$(date +%s%N)
  echo $(((t1 - t0) / 1000000))
}

# Starts "$@", sends SIGKILL after $1 milliseconds, waits for it.
kill_after() {
  local ms=$1
  shift
  "$@" >/dev/null 2>&1 &
  local pid=$!
  sleep "$(printf '%d.%03d' $((ms / 1000)) $((ms % 1000)))"
  kill -KILL "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
}

# Kill points: these fractions of a full run (the last ones near its end, where outputs are
# renamed into place), jittered by up to 2.5 % with a fixed seed.
FRACTIONS="15 50 85 97 99"
RANDOM=16
kill_points() {
  local total=$1 f
  for f in $FRACTIONS; do
    echo $((total * (f * 100 + RANDOM % 500 - 250) / 10000))
  done
}

# --- simulate -----------------------------------------------------------------------------
seq=$WORK/seq
sim=("$VKLOC" simulate room easy --frames 6 --reference --seed 3)
ms=$(timed "${sim[@]}" --out "$seq")
check_outputs "$seq"
echo "simulate: ${ms} ms to the end"
for at in $(kill_points "$ms"); do
  out=$WORK/sim_killed_$at
  kill_after "$at" "${sim[@]}" --out "$out"
  check_outputs "$out"
  rerun_clears "$out" "${sim[@]}" --out "$out"
  check_outputs "$out"
done

# --- track --------------------------------------------------------------------------------
track=("$VKLOC" track --sequence "$seq" --backend cpu --overlay-every 3)
ms=$(timed "${track[@]}" --out "$WORK/track/traj.txt" --overlay "$WORK/track/overlay")
check_outputs "$WORK/track" "$seq"
for f in traj.txt traj_frames.csv traj_filter.csv traj_report/track.json; do
  [ -f "$WORK/track/$f" ] || fail "a complete track run lacks $f"
done
echo "track: ${ms} ms to the end"
for at in $(kill_points "$ms"); do
  out=$WORK/track_killed_$at
  kill_after "$at" "${track[@]}" --out "$out/traj.txt" --overlay "$out/overlay"
  check_outputs "$out" "$seq"
  rerun_clears "$out" "${track[@]}" --out "$out/traj.txt" --overlay "$out/overlay"
  check_outputs "$out" "$seq"
done

# --- keyframes build ----------------------------------------------------------------------
build=("$VKLOC" keyframes build --sequence "$seq" --spacing 0.8 --margin 0.5 --headings 8 --renderer cpu --threads 2)
mkdir -p "$WORK/kdb"
ms=$(timed "${build[@]}" --out "$WORK/kdb/room.kdb")
check_outputs "$WORK/kdb"
[ -f "$WORK/kdb/room.kdb" ] || fail "a complete keyframes build lacks its database"
echo "keyframes build: ${ms} ms to the end"
for at in $(kill_points "$ms"); do
  out=$WORK/kdb_killed_$at
  mkdir -p "$out"
  kill_after "$at" "${build[@]}" --out "$out/room.kdb"
  check_outputs "$out"
done

echo "checked ${checked} files after $(($(echo $FRACTIONS | wc -w) * 3)) kills; ${temporaries} atomic-write temporaries met, ${reruns} folders with temporaries run again and cleared"
if [ "$failures" -gt 0 ]; then
  echo "${failures} failure(s)" >&2
  exit 1
fi
