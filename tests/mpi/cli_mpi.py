#!/usr/bin/env python3
"""softhd distance under `mpiexec -n 2` against the one-process run: rho, A, B and the
gradient file equal to 1e-12 (relative) for methods exact, tree and nearest; one result
printed (rank 0's); bad input gives exit status != 0 and its error line once.

usage: cli_mpi.py SOFTHD MPIEXEC WORKDIR"""
import json
import os
import random
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
sys.exit(1 if failures else 0)
