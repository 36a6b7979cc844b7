#!/usr/bin/python3
"""softhd's scan clean-up against Open3D's on one synthetic scene (issue 32, item 3).

The scene: a box body [0,1]x[0,0.5]x[0,0.3] on the table z = 0; its top and sides sampled
uniformly (2500 points per unit area, noise +-0.002), the table [-1,2]x[-1,1.5] outside the
body's footprint at the same density, 3 % of all points uniform outliers in
[-1,2]x[-1,1.5]x[0,1] (the scene of tests/test_scan_cleanup.cpp, drawn with NumPy here).
Both tools get the same cloud and the same steps and parameters: crop to the body's box
inflated by 0.3 of its diagonal, the dominant plane (inlier distance 0.01, 1000 RANSAC
samples), statistical outliers (20 neighbours, ratio 2). Printed: for each tool, the body
points kept (those more than 0.01 above the table), the table and outlier points left, and
the seconds of each step.

usage: PYTHONPATH=build/python studies/bench_scan_cleanup.py [--seed S]
Skipped with one line when Open3D (Debian python3-open3d) is missing.
"""
import argparse
import sys
import time

import numpy as np

import softhd

try:
    import open3d as o3d
except ImportError:
    print("bench_scan_cleanup: skipped: open3d is not installed (Debian python3-open3d)")
    sys.exit(0)

LOWER, UPPER, MARGIN = np.array([0.0, 0.0, 0.0]), np.array([1.0, 0.5, 0.3]), 0.3
PLANE, K, RATIO = 0.01, 20, 2.0


def scene(rng):
    density, parts, labels = 2500, [], []

    def face(axis, at, lo, hi):
        n = int(density * np.prod(np.subtract(hi, lo)))
        q = np.empty((n, 3))
        q[:, axis] = at + rng.uniform(-0.002, 0.002, n)
        q[:, (axis + 1) % 3] = rng.uniform(lo[0], hi[0], n)
        q[:, (axis + 2) % 3] = rng.uniform(lo[1], hi[1], n)
        parts.append(q), labels.append(np.zeros(n, int))

    face(2, 0.3, (0, 0), (1, 0.5))
    face(0, 0.0, (0, 0), (0.5, 0.3))
    face(0, 1.0, (0, 0), (0.5, 0.3))
    face(1, 0.0, (0, 0), (0.3, 1.0))
    face(1, 0.5, (0, 0), (0.3, 1.0))
    n = int(density * 7.5)
    t = np.c_[rng.uniform(-1, 2, n), rng.uniform(-1, 1.5, n), rng.uniform(-0.002, 0.002, n)]
    t = t[~((t[:, 0] >= 0) & (t[:, 0] <= 1) & (t[:, 1] >= 0) & (t[:, 1] <= 0.5))]
    parts.append(t), labels.append(np.ones(len(t), int))
    m = int(0.03 * sum(len(p) for p in parts) / 0.97)
    parts.append(rng.uniform([-1, -1, 0], [2, 1.5, 1], size=(m, 3)))
    labels.append(np.full(m, 2))
    return np.concatenate(parts), np.concatenate(labels)


def run_softhd(points):
    seconds, idx = [], np.arange(len(points))
    for step in ("crop", "plane", "outliers"):
        start = time.perf_counter()
        p = points[idx]
        if step == "crop":
            kept = softhd.crop_to_box(p, LOWER, UPPER, MARGIN)
        elif step == "plane":
            kept = softhd.remove_dominant_plane(p, PLANE, iterations=1000)
        else:
            kept = softhd.remove_statistical_outliers(p, K, RATIO)
        seconds.append(time.perf_counter() - start)
        idx = idx[kept]
    return idx, seconds


def run_open3d(points):
    seconds, idx = [], np.arange(len(points))
    o3d.utility.random.seed(1)
    m = MARGIN * np.linalg.norm(UPPER - LOWER)
    for step in ("crop", "plane", "outliers"):
        cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(points[idx]))
        start = time.perf_counter()
        if step == "crop":
            box = o3d.geometry.AxisAlignedBoundingBox(LOWER - m, UPPER + m)
            kept = np.asarray(box.get_point_indices_within_bounding_box(cloud.points))
        elif step == "plane":
            _, inliers = cloud.segment_plane(PLANE, 3, 1000)
            kept = np.setdiff1d(np.arange(len(idx)), inliers)
        else:
            _, kept = cloud.remove_statistical_outlier(K, RATIO)
            kept = np.asarray(kept)
        seconds.append(time.perf_counter() - start)
        idx = idx[np.sort(kept)]
    return idx, seconds


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=2026)
    args = parser.parse_args()
    points, labels = scene(np.random.default_rng(args.seed))
    body = (labels == 0) & (points[:, 2] > PLANE)
    print(f"scene: {len(points)} points: {body.sum()} body (z > {PLANE}), "
          f"{(labels == 1).sum()} table, {(labels == 2).sum()} outliers")
    print("tool     body kept         table left  outliers left  seconds crop/plane/outliers")
    for name, run in (("softhd", run_softhd), ("open3d", run_open3d)):
        idx, sec = run(points)
        alive = np.zeros(len(points), bool)
        alive[idx] = True
        kept = (alive & body).sum()
        print(f"{name:8s} {kept:5d} ({kept / body.sum():6.2%})  {(alive & (labels == 1)).sum():6d}"
              f"       {(alive & (labels == 2)).sum():5d} of {(labels == 2).sum()}   "
              + " / ".join(f"{s:.4f}" for s in sec))


if __name__ == "__main__":
    main()
