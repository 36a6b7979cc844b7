#!/usr/bin/python3
"""Issue 32's exact-subset goal: a scan that is an exact, rigidly moved subset of the body's
points, from --poses random rotations (uniform quaternions, seeded) and translations (normal,
L each): the largest rotation error (rad) and translation error / L of softhd.align.

The body: --body-points random points of the deformed finger (data/targets/finger_target.ply);
the scan: every other body point, moved by P⁻¹.

  bench/align_exact_subset.py BUILD_DIR [--poses N] [--body-points N] [--threads T]
"""
import argparse
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
BODY = os.path.join(os.path.dirname(HERE), "data", "targets", "finger_target.ply")


def rotation(q):
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("build")
    ap.add_argument("--poses", type=int, default=100)
    ap.add_argument("--body-points", type=int, default=2000)
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args()
    sys.path.insert(0, os.path.join(os.path.abspath(a.build), "python"))
    import softhd
    fine, _ = softhd.read_cloud(BODY)
    rng = np.random.default_rng(7)
    body = fine[np.sort(rng.choice(len(fine), a.body_points, replace=False))]
    L = float(np.linalg.norm(body.max(0) - body.min(0)))
    worst_r = worst_t = 0.0
    t0 = time.perf_counter()
    for k in range(a.poses):
        R, t = rotation(rng.normal(size=4)), rng.normal(size=3) * L
        scan = (body[::2] - t) @ R  # P⁻¹ y = Rᵀ (y − t)
        r = softhd.align(body, scan, threads=a.threads)
        M = r["matrix"]
        er = float(np.arccos(np.clip((np.trace(M[:3, :3] @ R.T) - 1) / 2, -1, 1)))
        if er < 1e-4:  # arccos loses digits near 0: the rotation vector of the difference
            D = M[:3, :3] @ R.T
            er = float(np.linalg.norm([D[2, 1] - D[1, 2], D[0, 2] - D[2, 0], D[1, 0] - D[0, 1]]) / 2)
        et = float(np.linalg.norm(M[:3, 3] - t) / L)
        worst_r, worst_t = max(worst_r, er), max(worst_t, et)
        print(f"pose {k:3d}: rotation error {er:.3g} rad, translation error {et:.3g} L, "
              f"{r['seconds']:.2f} s", flush=True)
    print(f"{a.poses} poses, body {len(body)} points, scan {len(body[::2])}: worst rotation error "
          f"{worst_r:.3g} rad, worst translation error {worst_t:.3g} L, "
          f"{time.perf_counter() - t0:.1f} s in all")


if __name__ == "__main__":
    main()
