#!/usr/bin/python3
"""softhd align against Open3D's FPFH + RANSAC + point-to-plane ICP (issue 32).

The body: the deformed finger (data/targets/finger_target.ply: the finger's state under a
known control, solved on a 2x finer mesh; 33 304 nodes), randomly subsampled to --body-points.
Each pose k (seed k) is a random camera (softhd.synthetic), each view "full" (all it
sees) and "half" (the left half of its image only); the scan: --scan-points visible points
of the full body, noise 0.5 % of the body's size L per coordinate, 3 % outliers uniform in
the inflated box, in the camera frame. Both aligners get the same body and scan clouds:
softhd.align(body, scan, distance=--distance, cap=--cap L) and bench/peers/open3d_align.py
(voxel L/40). Errors against the true pose: rotation (degrees), translation / L; success:
rotation error < 2 degrees; the translation error is that of the body's centre,
|M P⁻¹ c − c| / L (t itself is the camera's position, 3 L away). Wall seconds of each call (one process, --threads).

Writes one CSV row per (method, view, pose) and prints, per method and view, the success
rate, the median errors and the median time. Without python3-open3d the Open3D rows are
skipped with one line on stderr (softhd's rows are still written).

  bench/bench_align.py BUILD_DIR [--poses N] [--csv FILE] [--threads T] [--distance D]
                       [--cap C] [--body-points N] [--scan-points N] [--methods a,b]
                       [--score coverage|rho]
"""
import argparse
import csv
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
BODY = os.path.join(ROOT, "data", "targets", "finger_target.ply")
FINE_MESH = os.path.join(ROOT, "data", "meshes", "finger_fine.msh")  # BODY is its deformed nodes


def have(module):
    r = subprocess.run(["/usr/bin/python3", "-c", "import " + module], capture_output=True)
    return r.returncode == 0


def rotation_error_deg(Ra, Rb):
    c = (np.trace(Ra @ Rb.T) - 1.0) / 2.0
    return float(np.degrees(np.arccos(np.clip(c, -1.0, 1.0))))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("build")
    ap.add_argument("--poses", type=int, default=25)
    ap.add_argument("--csv", default="align.csv")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--distance", default="scan_to_body")
    ap.add_argument("--cap", type=float, default=0.0, help="soft cap as a fraction of L")
    ap.add_argument("--body-points", type=int, default=4000)
    ap.add_argument("--scan-points", type=int, default=2000)
    ap.add_argument("--methods", default="softhd,open3d")
    ap.add_argument("--refine-points", type=int, default=1000)
    ap.add_argument("--score", default="coverage", help="softhd's candidate score: coverage | rho")
    a = ap.parse_args()
    sys.path.insert(0, os.path.join(os.path.abspath(a.build), "python"))
    sys.path.insert(0, os.path.join(HERE, "peers"))
    import softhd
    from softhd import synthetic
    methods = a.methods.split(",")
    if "open3d" in methods and not have("open3d"):
        print("bench_align: open3d rows skipped (python3-open3d is not installed)", file=sys.stderr)
        methods.remove("open3d")
    if "open3d" in methods:
        import open3d_align
    fine, _ = softhd.read_cloud(BODY)
    triangles = softhd.read_mesh(FINE_MESH, order=2).boundary_triangles
    rng = np.random.default_rng(12345)
    body = fine[np.sort(rng.choice(len(fine), min(a.body_points, len(fine)), replace=False))]
    L = synthetic.body_size(body)
    centre = body.mean(0)
    rows = []
    for k in range(a.poses):
        for view in ("full", "half"):
            scan, P, info = synthetic.view(fine, triangles, 1000 + k, view, noise=0.005,
                                           outliers=0.03, points=a.scan_points)
            for m in methods:
                t0 = time.perf_counter()
                if m == "softhd":
                    r = softhd.align(body, scan, distance=a.distance, cap=a.cap * L,
                                     refine_points=a.refine_points, threads=a.threads,
                                     score=a.score)
                    M = r["matrix"]
                else:
                    M, _ = open3d_align.align(body, scan, L / 40.0, seed=k)
                sec = time.perf_counter() - t0
                rot = rotation_error_deg(M[:3, :3], P[:3, :3])
                # translation error where it matters: the body's centre moved by M P⁻¹
                # (the pose's t is the camera's position, 3 L away, where a rotation error
                # alone would show as a translation error 3 L times the angle)
                Pinv = np.linalg.inv(P)
                moved = M[:3, :3] @ (Pinv[:3, :3] @ centre + Pinv[:3, 3]) + M[:3, 3]
                tr = float(np.linalg.norm(moved - centre) / L)
                rows.append(dict(method=m, view=view, pose=k, rotation_deg=rot, translation_rel=tr,
                                 seconds=sec, success=int(rot < 2.0), scan_points=len(scan)))
                print(f"{m:7s} {view:4s} pose {k:3d}: rotation {rot:9.4f} deg, translation "
                      f"{tr:.2e} L, {sec:.2f} s", flush=True)
    with open(a.csv, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)
    print(f"\n{a.poses} poses, body {len(body)} points, L = {L:.4g}, distance {a.distance}, "
          f"cap {a.cap} L, softhd score {a.score}")
    for m in methods:
        for view in ("full", "half"):
            sel = [r for r in rows if r["method"] == m and r["view"] == view]
            rot = np.median([r["rotation_deg"] for r in sel])
            tr = np.median([r["translation_rel"] for r in sel])
            ok = sum(r["success"] for r in sel)
            sec = np.median([r["seconds"] for r in sel])
            total = sum(r["seconds"] for r in sel)
            print(f"{m:7s} {view:4s}: success {ok}/{len(sel)}, median rotation {rot:.4g} deg, "
                  f"median translation {tr:.3g} L, median {sec:.3g} s, total {total:.1f} s")


if __name__ == "__main__":
    main()
