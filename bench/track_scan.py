#!/usr/bin/env python3
"""Tracking from one depth view, measured (issue 32's goal: the node error within 1.5x that of
the same run against the clean, complete target in the body's frame).

    PYTHONPATH=build/python /usr/bin/python3 bench/track_scan.py [--seed S] [--view full|half]
        [--max-iter N] [--rounds K] [--out DIR]

1. The view. The finger of data/scenes/finger.json, deformed by m*(X) = -1.5 X3 on a 2x finer
   mesh (data/targets/finger_target.ply), is seen by a synthetic depth camera
   (bench/synthetic_scan.py): the points the camera sees, noise 0.5 % of the body's size L,
   3 % outliers, a table plane under the finger, a random camera pose. The scan is in the
   camera's frame.
2. Clean-up, in the camera's frame: the table (softhd.remove_dominant_plane) and the stray
   points (softhd.remove_statistical_outliers); the scan's density falls with the distance
   from the camera, so its points get estimated areas (softhd.area_weights, "delaunay").
3. Pose and shape, alternated K rounds: softhd.align puts the scan into the body's frame
   against the body as it is now (at rest in round 1), with the one-sided distance
   scan_to_body (the scan sees one side); softhd.optimise then fits the control to the aligned
   scan (scan_to_body, the body's moving cloud its boundary, a soft cap at 3 x the 90 %
   quantile of the scan's distances). Points outside the body's box inflated by 10 % are
   cropped after each alignment.
4. The same run against the clean, complete target in the body's frame (the scene's own),
   and the node errors of both against the true deformed nodes.

The pose and the control are found in turns, not jointly (softhd has no joint pose-and-control
optimisation yet), so a rigid offset left by an alignment is partly absorbed by the control.
Measured (seed 1, full view, 3 rounds of 15 iterations): the first alignment, against the body
at rest, is 23 degrees off (the finger's tip is bent up by a third of its length), the rounds
bring it to 20 degrees, and the node error's rms is 48x the clean run's: the goal is missed
until the pose is refined with the control.
Prints one line per stage and a table of node errors; writes the scan, the aligned scan and
the final bodies to --out.
"""

import argparse
import os
import sys

import numpy as np

import softhd

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import synthetic_scan  # noqa: E402  (bench/synthetic_scan.py)


def true_nodes(scene_nodes):
    """The true deformed positions of the finger's nodes: the fine mesh's deformed nodes at the
    same reference points (the fine mesh is the coarse one refined, so every coarse node is a
    fine node)."""
    fine_rest = softhd.read_mesh(os.path.join(ROOT, "data/meshes/finger_fine.msh"), order=2).nodes
    fine_deformed, _ = softhd.read_cloud(os.path.join(ROOT, "data/targets/finger_target.ply"))
    nearest = np.empty(len(scene_nodes), dtype=np.int64)
    gap = 0.0
    for s in range(0, len(scene_nodes), 100):  # brute force in blocks of 100 nodes
        d2 = ((scene_nodes[s:s + 100, None, :] - fine_rest[None, :, :]) ** 2).sum(-1)
        nearest[s:s + 100] = d2.argmin(1)
        gap = max(gap, float(np.sqrt(d2.min(1)).max()))
    if gap > 1e-6:
        sys.exit(f"track_scan: the fine mesh does not hold the coarse nodes (gap {gap:g})")
    return fine_deformed[nearest]


def node_errors(nodes, displacements, truth):
    e = np.linalg.norm(nodes + displacements - truth, axis=1)
    return float(e.max()), float(np.sqrt((e ** 2).mean()))


def clean_scan(scan, L, log):
    off_table = softhd.remove_dominant_plane(scan, distance=0.01 * L)
    kept = scan[off_table]
    inliers = softhd.remove_statistical_outliers(kept, k=20, ratio=2.0)
    log(f"clean-up: {len(scan)} points, table removed {len(scan) - len(off_table)}, "
        f"outliers removed {len(off_table) - len(inliers)}")
    return kept[inliers]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--view", choices=["full", "half"], default="full")
    ap.add_argument("--max-iter", type=int, default=40)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--out", default="results/track_scan")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    log = lambda s: print(s, flush=True)  # noqa: E731

    scene = softhd.Scene.load(os.path.join(ROOT, "data/scenes/finger.json"))
    nodes = scene.mesh.nodes
    truth = true_nodes(nodes)
    deformed, _ = softhd.read_cloud(os.path.join(ROOT, "data/targets/finger_target.ply"))
    scan, P_true, info = synthetic_scan.view(deformed, a.seed, a.view, noise=0.005,
                                             outliers=0.03, table=True)
    L = info["size"]
    softhd.write_cloud(os.path.join(a.out, "scan.ply"), scan)
    log(f"view: {len(scan)} points in the camera's frame: {info['kept'] - info['table']} of the "
        f"body, {info['table']} of the table, {info['outliers']} outliers; L = {L:.4g}")

    scan = clean_scan(scan, L, log)
    areas = softhd.area_weights(scan, "delaunay")
    lower, upper = nodes.min(0), nodes.max(0)
    u = np.zeros_like(nodes)
    for k in range(1, a.rounds + 1):
        body = nodes + u
        pose = softhd.align(body, scan, distance="scan_to_body")
        R, t = pose["matrix"][:3, :3], pose["matrix"][:3, 3]
        angle = np.degrees(np.arccos(np.clip((np.trace(R @ P_true[:3, :3].T) - 1) / 2, -1, 1)))
        aligned = scan @ R.T + t
        inside = softhd.crop_to_box(aligned, body.min(0), body.max(0), margin=0.1)
        target = (aligned[inside], areas[inside])
        log(f"round {k}: align {pose['status']}, rotation error {angle:.3f} deg, "
            f"overlap {pose['overlap']:.3f}, kept {len(inside)} of {len(aligned)} after the crop")
        rest = softhd.distance(body, target[0], distance="scan_to_body", fields=True)
        cap = 3.0 * float(np.quantile(rest.field_target, 0.9))
        r = softhd.optimise(scene, target, max_iter=a.max_iter, distance="scan_to_body", cap=cap,
                            particles="boundary", volumes="deformed")
        u = r.displacements
        e_max, e_rms = node_errors(nodes, u, truth)
        log(f"round {k}: optimise {r.iterations} iterations, {r.seconds:.1f} s, cap {cap:.3g}, "
            f"node error max {e_max:.4g} rms {e_rms:.4g}")
    softhd.write_cloud(os.path.join(a.out, "aligned.ply"), target[0], target[1])
    softhd.write_cloud(os.path.join(a.out, "body_scan.ply"), nodes + u)

    clean = softhd.optimise(scene, max_iter=a.max_iter)
    c_max, c_rms = node_errors(nodes, clean.displacements, truth)
    softhd.write_cloud(os.path.join(a.out, "body_clean.ply"), nodes + clean.displacements)
    s_max, s_rms = node_errors(nodes, u, truth)
    log(f"clean target: optimise {clean.iterations} iterations, {clean.seconds:.1f} s")
    log("")
    log("target                     node error max    rms      ratio (rms)")
    log(f"clean, complete, body frame  {c_max:10.4g} {c_rms:10.4g}")
    log(f"one {a.view} view, camera frame {s_max:10.4g} {s_rms:10.4g}   {s_rms / c_rms:.2f}")
    log(f"(L = {L:.4g}; at rest: rms {node_errors(nodes, 0 * u, truth)[1]:.4g})")


if __name__ == "__main__":
    main()
