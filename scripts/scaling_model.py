#!/usr/bin/env python3
"""The model of docs/scaling.md §3: time and memory per rank of one distance evaluation
(value and gradient) of a moving cloud of N points against a scan of M points on K ranks,
from the per-rank costs and message volumes bench_mpi_sums measured on this machine.

    scripts/scaling_model.py EXACT_CSV TREE_CSV [--n 1e6] [--m 1e9]

EXACT_CSV, TREE_CSV: bench_mpi_sums --grad --csv output with an exact row and a tree row.
Assumptions (stated in docs/scaling.md, constants below): one rank per core; the tree's
work per point at fixed tau and density is the measured one (linear in N + M); the part of
an evaluation that is not split (measured through the 2-rank CPU speed-up, Amdahl) stays
replicated; the reductions are MPI_Allreduce of the measured bytes per point, costed as a
ring (2 (K-1)/K bytes / bandwidth + 2 log2 K latency); memory per rank is the inventory of
the replicated arrays (docs/scaling.md §3) in bytes per point.
"""
import argparse
import csv
import math

BANDWIDTH = 10e9  # bytes/s of the allreduce per rank (a 100 Gb/s class link; docs/scaling.md §3)
LATENCY = 2e-6  # seconds per message step
BYTES_PER_TARGET_POINT = 255  # inventory, docs/scaling.md §3 (replicated on every rank)
BYTES_PER_MOVING_POINT = 290  # inventory with the gradient, docs/scaling.md §3


def row(path, method):
    with open(path) as f:
        for r in csv.DictReader(f):
            if r["method"] == method:
                return {k: (v if k == "method" else float(v)) for k, v in r.items()}
    raise SystemExit("%s: no %s row" % (path, method))


def serial_fraction(cpu_speedup):
    # Amdahl on 2 ranks: s = 1 / (f + (1 - f) / 2)  =>  f = 2 / s - 1
    return max(0.0, 2.0 / cpu_speedup - 1.0)


def allreduce_seconds(nbytes, k):
    return 2.0 * (k - 1) / k * nbytes / BANDWIDTH + 2.0 * math.log2(k) * LATENCY


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("exact_csv")
    ap.add_argument("tree_csv")
    ap.add_argument("--n", type=float, default=1e6)
    ap.add_argument("--m", type=float, default=1e9)
    a = ap.parse_args()
    ex, tr = row(a.exact_csv, "exact"), row(a.tree_csv, "tree")
    pair_rate = 2.0 * ex["n"] * ex["m"] / ex["cpu_1"]  # two passes (value + gradient)
    tree_per_point = tr["cpu_1"] / (tr["n"] + tr["m"])
    bytes_per_point = tr["bytes_per_rank"] / (tr["n"] * 9 + tr["m"] * 2)  # 8: doubles
    f_exact, f_tree = serial_fraction(ex["cpu_speedup"]), serial_fraction(tr["cpu_speedup"])
    n, m = a.n, a.m
    t1_exact = 2.0 * n * m / pair_rate
    t1_tree = tree_per_point * (n + m)
    nbytes = bytes_per_point * (9 * n + 2 * m)
    mem = (BYTES_PER_TARGET_POINT * m + BYTES_PER_MOVING_POINT * n) / 1e9
    mem_split = lambda k: (BYTES_PER_TARGET_POINT * m / k + BYTES_PER_MOVING_POINT * n) / 1e9
    print("measured: exact %.3g pairs/s per core (serial part %.3f), tree tau %g %.3g s per point "
          "(serial part %.3f), %.1f bytes reduced per point-double"
          % (pair_rate, f_exact, tr["tau"], tree_per_point, f_tree, bytes_per_point))
    print("N = %.0e moving, M = %.0e scan points; one evaluation with the gradient; %.0f GB per rank"
          % (n, m, mem))
    print("| ranks K | exact: compute | tree: compute | reductions | tree total | tree speed-up | memory per rank (replicated / scan split) |")
    print("|---|---|---|---|---|---|---|")
    for k in (1, 8, 32, 128, 512):
        ce = t1_exact * (f_exact + (1 - f_exact) / k)
        ct = t1_tree * (f_tree + (1 - f_tree) / k)
        comm = allreduce_seconds(nbytes, k) if k > 1 else 0.0
        print("| %d | %s | %s | %s | %s | %.1f | %.0f GB / %.1f GB |" % (
            k, fmt(ce), fmt(ct), fmt(comm), fmt(ct + comm), t1_tree / (ct + comm), mem, mem_split(k)))


def fmt(s):
    if s >= 86400:
        return "%.1f d" % (s / 86400)
    if s >= 3600:
        return "%.1f h" % (s / 3600)
    if s >= 60:
        return "%.1f min" % (s / 60)
    return "%.2g s" % s


if __name__ == "__main__":
    main()
