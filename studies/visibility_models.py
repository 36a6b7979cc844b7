#!/usr/bin/python3
"""The two visibility models softhd had, measured on the same cases (docs/formulation.md §8.7,
"Measured"): the library's ray cast (softhd.visible_points: facing test and a segment cast
through a bounding-volume hierarchy of the boundary triangles) and the point z-buffer
softhd.synthetic used (the nodes projected onto a `pixels` square image framing the body, a
node kept when its depth is within depth_tol L of its pixel's nearest).

Cases: the box plate of data/scenes/bending.json (P2, 10 x 2 x 0.1), straight and bent onto a
half circle (an exact map of the rest nodes, no solve); the Gmsh finger (data/meshes/finger.msh,
P2) straight, and its 2x finer mesh straight and bent (finger_fine.msh with the solved target
data/targets/finger_target.ply). Cameras: softhd.synthetic's random cameras (seeds 0..5) at 3 L.

Reference: brute force in float64 without slack: a boundary node is seen iff an incident
triangle faces the camera and no other triangle meets the segment camera -> node at t in
(0, 1 - 1e-9); an interior node is never seen. Accuracy: the fraction of nodes on which a model
agrees with the reference, over all nodes and over the silhouette band (boundary nodes within
3 h of a boundary node whose seen/hidden state differs from a triangle neighbour's, h the
median boundary edge). Time: per call, one thread (OMP_NUM_THREADS=1), best of 3.

  OMP_NUM_THREADS=1 studies/visibility_models.py BUILD_DIR
"""
import argparse
import os
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, "..")


def zbuffer(cam, pixels, depth_tol, L):
    """The z-buffer softhd.synthetic used (camera-frame points `cam`, z forward)."""
    u, v = cam[:, 0] / cam[:, 2], cam[:, 1] / cam[:, 2]
    lo_u, lo_v = u.min(), v.min()
    span = max(u.max() - lo_u, v.max() - lo_v) * (1 + 1e-9)
    iu = np.minimum(((u - lo_u) / span * pixels).astype(int), pixels - 1)
    iv = np.minimum(((v - lo_v) / span * pixels).astype(int), pixels - 1)
    pix = iv * pixels + iu
    zbuf = np.full(pixels * pixels, np.inf)
    np.minimum.at(zbuf, pix, cam[:, 2])
    return cam[:, 2] <= zbuf[pix] + depth_tol * L


def brute_force(nodes, tri, c):
    """The reference mask (see the module text), every triangle tried for every node."""
    seen = np.zeros(len(nodes), bool)
    A, B, C = nodes[tri[:, 0]], nodes[tri[:, 1]], nodes[tri[:, 2]]
    n = np.cross(B - A, C - A)
    e1, e2 = B - A, C - A
    facing = np.zeros(len(nodes), bool)
    for k in range(3):
        np.logical_or.at(facing, tri[:, k], np.einsum("ij,ij->i", n, c - nodes[tri[:, k]]) > 0)
    for i in np.flatnonzero(facing):
        d = nodes[i] - c  # camera + t d, t in (0, 1)
        p = np.cross(d, e2)
        det = np.einsum("ij,ij->i", e1, p)
        s = c - A
        q = np.cross(s, e1)
        with np.errstate(divide="ignore", invalid="ignore"):
            v = np.einsum("ij,ij->i", s, p) / det
            w = (q @ d) / det
            t = np.einsum("ij,ij->i", e2, q) / det
        own = (tri == i).any(1)
        hit = (det != 0) & (v >= 0) & (w >= 0) & (v + w <= 1) & (t > 0) & (t < 1 - 1e-9) & ~own
        seen[i] = not hit.any()
    return seen


def band(nodes, tri, ref, h, width=3.0):
    """Boundary nodes within width h of a node on the seen/hidden border of `ref`."""
    b = np.unique(tri)
    edges = np.vstack([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    border = np.unique(edges[ref[edges[:, 0]] != ref[edges[:, 1]]])
    out = np.zeros(len(nodes), bool)
    if len(border) == 0:
        return out
    for s in range(0, len(b), 2000):
        d2 = ((nodes[b[s:s + 2000], None, :] - nodes[None, border, :]) ** 2).sum(-1)
        out[b[s:s + 2000]] = d2.min(1) <= (width * h) ** 2
    return out


def best_time(f, repeat=3):
    best = np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        r = f()
        best = min(best, time.perf_counter() - t)
    return r, best


def cases(softhd):
    plate = softhd.Scene.load(os.path.join(ROOT, "data/scenes/bending.json")).mesh
    X = plate.nodes
    R = 10.0 / np.pi  # the plate's length on a half circle: θ = X1 / R, the mid-plane at z 0.05
    r = R - (X[:, 2] - 0.05)
    bent = np.stack([r * np.sin(X[:, 0] / R), X[:, 1], R - r * np.cos(X[:, 0] / R)], 1)
    finger = softhd.read_mesh(os.path.join(ROOT, "data/meshes/finger.msh"), order=2)
    fine = softhd.read_mesh(os.path.join(ROOT, "data/meshes/finger_fine.msh"), order=2)
    fine_bent, _ = softhd.read_cloud(os.path.join(ROOT, "data/targets/finger_target.ply"))
    return [("plate straight", X, plate.boundary_triangles),
            ("plate bent", bent, plate.boundary_triangles),
            ("finger straight", finger.nodes, finger.boundary_triangles),
            ("finger fine straight", fine.nodes, fine.boundary_triangles),
            ("finger fine bent", fine_bent, fine.boundary_triangles)]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("build")
    ap.add_argument("--cameras", type=int, default=6)
    ap.add_argument("--pixels", type=int, nargs="*", default=[60, 120, 240])
    a = ap.parse_args()
    sys.path.insert(0, os.path.join(os.path.abspath(a.build), "python"))
    import softhd
    from softhd import synthetic
    print("case | nodes (boundary) | model | agree, all | agree, silhouette band | ms per call")
    totals = {}
    for name, nodes, tri in cases(softhd):
        nodes = np.ascontiguousarray(nodes, dtype=float)
        L = synthetic.body_size(nodes)
        centre = (nodes.min(0) + nodes.max(0)) / 2
        e = np.vstack([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
        h = float(np.median(np.linalg.norm(nodes[e[:, 0]] - nodes[e[:, 1]], axis=1)))
        rows = {}
        for k in range(a.cameras):
            Rc, c = synthetic.camera_pose(np.random.default_rng(k), centre, 3.0 * L)
            ref = brute_force(nodes, tri, c)
            near = band(nodes, tri, ref, h)
            models = [("ray cast", lambda: softhd.visible_points(nodes, tri, c))]
            cam = (nodes - c) @ Rc.T
            for p in a.pixels:
                models.append((f"z-buffer {p} px", lambda p=p: zbuffer(cam, p, 0.01, L)))
            for model, f in models:
                got, t = best_time(f)
                agree = got == ref
                r = rows.setdefault(model, [0, 0, 0, 0, 0.0])
                r[0] += agree.sum()
                r[1] += len(agree)
                r[2] += agree[near].sum()
                r[3] += near.sum()
                r[4] += t / a.cameras
        nb = len(np.unique(tri))
        for model, (ok, n, okb, nband, t) in rows.items():
            print(f"{name} | {len(nodes)} ({nb}) | {model} | {ok / n:.4f} | "
                  f"{okb / max(nband, 1):.4f} ({nband // a.cameras} per view) | {1e3 * t:.2f}",
                  flush=True)
            tot = totals.setdefault(model, [0, 0, 0, 0, 0.0])
            for i, x in enumerate((ok, n, okb, nband, t)):
                tot[i] += x
    for model, (ok, n, okb, nband, t) in totals.items():
        print(f"all cases | {model} | {ok / n:.4f} | {okb / nband:.4f} | {1e3 * t:.2f} (sum)")


if __name__ == "__main__":
    main()
