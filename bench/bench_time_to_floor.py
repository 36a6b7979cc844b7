#!/usr/bin/python3
"""Time to the floor: `softhd optimise` on the reference scenes with MMA (the paper's method) and
with the trust-region Newton–CG side by side, one run at a time, each from the run's own clock
(history.csv's seconds, over all levels).

For each case: the first accepted iteration on the user's mesh (level 0) at which rho / the
matched floor fell to 3, 1.25, 1.05 and 1.01 (iteration and seconds; the level-0 start, which a
multilevel run may already have below a threshold, is not in history.csv, so the first level-0
iterate is the earliest time counted); the projected-gradient norm relative to the first level-0
iterate's and the first time it fell below 1e-2 and 1e-4 of it; the ratio at the end; for newton
the CG iterations per Newton step; the time per level and per stage (summary.json); and why the
run stopped. With --mesh-independence, also newton on one level (--levels 1) on the bending
plate at 25x5x1, 50x5x2 (the scene's) and 100x10x2 cells (scene files written to a temporary
folder) until the projected gradient falls by 1e-4 or the time limit (12 more minutes: not part
of make bench, which must stay within an hour).

  bench/bench_time_to_floor.py BUILD_DIR --csv OUT.csv [--quick] [--mesh-independence]

--quick: the first two cases (bending with MMA and newton) for one iteration per level (the smoke variant CTest runs), not a
measurement.
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
THRESHOLDS = (3.0, 1.25, 1.05, 1.01)

PG_THRESHOLDS = (1e-2, 1e-4)
BENDING = "data/scenes/bending.json"

# (name, scene, extra flags, limit flags): each scene with MMA and with newton, then newton on the
# plate at three resolutions ("cells" replaces the scene's mesh cells).
CASES = [
    ("bending mma", BENDING, ["--algorithm", "mma"], ["--max-seconds", "150"]),
    ("bending newton", BENDING, ["--algorithm", "newton"], ["--max-seconds", "150"]),
    ("torsion mma", "data/scenes/torsion.json", ["--algorithm", "mma"],
     ["--max-iter", "120", "--max-seconds", "100"]),
    ("torsion newton", "data/scenes/torsion.json", ["--algorithm", "newton"],
     ["--max-iter", "120", "--max-seconds", "100"]),
    ("finger mma", "data/scenes/finger.json", ["--algorithm", "mma"], ["--max-seconds", "90"]),
    ("finger newton", "data/scenes/finger.json", ["--algorithm", "newton"],
     ["--max-seconds", "90"]),
]
MESH_CASES = [((25, 5, 1), 120), ((50, 5, 2), 200), ((100, 10, 2), 400)]


def mesh_cases(tmp):
    """The newton --levels 1 cases on the plate at each of MESH_CASES' cells."""
    with open(os.path.join(ROOT, BENDING)) as f:
        scene = json.load(f)
    cases = []
    for cells, seconds in MESH_CASES:
        scene["mesh"]["cells"] = list(cells)
        scene["name"] = "bending_%dx%dx%d" % cells
        path = os.path.join(tmp, scene["name"] + ".json")
        with open(path, "w") as f:
            json.dump(scene, f)
        cases.append(("bending %dx%dx%d newton --levels 1" % cells, path,
                      ["--algorithm", "newton", "--levels", "1"],
                      ["--max-seconds", str(seconds)]))
    return cases


def first_reached(rows, k):
    """(iteration, seconds) of the first level-0 row with rho/floor <= k, or None."""
    for r in rows:
        if r["level"] == "0" and r["rho_over_floor"] and float(r["rho_over_floor"]) <= k:
            return int(r["iteration"]), float(r["seconds"])
    return None


def run_case(cli, name, scene, extra, limits, quick):
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "run")
        limits = ["--max-iter", "1", "--coarse-iterations", "1"] if quick else limits
        cmd = [cli, "optimise", os.path.join(ROOT, scene), "--out", out, "--quiet",
               "--vtu-every", "0"] + extra + limits
        print("==", name, ":", " ".join(cmd), flush=True)
        subprocess.run(cmd, check=True)
        with open(os.path.join(out, "history.csv")) as f:
            rows = list(csv.DictReader(f))
        with open(os.path.join(out, "summary.json")) as f:
            s = json.load(f)
    row = {"case": name, "scene": os.path.basename(scene), "flags": " ".join(extra + limits)}
    for k in THRESHOLDS:
        hit = first_reached(rows, k)
        row[f"it_to_{k:g}"] = hit[0] if hit else ""
        row[f"s_to_{k:g}"] = f"{hit[1]:.4g}" if hit else ""
    level0 = [r for r in rows if r["level"] == "0"]
    pg0 = float(level0[0]["projected_gradient_norm"]) if level0 else float("nan")
    for k in PG_THRESHOLDS:
        hit = next(((int(r["iteration"]), float(r["seconds"])) for r in level0
                    if float(r["projected_gradient_norm"]) <= k * pg0), None)
        row[f"it_to_pg_{k:g}"] = hit[0] if hit else ""
        row[f"s_to_pg_{k:g}"] = f"{hit[1]:.4g}" if hit else ""
    row["pg_final_over_first"] = (
        f"{float(level0[-1]['projected_gradient_norm']) / pg0:.3g}" if level0 else "")
    cg = [int(r["cg_iterations"]) for r in level0 if r.get("cg_iterations")]
    row["cg_per_step"] = f"{sum(cg) / len(cg):.3g}" if cg else ""
    levels = s.get("levels") or [{"level": 0, "iterations": s["iterations"],
                                  "seconds": s["seconds"]}]
    row["levels"] = "; ".join(f"level {l['level']}: {l['iterations']} it {l['seconds']:.3g} s"
                              for l in levels)
    row["iterations"] = s["iterations"]
    row["evaluations"] = s["evaluations"]
    row["newton_iterations"] = s["newton_iterations"]
    row["seconds"] = f"{s['seconds']:.4g}"
    for stage in ("state", "distance", "adjoint"):
        row[f"seconds_{stage}"] = f"{s['seconds_' + stage]:.4g}"
    row["ratio_final"] = f"{s['rho_final_over_floor']:.4g}"
    row["termination"] = s["termination"]
    print(json.dumps(row), flush=True)
    return row


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("build")
    p.add_argument("--csv", required=True)
    p.add_argument("--quick", action="store_true")
    p.add_argument("--mesh-independence", action="store_true")
    a = p.parse_args()
    cli = os.path.join(a.build, "apps", "softhd")
    if not os.access(cli, os.X_OK):
        sys.exit(f"bench_time_to_floor: no softhd tool at {cli}")
    with tempfile.TemporaryDirectory() as tmp:
        cases = CASES[:2] if a.quick else CASES
        if a.mesh_independence:
            cases = cases + mesh_cases(tmp)
        rows = [run_case(cli, *c, a.quick) for c in cases]
    with open(a.csv, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


if __name__ == "__main__":
    main()
