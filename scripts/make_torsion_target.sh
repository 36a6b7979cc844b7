#!/usr/bin/env bash
# Regenerates data/targets/torsion_target.ply, the torsion scene's target (issue 5, docs/formulation.md §5.2):
# the equilibrium of the torsion beam for the known control m*(X) = -1e6 * X3 / 2, solved on a
# mesh 2x finer in each direction (data/targets/torsion_fine.json); its deformed nodes, in
# node order, with their deformed volumes V_i = ∫ N_i J dX.
# Grid sequencing (--coarse-levels 2: 25x2x1, then 50x4x2, then 100x8x4) makes it ~1 minute.
# Usage: scripts/make_torsion_target.sh [SOFTHD_BINARY]   (default build/apps/softhd)
set -euo pipefail
cd "$(dirname "$0")/.."
softhd=${1:-build/apps/softhd}
scene=data/targets/torsion_fine.json
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$softhd" forward "$scene" --write-control-nodes "$work/nodes.txt"
# m*(X) = -1e6 X3/2 at every control vertex (linear in X3, so both meshes represent it exactly).
awk '/^#/ {next} NF {printf "%s %s %s %.17g\n", $1, $2, $3, -1e6 * $3 / 2}' \
  "$work/nodes.txt" >"$work/m_star.txt"
"$softhd" forward "$scene" --control "$work/m_star.txt" --out "$work" \
  --coarse-levels 2 --write-cloud data/targets/torsion_target.ply --probe 50,4,2 --probe 50,0,0
