#!/usr/bin/python3
"""The pose the data term itself prefers: align each synthetic view of the bent finger (m* = -1.5 X3,
noise 0.5 % L, 3 % outliers, a table removed at 0.02 L) against the TRUE deformed body, refined from
the TRUE pose (no global start, every point), and report how far the minimiser of rho lies from the
truth. No optimiser of pose and control together can end nearer the true pose than this, whatever
its start: it is the bias of the data term on that view.

    PYTHONPATH=build/python OMP_NUM_THREADS=1 /usr/bin/python3 studies/pose_bias.py [--views full half]
        [--seeds 1 2 3 4] [--beta 4] [--cap 0]   (cap as a fraction of L)
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import softhd  # noqa: E402
import track_scan as ts  # noqa: E402

ROOT = ts.ROOT


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--views", nargs="+", default=["full", "half"], choices=["full", "half"])
    ap.add_argument("--seeds", nargs="+", type=int, default=[1, 2, 3, 4])
    ap.add_argument("--beta", type=float, default=4.0)
    ap.add_argument("--cap", type=float, default=0.0, help="the soft cap, a fraction of L (0: none)")
    a = ap.parse_args()
    scene = softhd.Scene.load(os.path.join(ROOT, "data/scenes/finger.json"))
    bodies = {"mesh nodes at m*": ts.true_nodes(scene.mesh.nodes)}
    bodies["fine cloud at m*"], _ = softhd.read_cloud(os.path.join(ROOT, "data/targets/finger_target.ply"))
    fine = softhd.read_mesh(os.path.join(ROOT, "data/meshes/finger_fine.msh"), order=2)
    for view in a.views:
        for seed in a.seeds:
            scan, P, info = ts.synthetic_scan.view(bodies["fine cloud at m*"], fine.boundary_triangles,
                                                   seed, view, noise=0.005, outliers=0.03, table=True)
            L = info["size"]
            scan = ts.clean_scan(scan, L, lambda s: None, 0.02)
            centre = P[:3, :3] @ scan.mean(0) + P[:3, 3]
            for name, body in bodies.items():
                r = softhd.align(body, scan, distance="scan_to_body", global_start=False, initial=P,
                                 refine_points=0, cap=a.cap * L, beta=a.beta)
                M = r["matrix"]
                moved = M[:3, :3] @ scan.mean(0) + M[:3, 3]
                print(f"{view} seed {seed} {name:17s}: pose {ts.rotation_error(M[:3, :3], P):.3f} deg, "
                      f"centroid {np.linalg.norm(moved - centre) / L * 100:.3f} % L, rho {r['rho']:.4g}",
                      flush=True)


if __name__ == "__main__":
    main()
