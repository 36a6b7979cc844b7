#!/usr/bin/env bash
# Runs every libFuzzer target of a fuzz build (SOFTHD_FUZZ=ON, clang, ASan+UBSan) for a
# set time on its seed corpus (fuzz/corpus/<target>), and fails on the first finding.
# usage: scripts/fuzz.sh BUILD_DIR SECONDS_PER_TARGET [JOBS [TARGET...]]
# JOBS targets run at once (default 1; each target is one process on one core, so 2 halve
# the wall time on 2 cores). Every target still gets SECONDS of its own; the lines are
# printed in the targets' order. TARGETs (e.g. msh) run only those (the sanitizer suite runs
# one per CTest test); default all.
# New corpus entries go to BUILD_DIR/fuzz-corpus/<target>; a crashing input is kept as
# BUILD_DIR/fuzz-findings/<target>/crash-* and printed as a path.
set -euo pipefail
build=${1:?usage: fuzz.sh BUILD_DIR SECONDS [JOBS [TARGET...]]}
seconds=${2:?usage: fuzz.sh BUILD_DIR SECONDS [JOBS [TARGET...]]}
jobs=${3:-1}
source_dir=$(cd "$(dirname "$0")/.." && pwd)
targets=(text_cloud ply_cloud pcd_cloud scene checkpoint msh)
if [ $# -gt 3 ]; then targets=("${@:4}"); fi
for t in "${targets[@]}"; do
  [ -x "$build/fuzz/fuzz_$t" ] || { echo "fuzz.sh: $build/fuzz/fuzz_$t is missing (build with -DSOFTHD_FUZZ=ON)"; exit 1; }
done

# One target: its report line(s) in $build/fuzz-$t.result, status 1 on a finding.
run_target() {
  local t=$1 exe="$build/fuzz/fuzz_$1" corpus="$build/fuzz-corpus/$1"
  local findings="$build/fuzz-findings/$1" log="$build/fuzz-$1.log" result="$build/fuzz-$1.result"
  mkdir -p "$corpus" "$findings"
  # -timeout: an input taking 10 s is a hang; -rss_limit_mb: 2 GiB is a runaway allocation.
  if "$exe" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
      -artifact_prefix="$findings/" "$corpus" "$source_dir/fuzz/corpus/$t" >"$log" 2>&1; then
    runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || true)
    echo "fuzz $t: ${seconds} s, ${runs:-?} inputs, no finding" >"$result"
  else
    { echo "fuzz $t: FINDING (log $log):"
      grep -E 'ERROR|SUMMARY|Test unit written|terminate|what\(\)' "$log" | head -20; } >"$result"
    return 1
  fi
}

status=0
pids=()
for t in "${targets[@]}"; do
  run_target "$t" &
  pids+=($!)
  if [ ${#pids[@]} -ge "$jobs" ]; then
    wait "${pids[0]}" || status=1
    pids=("${pids[@]:1}")
  fi
done
for p in "${pids[@]}"; do wait "$p" || status=1; done
for t in "${targets[@]}"; do cat "$build/fuzz-$t.result"; done
exit $status
