#!/usr/bin/env bash
# Regenerates data/targets/finger_target.ply, the finger scene's target (issue 30): the
# equilibrium of the finger for the known control m*(X) = -1.5 X3, solved on a mesh 2x finer (data/targets/finger_fine.json); its deformed
# nodes, in node order, with their deformed volumes.
# Usage: scripts/make_finger_target.sh [SOFTHD_BINARY]   (default build/apps/softhd)
set -euo pipefail
cd "$(dirname "$0")/.."
softhd=${1:-build/apps/softhd}
scene=data/targets/finger_fine.json
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$softhd" forward "$scene" --write-control-nodes "$work/nodes.txt"
# Linear in X3, so both meshes' P1 vertex controls represent it exactly.
awk '/^#/ {next} NF {printf "%s %s %s %.17g\n", $1, $2, $3, -1.5 * $3}' \
  "$work/nodes.txt" >"$work/m_star.txt"
"$softhd" forward "$scene" --control "$work/m_star.txt" --out "$work" \
  --write-cloud data/targets/finger_target.ply --probe 60,6,11.5 --probe 60,6,0
