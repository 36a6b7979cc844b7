#!/usr/bin/env bash
# The main job (make demo): optimise the bending scene (docs/formulation.md §5.1) against its half-circle
# target, then draw the convergence history and the final shape against the target.
set -euo pipefail
build=${1:-build}
cd "$(dirname "$0")/.."
out=results/bending
"$build/apps/softhd" optimise data/scenes/bending.json --out "$out" --max-iter 200 \
  --max-seconds 280 --vtu-every 25
echo
echo "Look at: $out/summary.json (numbers), $out/convergence.png and $out/shape.png"
echo "(pictures), $out/body.pvd and $out/target.vtu in ParaView."
