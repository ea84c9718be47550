#!/usr/bin/env bash
# Builds the libFuzzer targets (preset fuzz: clang, ASan + UBSan) and runs each for a longer time
# than CI does, keeping a corpus outside git in build/fuzz/corpus/<target> (seeded from
# tests/fuzz/corpus) and what the fuzzer finds in build/fuzz/findings/<target>. Prints per target
# executions, coverage (cov: edges, ft: features) and findings; exits 1 when anything was found.
#
#   scripts/fuzz.sh [-t SECONDS] [-j JOBS] [--strict] [--keep-going] [--list] [TARGET...]
#     -t SECONDS  time per target (default 600)
#     -j JOBS     targets run at the same time (default 1)
#     --strict    known findings (tests/fuzz/known_findings.txt) fail too (leaks inside
#                 third-party libraries stay suppressed: tests/sanitizers/lsan.supp)
#     --keep-going  fork mode: a crash, timeout or OOM is saved and fuzzing goes on (for a target
#                 whose first finding is known and not fixed yet)
#     --list      print the target names and exit
#     TARGET      e.g. model_obj camera_yaml (default: all)
# Logs are build/fuzz/logs/<target>.log. Reproduce a finding with
# `build/fuzz/tests/fuzz/fuzz_<target> build/fuzz/findings/<target>/crash-...`.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=600
jobs=1
strict=0
keep_going=0
list=0
targets=()
while [ "$#" -gt 0 ]; do
  case "$1" in
    -t) seconds="$2"; shift 2 ;;
    -j) jobs="$2"; shift 2 ;;
    --strict) strict=1; shift ;;
    --keep-going) keep_going=1; shift ;;
    --list) list=1; shift ;;
    -h|--help) sed -n '2,18p' "$0"; exit 0 ;;
    -*) echo "fuzz.sh: unknown option $1" >&2; exit 2 ;;
    *) targets+=("$1"); shift ;;
  esac
done

cmake --preset fuzz >/dev/null
cmake --build --preset fuzz -j "${VKLOC_BUILD_JOBS:-2}"
manifest=build/fuzz/tests/fuzz/fuzzers.txt

if [ "$list" -eq 1 ]; then
  cut -d' ' -f1 "$manifest"
  exit 0
fi
if [ "${#targets[@]}" -eq 0 ]; then
  mapfile -t targets < <(cut -d' ' -f1 "$manifest")
fi
for t in "${targets[@]}"; do
  grep -q "^$t " "$manifest" || { echo "fuzz.sh: no target '$t' (--list)" >&2; exit 2; }
done

known=""
if [ "$strict" -eq 0 ]; then
  known=$(grep -E '^[a-z]' tests/fuzz/known_findings.txt | awk '{print $1}' | paste -sd, - || true)
fi
mkdir -p build/fuzz/logs
start=build/fuzz/logs/.start
touch "$start"

run_one() {
  local name=$1 exe seeds max_len dict
  read -r _ exe seeds max_len dict < <(grep "^$name " "$manifest")
  local corpus=build/fuzz/corpus/$name findings=build/fuzz/findings/$name
  mkdir -p "$corpus" "$findings"
  local args=("$corpus" "$seeds" "-max_total_time=$seconds" -timeout=5 -rss_limit_mb=2048 "-max_len=$max_len"
    "-artifact_prefix=$findings/" -print_final_stats=1)
  if [ -n "$dict" ]; then args+=("-dict=$dict"); fi
  if [ "$keep_going" -eq 1 ]; then args+=(-fork=1 -ignore_crashes=1 -ignore_timeouts=1 -ignore_ooms=1); fi
  VKLOC_FUZZ_KNOWN="$known" LSAN_OPTIONS="suppressions=$PWD/tests/sanitizers/lsan.supp" "$exe" "${args[@]}" >"build/fuzz/logs/$name.log" 2>&1 || true
}

running=0
for t in "${targets[@]}"; do
  echo "fuzz.sh: $t (${seconds} s)"
  run_one "$t" &
  running=$((running + 1))
  if [ "$running" -ge "$jobs" ]; then
    wait -n || true
    running=$((running - 1))
  fi
done
wait

status=0
printf '%-24s %12s %8s %8s %8s %9s  %s\n' target executions exec/s cov ft corpus findings
for t in "${targets[@]}"; do
  log=build/fuzz/logs/$t.log
  execs=$(grep -oE 'stat::number_of_executed_units: [0-9]+' "$log" | awk '{print $2}' | tail -1 || true)
  rate=$(grep -oE 'stat::average_exec_per_sec: +[0-9]+' "$log" | awk '{print $2}' | tail -1 || true)
  last=$(grep -E '^#[0-9]+' "$log" | tail -1 || true)
  if [ -z "$execs" ]; then execs=$(grep -oE '^#[0-9]+' <<<"$last" | tr -d '#' || true); fi
  if [ -z "$rate" ]; then rate=$(grep -oE 'exec/s:? [0-9]+' <<<"$last" | grep -oE '[0-9]+$' || true); fi
  cov=$(grep -oE 'cov: [0-9]+' <<<"$last" | awk '{print $2}' || true)
  ft=$(grep -oE 'ft: [0-9]+' <<<"$last" | awk '{print $2}' || true)
  corpus=$(find "build/fuzz/corpus/$t" -type f | wc -l)
  found=$(find "build/fuzz/findings/$t" -type f -newer "$start" | wc -l)
  known_hits=$(grep -oE "known finding '[^']+'" "$log" | sort -u | cut -d"'" -f2 | paste -sd, - || true)
  note=$found
  if [ -n "$known_hits" ]; then note="$found (known: $known_hits)"; fi
  printf '%-24s %12s %8s %8s %8s %9s  %s\n' "$t" "${execs:-?}" "${rate:-?}" "${cov:-?}" "${ft:-?}" "$corpus" "$note"
  if [ "$found" -gt 0 ] || [ -z "$last" ]; then status=1; fi
done
if [ "$status" -ne 0 ]; then echo "fuzz.sh: findings in build/fuzz/findings, logs in build/fuzz/logs" >&2; fi
exit "$status"
