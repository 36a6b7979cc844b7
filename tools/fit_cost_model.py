#!/usr/bin/env python3
"""Fits the dual tree's cost model (docs/tree_tolerance.md §8) to a ladder run with
`bench_hausdorff --no-fallback` (every pass planned), in units of one pair of the exact
backend measured in the same run:

    run  = plan+run seconds − plan seconds ≈ a·near_pairs + b·far_kernel + c·far_basis
    plan = plan seconds                    ≈ v·node_pairs + x·bound_axes + q·(N + M)

Least squares on each row divided by its all-pairs work 2·N·M, so that every case
weighs the same. Prints the weights and, per case, measured against modelled work.
By default only the value rows are fitted: there both passes sum S alone, the unit of
the library's weights (dual_tree_internal.hpp; passes with gradient sums divide the
basis and planning weights by kGradPairCost).

    tools/fit_cost_model.py LADDER.csv [--min-n 3000] [--mode value|value+grad|all]
"""
import argparse
import csv

import numpy as np


def load(path, min_n):
    rows = list(csv.DictReader(open(path)))
    exact = {(r["shape"], r["N"], r["mode"]): float(r["sums_s"])
             for r in rows if r["method"] == "exact"}
    out = []
    for r in rows:
        key = (r["shape"], r["N"], r["mode"])
        if r["method"] != "tree" or key not in exact or int(r["N"]) < min_n:
            continue
        if int(r["exact_passes"]) > 0:
            raise SystemExit("%s: a pass fell back; run bench_hausdorff with --no-fallback" % path)
        nm = 2.0 * float(r["N"]) * float(r["M"])
        unit = exact[key] / nm  # seconds per pair of the exact backend
        d = {k: float(r[k]) / nm for k in ("near_pairs", "far_kernel", "far_basis",
                                           "node_pairs", "bound_axes")}
        d["points"] = (float(r["N"]) + float(r["M"])) / nm
        d["plan"] = float(r["plan_s"]) / unit / nm
        d["run"] = float(r["sums_s"]) / unit / nm - d["plan"]
        d["case"] = "%s %s %s %s" % (r["shape"], r["N"], r["tau"], r["mode"])
        out.append(d)
    return out


def fit(data, cols, target):
    A = np.array([[d[c] for c in cols] for d in data])
    y = np.array([d[target] for d in data])
    w, *_ = np.linalg.lstsq(A, y, rcond=None)
    return w, A @ w


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv")
    ap.add_argument("--min-n", type=int, default=3000)
    ap.add_argument("--mode", default="value", choices=["value", "value+grad", "all"])
    a = ap.parse_args()
    data = [d for d in load(a.csv, a.min_n)
            if a.mode == "all" or d["case"].endswith(" " + a.mode)]
    run_cols = ["near_pairs", "far_kernel", "far_basis"]
    plan_cols = ["node_pairs", "bound_axes", "points"]
    wr, pr = fit(data, run_cols, "run")
    wp, pp = fit(data, plan_cols, "plan")
    print("run weights:  " + ", ".join("%s %.3g" % c for c in zip(run_cols, wr)))
    print("plan weights: " + ", ".join("%s %.3g" % c for c in zip(plan_cols, wp)))
    print("%-32s %6s %6s %6s %6s %6s" % ("case (work / all pairs)", "run", "plan", "total",
                                         "model", "ratio"))
    ratios = []
    for d, r, p in zip(data, pr, pp):
        total = d["run"] + d["plan"]
        ratios.append(total / (r + p))
        print("%-32s %6.2f %6.2f %6.2f %6.2f %6.2f" % (d["case"], d["run"], d["plan"], total,
                                                      r + p, ratios[-1]))
    print("measured / modelled: %.2f … %.2f over %d cases" % (min(ratios), max(ratios),
                                                              len(ratios)))


if __name__ == "__main__":
    main()
