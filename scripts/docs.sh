#!/usr/bin/env bash
# The API reference: Doxygen over the public headers (docs/Doxyfile).
#   scripts/docs.sh OUT_DIR            HTML in OUT_DIR/html, warnings in OUT_DIR/warnings.log
#   scripts/docs.sh --check OUT_DIR    the same, and exit 1 if doxygen printed any warning
# Without doxygen: one line saying so and exit 77 (CTest reports the test as skipped).
set -euo pipefail
check=0
if [ "${1:-}" = "--check" ]; then check=1; shift; fi
out=${1:?usage: scripts/docs.sh [--check] OUT_DIR}
if ! command -v doxygen > /dev/null 2>&1; then
  echo "SKIPPED: doxygen is not installed (scripts/install-deps.sh or apt-get install doxygen)"
  exit 77
fi
root=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$out"
out=$(cd "$out" && pwd)
log="$out/warnings.log"
cd "$root"
( cat docs/Doxyfile; echo "OUTPUT_DIRECTORY = $out"; echo "WARN_LOGFILE = $log" ) | doxygen - > /dev/null
count=$(grep -c . "$log" || true)
echo "doxygen $(doxygen --version): $count warning(s) on the public headers; reference in $out/html/index.html"
if [ "$count" -gt 0 ]; then
  cat "$log"
  [ "$check" -eq 1 ] && exit 1
fi
exit 0
