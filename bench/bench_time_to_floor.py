#!/usr/bin/python3
"""Time to the floor (issue 31): `softhd optimise` on the reference scenes, one run at a time,
each from the run's own clock (history.csv's seconds, over all levels).

For each case: the first accepted iteration on the user's mesh (level 0) at which rho / the
matched floor fell to 3, 1.25, 1.05 and 1.01 (iteration and seconds; the level-0 start, which a
multilevel run may already have below a threshold, is not in history.csv, so the first level-0
iterate is the earliest time counted), the ratio at the end, the time per level and per stage
(summary.json), and why the run stopped. The bending case runs with the default levels (3: the
plate, 25x5x1 and 13x3x1), with --levels 2 (the default before the rounded halving) and with
--levels 1 one after the other, so their times are a ratio from one benchmark run.

  bench/bench_time_to_floor.py BUILD_DIR --csv OUT.csv [--quick]

--quick: the first case for one iteration per level (the smoke variant CTest runs), not a
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

# (name, scene, extra flags, limit flags): the goals are for the defaults; --levels 2 and
# --levels 1 are the runs the defaults replaced.
CASES = [
    ("bending", "data/scenes/bending.json", [], ["--max-seconds", "150"]),
    ("bending --levels 2", "data/scenes/bending.json", ["--levels", "2"], ["--max-seconds", "150"]),
    ("bending --levels 1", "data/scenes/bending.json", ["--levels", "1"], ["--max-seconds", "150"]),
    ("torsion", "data/scenes/torsion.json", [], ["--max-iter", "120", "--max-seconds", "300"]),
]


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
    row = {"case": name, "scene": scene, "flags": " ".join(extra + limits)}
    for k in THRESHOLDS:
        hit = first_reached(rows, k)
        row[f"it_to_{k:g}"] = hit[0] if hit else ""
        row[f"s_to_{k:g}"] = f"{hit[1]:.4g}" if hit else ""
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
    a = p.parse_args()
    cli = os.path.join(a.build, "apps", "softhd")
    if not os.access(cli, os.X_OK):
        sys.exit(f"bench_time_to_floor: no softhd tool at {cli}")
    rows = [run_case(cli, *c, a.quick) for c in (CASES[:1] if a.quick else CASES)]
    with open(a.csv, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


if __name__ == "__main__":
    main()
