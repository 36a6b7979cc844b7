#!/usr/bin/env python3
"""softhd distance under `mpiexec -n 2` against the one-process run: rho, A, B and the
gradient file equal to 1e-12 (relative) for methods exact, tree and nearest; one result
printed (rank 0's); bad input gives exit status != 0 and its error line once. softhd
optimise under `mpiexec -n 2 ... --state-backend petsc-mumps` against the one-process
cholmod run: the same history (J per iteration) and final control to 1e-8 relative, one
progress report; stopped after 2 iterations and resumed, the uninterrupted PETSc run (its
history as written, the control to 1e-10); an unknown backend refused; an error met by
rank 0 alone (it cannot write history.csv) ends the whole job with exit status 2 and its
line, instead of leaving rank 1 waiting for it (the job hung before).

usage: cli_mpi.py SOFTHD MPIEXEC WORKDIR"""
import json
import os
import random
import shutil
import subprocess
import sys

softhd, mpiexec, work = sys.argv[1], sys.argv[2], sys.argv[3]
os.makedirs(work, exist_ok=True)
MPI = [mpiexec, "-n", "2", "--oversubscribe"]
failures = []


def check(ok, what):
    if not ok:
        failures.append(what)
        print("FAIL:", what)


def write_cloud(path, n, seed, spread):
    rng = random.Random(seed)
    with open(path, "w") as f:
        for _ in range(n):
            f.write("%r %r %r %r\n" % (rng.random() * spread, rng.random(), rng.random(),
                                        0.5 + rng.random()))


def run(cmd):
    return subprocess.run(cmd, capture_output=True, text=True, timeout=240)


def read_rows(path):
    with open(path) as f:
        return [[float(v) for v in line.split()] for line in f if not line.startswith("#")]


def close(a, b):
    return abs(a - b) <= 1e-12 * abs(b)


moving, target = os.path.join(work, "moving.txt"), os.path.join(work, "target.txt")
write_cloud(moving, 2500, 1, 1.0)
write_cloud(target, 3000, 2, 1.3)
for method in ("exact", "tree", "nearest"):
    args = [softhd, "distance", moving, target, "--method", method, "--tol", "1e-3",
            "--threads", "1", "--json"]
    grads = {}
    if method != "nearest":
        for who in ("serial", "mpi"):
            grads[who] = os.path.join(work, "grad_%s_%s.txt" % (method, who))
    one = run(args + (["--grad", grads["serial"]] if grads else []))
    two = run(MPI + args + (["--grad", grads["mpi"]] if grads else []))
    check(one.returncode == 0, "%s: serial run failed: %s" % (method, one.stderr))
    check(two.returncode == 0, "%s: mpiexec run failed: %s" % (method, two.stderr))
    if one.returncode or two.returncode:
        continue
    check(two.stdout.count('"rho"') == 1, "%s: %d results printed under mpiexec"
          % (method, two.stdout.count('"rho"')))
    a, b = json.loads(one.stdout), json.loads(two.stdout)
    check(b["ranks"] == 2 and a["ranks"] == 1, "%s: ranks %s, %s" % (method, a["ranks"], b["ranks"]))
    for key in ("rho", "A", "B"):
        check(close(b[key], a[key]), "%s: %s %r (2 ranks) vs %r (1)" % (method, key, b[key], a[key]))
    if grads:
        ga, gb = read_rows(grads["serial"]), read_rows(grads["mpi"])
        check(len(ga) == len(gb) == 2500, "%s: gradient rows %d, %d" % (method, len(ga), len(gb)))
        scale = max(abs(v) for row in ga for v in row[3:])
        worst = max(abs(x - y) for ra, rb in zip(ga, gb) for x, y in zip(ra[3:], rb[3:]))
        check(worst <= 1e-12 * scale, "%s: gradient differs by %g (scale %g)" % (method, worst, scale))
    print("%s: rho %.17g on 1 rank, %.17g on 2" % (method, a["rho"], b["rho"]))

bad = run(MPI + [softhd, "distance", moving, os.path.join(work, "missing.txt")])
check(bad.returncode != 0, "missing file: exit status 0 under mpiexec")
check(bad.stderr.count("softhd distance: error: cannot open") == 1,
      "missing file: error line printed %d times" % bad.stderr.count("softhd distance: error"))

# softhd optimise on a small plate: PETSc (MUMPS) on 2 ranks against serial CHOLMOD.
SCENE = """{
  "name": "small_bend",
  "mesh": { "type": "box", "lower": [0, 0, 0], "upper": [2, 0.4, 0.2], "cells": [6, 1, 2], "order": 1 },
  "material": { "model": "mooney_rivlin", "a": 1e5, "b": 2e4, "c": 3e5 },
  "fibers": [1, 0, 0],
  "clamp": ["x0"],
  "control": { "space": "vertex", "lower": -1e5, "upper": 0, "initial": 0 },
  "target": { "kind": "arc", "angle": 0.6, "cells": [12, 2, 4] }
}"""
scene = os.path.join(work, "small_bend.json")
with open(scene, "w") as f:
    f.write(SCENE)


def history(out):
    with open(os.path.join(out, "history.csv")) as f:
        rows = [line.strip().split(",") for line in f][1:]
    return [float(r[2]) for r in rows]


def controls(out):
    return [row[-1] for row in read_rows(os.path.join(out, "control.csv"))]


opt = [softhd, "optimise", scene, "--threads", "1", "--vtu-every", "0", "--checkpoint-every", "1"]
outs = {who: os.path.join(work, "opt_" + who) for who in ("serial", "petsc", "resumed")}
for out in outs.values():
    shutil.rmtree(out, ignore_errors=True)
petsc = MPI + opt + ["--state-backend", "petsc-mumps"]
one = run(opt + ["--max-iter", "4", "--out", outs["serial"]])
two = run(petsc + ["--max-iter", "4", "--out", outs["petsc"]])
check(one.returncode == 0, "optimise: serial run failed: %s" % one.stderr)
check(two.returncode == 0, "optimise: petsc-mumps run failed: %s" % two.stderr)
if one.returncode == 0 and two.returncode == 0:
    check(two.stderr.count("softhd optimise small_bend") == 1,
          "optimise: %d progress headers under mpiexec" % two.stderr.count("softhd optimise"))
    ha, hb = history(outs["serial"]), history(outs["petsc"])
    check(len(ha) == len(hb) == 4, "optimise: %d and %d iterations" % (len(ha), len(hb)))
    worst = max(abs(a - b) / abs(a) for a, b in zip(ha, hb))
    check(worst <= 1e-8, "optimise: J differs by %g relative" % worst)
    ca, cb = controls(outs["serial"]), controls(outs["petsc"])
    scale = max(abs(v) for v in ca)
    worst_m = max(abs(a - b) for a, b in zip(ca, cb)) / scale
    check(len(ca) == len(cb) and worst_m <= 1e-8, "optimise: control differs by %g" % worst_m)
    with open(os.path.join(outs["petsc"], "summary.json")) as f:
        summary = json.load(f)
    check(summary["state_backend"] == "petsc-mumps" and summary["ranks"] == 2,
          "optimise: summary says %s on %s ranks" % (summary["state_backend"], summary["ranks"]))
    print("optimise: 4 iterations, J agrees to %.3e, control to %.3e" % (worst, worst_m))
    # Stopped after 2 iterations, resumed to 4: the uninterrupted PETSc run (history.csv's
    # values as written, 10 digits; the control to round-off, not bit for bit: two identical
    # runs of MUMPS on 2 ranks already differ at round-off, measured 9.28e-12 and 9.48e-12
    # from the serial control, and the resumed one differed by 3.6e-12).
    first = run(petsc + ["--max-iter", "2", "--out", outs["resumed"]])
    again = run(petsc + ["--max-iter", "4", "--out", outs["resumed"], "--resume"])
    check(first.returncode == 0 and again.returncode == 0,
          "optimise: interrupted/resumed runs failed: %s %s" % (first.stderr, again.stderr))
    if first.returncode == 0 and again.returncode == 0:
        with open(os.path.join(outs["petsc"], "history.csv")) as f:
            a = [line.split(",")[:10] for line in f]
        with open(os.path.join(outs["resumed"], "history.csv")) as f:
            b = [line.split(",")[:10] for line in f]
        check(a == b, "optimise: resumed history.csv differs from the uninterrupted run's")
        ca, cb = controls(outs["petsc"]), controls(outs["resumed"])
        worst_r = max(abs(x - y) for x, y in zip(ca, cb)) / max(abs(v) for v in ca)
        check(len(ca) == len(cb) and worst_r <= 1e-10,
              "optimise: resumed control differs by %g relative" % worst_r)
        print("optimise: resumed after 2 iterations, control within %.3e" % worst_r)
        # The checkpoint's fingerprint records the backend (tests/test_run_fields.cpp checks
        # every other field without PETSc): the serial backend does not resume the PETSc run.
        other = run(MPI + opt + ["--max-iter", "5", "--out", outs["resumed"], "--resume"])
        check(other.returncode != 0 and other.stderr.count("state differs (checkpoint "
                                                           "petsc-mumps, now (absent))") == 1,
              "optimise: a cholmod resume of the petsc-mumps run was not refused naming the "
              "state: %s" % other.stderr)
bad = run(MPI + opt + ["--out", outs["petsc"], "--state-backend", "mumps"])
check(bad.returncode != 0, "unknown backend: exit status 0 under mpiexec")
check(bad.stderr.count("--state-backend: unknown state backend 'mumps'") == 1,
      "unknown backend: error line printed %d times"
      % bad.stderr.count("--state-backend: unknown state backend"))
# rank 0 alone fails (history.csv is a directory it cannot replace); rank 1 goes on to the
# optimiser's first collective call. The job must end (within the 240 s of run()) with 2.
stuck = os.path.join(work, "opt_stuck")
shutil.rmtree(stuck, ignore_errors=True)
os.makedirs(os.path.join(stuck, "history.csv"))
try:
    bad = run(petsc + ["--max-iter", "2", "--out", stuck])
    check(bad.returncode == 2, "rank 0 failing alone: exit status %d, not 2" % bad.returncode)
    check(bad.stderr.count("softhd optimise: error: cannot write") == 1,
          "rank 0 failing alone: its error line printed %d times"
          % bad.stderr.count("softhd optimise: error"))
except subprocess.TimeoutExpired:
    check(False, "rank 0 failing alone: the job hung (killed after 240 s)")
sys.exit(1 if failures else 0)
