#!/usr/bin/env python3
"""Two PLY scans compared at several resolutions, with a plot.

    python3 examples/compare_scans.py [SCAN_A.ply SCAN_B.ply] [--sizes 500 2000 8000] [--out DIR]

Without scans, A is data/targets/torsion_target.ply (the deformed torsion body, 30753 points)
and B a re-scan of it made here: a random 70 % of its points, rotated by 0.5 degrees about the
clamp's axis and perturbed by 2 mm noise. Each scan is subsampled to every size (volumes scaled
so that each subset keeps the scan's total volume), and the regularised distance rho_H, the
exact Hausdorff distance and the floor rho_H(A_n, A_n) are plotted against the size. Both
distances fall as the samples get denser: between sparse samples of nearly the same body
they measure the sampling gaps more than the difference of the shapes, which is why results
are judged against the floor of the same resolution.
"""

import argparse
import os
import sys

import numpy as np

import softhd

HERE = os.path.dirname(os.path.abspath(__file__))


def rescan(points, volumes, rng, out):
    """A second scan of the same body: a subset, slightly rotated, with noise (written as PLY)."""
    keep = rng.random(len(points)) < 0.7
    p = points[keep]
    t = np.radians(0.5)
    R = np.array([[1, 0, 0], [0, np.cos(t), -np.sin(t)], [0, np.sin(t), np.cos(t)]])
    p = p @ R.T + rng.normal(scale=0.002, size=p.shape)
    softhd.write_cloud(out, p, volumes[keep] / 0.7)
    return out


def subsample(points, volumes, n, rng):
    """n of the points (all if fewer), volumes scaled to keep the total."""
    if n >= len(points):
        return points, volumes
    idx = rng.choice(len(points), size=n, replace=False)
    v = volumes[idx]
    return points[idx], v * (volumes.sum() / v.sum())


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scans", nargs="*", help="two PLY (or text) cloud files")
    ap.add_argument("--sizes", type=int, nargs="+", default=[500, 1000, 2000, 4000, 8000])
    ap.add_argument("--out", default="compare_scans")
    ap.add_argument("--eps", type=float, default=1e-3)
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    rng = np.random.default_rng(1)
    if len(args.scans) == 2:
        path_a, path_b = args.scans
    elif not args.scans:
        path_a = os.path.join(HERE, "..", "data", "targets", "torsion_target.ply")
        path_b = rescan(*softhd.read_cloud(path_a), rng, os.path.join(args.out, "rescan.ply"))
    else:
        sys.exit("give two scans, or none for the built-in pair")
    A, VA = softhd.read_cloud(path_a)
    B, VB = softhd.read_cloud(path_b)
    print(f"A: {path_a} ({len(A)} points)\nB: {path_b} ({len(B)} points)")
    print(f"{'n':>7} {'rho_H':>12} {'floor':>12} {'Hausdorff':>12} {'seconds':>8}")
    rows = []
    for n in args.sizes:
        a, va = subsample(A, VA, n, rng)
        b, vb = subsample(B, VB, n, rng)
        r = softhd.distance(a, b, va, vb, eps=args.eps, method="tree")
        floor = softhd.distance(a, a, va, va, eps=args.eps, method="tree").rho
        h = softhd.hausdorff_nearest(a, b).rho
        rows.append((len(a), r.rho, floor, h))
        print(f"{len(a):7d} {r.rho:12.6g} {floor:12.6g} {h:12.6g} {r.seconds:8.3f}")
    plot(np.array(rows), os.path.join(args.out, "compare_scans.png"))


def plot(rows, path):
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("(no plot: needs python3-matplotlib)")
        return
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.loglog(rows[:, 0], rows[:, 1], "o-", label=r"$\tilde\rho_H$(A, B)")
    ax.loglog(rows[:, 0], rows[:, 2], "s--", label=r"floor $\tilde\rho_H$(A, A)")
    ax.loglog(rows[:, 0], rows[:, 3], "^-", label="exact Hausdorff")
    ax.set_xlabel("points per scan")
    ax.set_ylabel("distance")
    ax.legend()
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
