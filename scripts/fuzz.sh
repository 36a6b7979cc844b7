#!/usr/bin/env bash
# Runs every libFuzzer target of a fuzz build (SOFTHD_FUZZ=ON, clang, ASan+UBSan) for a
# set time on its seed corpus (fuzz/corpus/<target>), and fails on the first finding.
# usage: scripts/fuzz.sh BUILD_DIR SECONDS_PER_TARGET
# New corpus entries go to BUILD_DIR/fuzz-corpus/<target>; a crashing input is kept as
# BUILD_DIR/fuzz-findings/<target>/crash-* and printed as a path.
set -euo pipefail
build=${1:?usage: fuzz.sh BUILD_DIR SECONDS}
seconds=${2:?usage: fuzz.sh BUILD_DIR SECONDS}
source_dir=$(cd "$(dirname "$0")/.." && pwd)
status=0
for t in text_cloud ply_cloud pcd_cloud scene checkpoint msh; do
  exe="$build/fuzz/fuzz_$t"
  [ -x "$exe" ] || { echo "fuzz.sh: $exe is missing (build with -DSOFTHD_FUZZ=ON)"; exit 1; }
  corpus="$build/fuzz-corpus/$t"
  findings="$build/fuzz-findings/$t"
  mkdir -p "$corpus" "$findings"
  log="$build/fuzz-$t.log"
  # -timeout: an input taking 10 s is a hang; -rss_limit_mb: 2 GiB is a runaway allocation.
  if "$exe" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
      -artifact_prefix="$findings/" "$corpus" "$source_dir/fuzz/corpus/$t" >"$log" 2>&1; then
    runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || true)
    echo "fuzz $t: ${seconds} s, ${runs:-?} inputs, no finding"
  else
    status=1
    echo "fuzz $t: FINDING (log $log):"
    grep -E 'ERROR|SUMMARY|Test unit written|terminate|what\(\)' "$log" | head -20
  fi
done
exit $status
