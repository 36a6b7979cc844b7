#!/usr/bin/env python3
"""Forward solve, softhd against FEniCS on the same case and mesh, in one run (issue 12).

The torsion beam of data/scenes/torsion.json (Q2 50x4x2, 13 635 dofs) from rest under a
uniform m = -5e5: `softhd forward` as it runs by default (grid sequencing: the 25x2x1 mesh
solved first, then Newton with PCG on a kept Cholesky factorisation on the fine mesh), the
same without grid sequencing (`--coarse-levels 0`, "from-rest"), the classical variant
that factorises every tangent (from rest), and the independent FEniCS 2019 solver
bench/peers/fenics_forward.py (Q2 hexahedra, exact Newton, MUMPS, load stepping), run
alternately --repeats times. Prints a CSV: code, repeat, solve seconds (FEniCS: its
wall_solve_s, JIT excluded; softhd: its Newton seconds, coarse levels included), Newton
iterations (coarse+fine), factorisations (all levels),
the displacement at the probes and the largest difference from FEniCS's.

FEniCS needs Debian's python3-dolfin (`apt-get install python3-dolfin`, about 1 GB); when
it is missing the FEniCS rows are skipped with one line on stderr and only softhd runs.

  bench/bench_forward_fenics.py BUILD_DIR [--repeats N] [--csv FILE] [--threads T]
"""
import argparse
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
PROBES = [(50.0, 2.0, 1.0), (50.0, 0.0, 0.0), (25.0, 2.0, 1.0)]
M0 = -5e5


def have_dolfin():
    r = subprocess.run(["/usr/bin/python3", "-c", "import dolfin"], capture_output=True)
    return r.returncode == 0


def run_softhd(build, threads, classical, from_rest=False):
    cmd = [os.path.join(build, "apps", "softhd"), "forward",
           os.path.join(ROOT, "data", "scenes", "torsion.json"), "--control-uniform", str(M0),
           "--json", "--threads", str(threads), "--out", os.path.join(build, "bench-forward")]
    if classical:
        cmd.append("--factorize-every-step")
    if from_rest:  # no grid sequencing: the fine Newton solve starts from rest
        cmd += ["--coarse-levels", "0"]
    for p in PROBES:
        cmd += ["--probe", "%g,%g,%g" % p]
    out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    d = json.loads(out)
    coarse = d["coarse_levels"]
    return {"seconds": d["seconds_solve"],
            "newton_iterations": "%d+%d" % (sum(c["newton_iterations"] for c in coarse),
                                            d["newton_iterations"]) if coarse
            else d["newton_iterations"],
            "factorizations": sum(c["factorizations"] for c in coarse) + d["factorizations"],
            "u": [pr["u"] for pr in d["probes"]]}


def run_fenics():
    cmd = ["/usr/bin/python3", os.path.join(HERE, "peers", "fenics_forward.py"), "torsion",
           "--elem", "Q2", "--n", "50,4,2", "--from-scratch", "--json", "--m0", str(M0)]
    out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    d = json.loads(out[out.index("{"):])  # FFC's JIT lines come first on a cold cache
    key = lambda p: "(%d, %d, %d)" % p
    return {"seconds": d["wall_solve_s"], "newton_iterations": d["newton_iterations"],
            "factorizations": d["factorizations"], "u": [d["points"][key(p)] for p in PROBES]}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("build")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--csv")
    a = ap.parse_args()
    fenics = have_dolfin()
    if not fenics:
        print("bench_forward_fenics: python3-dolfin is not installed; FEniCS skipped "
              "(apt-get install python3-dolfin)", file=sys.stderr)
    else:
        run_fenics()  # warm the JIT cache outside the timed runs
    rows = []
    for r in range(a.repeats):
        results = [("softhd", run_softhd(a.build, a.threads, False)),
                   ("softhd-from-rest", run_softhd(a.build, a.threads, False, True)),
                   ("softhd-classical", run_softhd(a.build, a.threads, True, True))]
        if fenics:
            results.append(("fenics", run_fenics()))
        ref = dict(results).get("fenics")
        for code, res in results:
            diff = "" if ref is None else max(
                abs(x - y) for pu, pf in zip(res["u"], ref["u"]) for x, y in zip(pu, pf))
            rows.append([code, r, res["seconds"], res["newton_iterations"],
                         res["factorizations"], res["u"][0][0], res["u"][0][1], res["u"][0][2],
                         diff])
    header = ("code,repeat,solve_seconds,newton_iterations,factorizations,u1_probe,u2_probe,"
              "u3_probe,max_abs_diff_vs_fenics")
    lines = [header] + [",".join(str(v) for v in row) for row in rows]
    text = "\n".join(lines) + "\n"
    sys.stdout.write(text)
    if a.csv:
        with open(a.csv, "w") as f:
            f.write(text)
    best = {}
    for row in rows:
        best[row[0]] = min(best.get(row[0], 1e300), row[2])
    if "fenics" in best:
        for code in ("softhd", "softhd-from-rest", "softhd-classical"):
            print("# %s: best %.3f s, FEniCS best %.3f s: %.2fx faster"
                  % (code, best[code], best["fenics"], best["fenics"] / best[code]))


if __name__ == "__main__":
    main()
