#!/usr/bin/env bash
# Is the bending shape error's plateau (docs/benchmarks.md, bench_resolution: RMS ~0.07 on
# every target and mesh) a property of the 180° arc target or of the functional / optimiser?
#
# Runs the bending scene on two state meshes (Q2 25x3x1 and 50x5x2) against two targets:
#   arc           the scene's own target, the analytic arc (not known to be an equilibrium)
#   manufactured  the equilibrium for the known control m†(X) = -2.6e4 X3/0.1 (a curl of about
#                 180°) solved on the 2x finer mesh 100x10x4: reachable by construction, up
#                 to the coarse mesh's discretisation error
# and writes a table (shape error against each target's known map, ρ̃/matched floor, and for
# the manufactured target ‖m − m†‖/‖m†‖) to OUT_DIR/reachability.md. About 16 minutes on 2 cores.
#
# Usage: scripts/study_bending_reachability.sh [SOFTHD_BINARY] [OUT_DIR] [MAX_ITER]
#        (defaults: build/apps/softhd, results/bending_reachability, 100)
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
softhd=$(realpath "${1:-build/apps/softhd}")
out=${2:-results/bending_reachability}
max_iter=${3:-100}
m_top=-2.6e4  # m† at the top face X3 = 0.1 (linear in X3, 0 at the bottom)
mkdir -p "$out"
out=$(realpath "$out")
cd "$out"

# Scenes derived from data/scenes/bending.json: the fine mesh, and each state mesh with
# either target.
/usr/bin/python3 - "$here/data/scenes/bending.json" <<'EOF'
import json, sys
base = json.load(open(sys.argv[1]))
fine = dict(base, name="bending_fine_100x10x4")
fine["mesh"] = dict(base["mesh"], cells=[100, 10, 4])
del fine["target"]
json.dump(fine, open("fine.json", "w"), indent=1)
for cells in ([25, 3, 1], [50, 5, 2]):
    tag = "x".join(map(str, cells))
    for kind in ("arc", "manufactured"):
        s = dict(base, name=f"{kind}_{tag}")
        s["mesh"] = dict(base["mesh"], cells=cells)
        if kind == "manufactured":
            s["target"] = {"kind": "cloud", "file": "target_fine.ply", "solved_on": "fine.json"}
        json.dump(s, open(f"{kind}_{tag}.json", "w"), indent=1)
EOF

# The manufactured target: m† at every control vertex of the fine mesh, its equilibrium.
"$softhd" forward fine.json --write-control-nodes fine_nodes.txt
awk -v m_top="$m_top" '/^#/ {next} NF {printf "%s %s %s %.17g\n", $1, $2, $3, m_top * $3 / 0.1}' \
  fine_nodes.txt >m_dagger.txt
"$softhd" forward fine.json --control m_dagger.txt --coarse-levels 1 --out fine_state \
  --write-cloud target_fine.ply --probe 10,1,0.05 >fine_state.log 2>&1

for tag in 25x3x1 50x5x2; do
  for kind in arc manufactured; do
    echo "== $kind $tag ($max_iter iterations)" >&2
    "$softhd" optimise "${kind}_${tag}.json" --out "${kind}_${tag}" --max-iter "$max_iter" \
      --quiet >"${kind}_${tag}.log" 2>&1
  done
done

/usr/bin/python3 - "$m_top" <<'EOF' | tee reachability.md
import json, sys
import numpy as np
print(f"| state mesh | target | ρ̃/matched floor | shape err max | shape err RMS | ‖m − m†‖/‖m†‖ | iterations | s |")
print("|---|---|---|---|---|---|---|---|")
for tag in ("25x3x1", "50x5x2"):
    for kind in ("arc", "manufactured"):
        s = json.load(open(f"{kind}_{tag}/summary.json"))
        merr = "–"
        if kind == "manufactured":
            c = np.loadtxt(f"{kind}_{tag}/control.csv")
            m_dagger = float(sys.argv[1]) * c[:, 2] / 0.1
            merr = f"{np.linalg.norm(c[:, 3] - m_dagger) / np.linalg.norm(m_dagger):.3g}"
        print(f"| {tag} | {kind} | {s['rho_final_over_floor']:.3g} | {s['shape_error_max']:.3g} "
              f"| {s['shape_error_rms']:.3g} | {merr} | {s['iterations']} | {s['seconds']:.0f} |")
EOF
