#!/usr/bin/python3
"""Issue 32's flip diagnosis: on bench_align.py's finger views (seed 1000 + k, noise 0.5 % L,
3 % outliers), the pose softhd.align finds and the one it reaches when started at the truth,
each scored by rho (scan_to_body and symmetric, eps L/1000, no cap) and by a visible-side
distance: the body points a z-buffer (40 pixels over the moved body, depth tolerance L/100)
shows the camera at the scan frame's origin, over the pixels holding scan points, and their
mean nearest distance to the scan (capped at 0.05 L) / L. A prototype of the C++ score of
docs/formulation.md section 8.5 (which also adds the scan's side).

  studies/align_flip_diagnosis.py BUILD_DIR [SEED ...] [--score coverage|rho]
"""
import argparse
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("build")
    ap.add_argument("seeds", nargs="*", type=int, default=[0, 1, 3, 5])
    ap.add_argument("--score", default="coverage")
    a = ap.parse_args()
    sys.path.insert(0, os.path.join(os.path.abspath(a.build), "python"))
    import softhd
    from softhd import synthetic as synthetic_scan
    from scipy.spatial import cKDTree
    fine, _ = softhd.read_cloud(os.path.join(HERE, "..", "data", "targets", "finger_target.ply"))
    triangles = softhd.read_mesh(os.path.join(HERE, "..", "data", "meshes", "finger_fine.msh"),
                                 order=2).boundary_triangles
    rng = np.random.default_rng(12345)  # as bench_align.py
    body = fine[np.sort(rng.choice(len(fine), 4000, replace=False))]
    L = synthetic_scan.body_size(body)

    def rot_err(Ra, Rb):
        return float(np.degrees(np.arccos(np.clip((np.trace(Ra @ Rb.T) - 1) / 2, -1, 1))))

    def rho(M, scan, form):
        moved = scan @ M[:3, :3].T + M[:3, 3]
        return softhd.distance(body, moved, eps=1e-3 * L, method="tree", distance=form).rho

    def visible_side(M, scan, pix=40):
        Mi = np.linalg.inv(M)
        xb = body @ Mi[:3, :3].T + Mi[:3, 3]  # the body in the camera's frame
        e3 = scan.mean(0) / np.linalg.norm(scan.mean(0))
        e1 = np.cross(e3, [1.0, 0, 0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(e3, e1)
        ub, vb = xb @ e1 / (xb @ e3), xb @ e2 / (xb @ e3)
        us, vs = scan @ e1 / (scan @ e3), scan @ e2 / (scan @ e3)
        lo_u, lo_v = ub.min(), vb.min()
        h = max(ub.max() - lo_u, vb.max() - lo_v) / pix
        key = lambda u, v: np.floor((u - lo_u) / h).astype(int) * 100000 + np.floor((v - lo_v) / h).astype(int)
        kb, ks = key(ub, vb), key(us, vs)
        depth = np.linalg.norm(xb, axis=1)
        zmin = {}
        for k, d in zip(kb, depth):
            zmin[k] = min(zmin.get(k, np.inf), d)
        foot = set(ks.tolist())
        sel = np.array([d <= zmin[k] + 0.01 * L and k in foot for k, d in zip(kb, depth)])
        d, _ = cKDTree(scan).query(xb[sel])
        return float(np.mean(np.minimum(d, 0.05 * L)) / L)

    for k in a.seeds:
        for view in ("full", "half"):
            scan, P, _ = synthetic_scan.view(fine, triangles, 1000 + k, view, noise=0.005,
                                             outliers=0.03, points=2000)
            found = softhd.align(body, scan, distance="scan_to_body", threads=1, score=a.score)
            start = softhd.align(body, scan, distance="scan_to_body", threads=1,
                                 global_start=False, initial=P)
            line = f"{view} {k:3d}:"
            for name, r in (("found", found), ("from truth", start)):
                M = r["matrix"]
                line += (f" | {name}: error {rot_err(M[:3, :3], P[:3, :3]):6.2f} deg, rho "
                         f"scan_to_body {rho(M, scan, 'scan_to_body'):.5f}, symmetric "
                         f"{rho(M, scan, 'symmetric'):.5f}, visible side {visible_side(M, scan):.4f}")
            print(line, flush=True)


if __name__ == "__main__":
    main()
