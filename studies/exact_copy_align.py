#!/usr/bin/env python3
"""An exact copy of a bent body, rigidly moved, recovered by softhd.align with its defaults
(docs/formulation.md section 8.5, "Measured").

    PYTHONPATH=build/python /usr/bin/python3 studies/exact_copy_align.py \
        [--poses 100] [--points 3000] [--score coverage rho] [--body copy nodes resample]

The bent body: data/scenes/finger.json bent by m* = -1.5 X3, i.e. the 2x finer mesh
(data/meshes/finger_fine.msh, P2) at its deformed nodes (data/targets/finger_target.ply), its
boundary cut into flat triangles through its nodes (Mesh.boundary_triangles). Its whole surface
is sampled area-weighted (a triangle drawn with probability proportional to its area, a point
uniform in it; seed 0; each point's volume the surface's area over the count): the cloud S.
The body given to align and the scan:

  surface:  the body is the bent mesh's nodes with its surface (body_triangles: the boundary
            triangles), the scan S moved: the scan is an exact copy of the body's surface, its
            points not the body's (default),
  copy:     the body is S, the scan S moved (an exact copy of the body's points),
  nodes:    the bent mesh's nodes without the surface, the scan S moved (a surface sample of a
            node cloud: recovered only to the nodes' spacing),
  coarse:   the same with the scene's own (2x coarser) mesh's nodes, bent (synthetic.matched_nodes),
  resample: the body is a second, independent sample of the same surface (seed 1), the scan S
            moved (recovered only to the samples' spacing).

Pose k (k = 1..poses): a rotation uniform on SO(3) (a normalised 4D Gaussian quaternion, NumPy's
default_rng(k)) and a translation of length L/2 (L the body's bounding-box diagonal) in a
uniform direction: scan = R S + t; the true pose (scan -> body) y -> R^T (y - t). Errors as
docs/formulation.md section 8.4: the angle of R_found R_true^T (rad) and |t_found - t_true| / L.
Prints one line per pose and score (and the worst errors, the count within 1e-6 rad and 1e-6 L,
the seconds), then a summary.
"""

import argparse
import os
import time

import numpy as np

import softhd
from softhd import synthetic

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def surface_samples(points, triangles, count, seed):
    """(count, 3) points uniform on the triangulated surface and their volumes (area / count)."""
    rng = np.random.default_rng(seed)
    a, b, c = (points[triangles[:, k]] for k in range(3))
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    tri = rng.choice(len(area), size=count, p=area / area.sum())
    r1, r2 = rng.random(count), rng.random(count)
    s = np.sqrt(r1)  # uniform in the triangle: a (1 - s) + b s (1 - r2) + c s r2
    x = (a[tri] * (1 - s)[:, None] + b[tri] * (s * (1 - r2))[:, None]
         + c[tri] * (s * r2)[:, None])
    return x, np.full(count, area.sum() / count)


def random_pose(k, L):
    rng = np.random.default_rng(k)
    q = rng.normal(size=4)
    w, x, y, z = q / np.linalg.norm(q)
    R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                  [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                  [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
    d = rng.normal(size=3)
    return R, 0.5 * L * d / np.linalg.norm(d)


def errors(P, R, t, L):
    """(rotation error in rad, translation error / L) of P against the true y -> R^T (y - t)."""
    Rt, tt = R.T, -R.T @ t
    c = (np.trace(P[:3, :3] @ Rt.T) - 1) / 2
    # the angle from the skew part as well, so that errors near 0 keep their digits
    w = P[:3, :3] @ Rt.T
    s = 0.5 * np.linalg.norm([w[2, 1] - w[1, 2], w[0, 2] - w[2, 0], w[1, 0] - w[0, 1]])
    return float(np.arctan2(s, c)), float(np.linalg.norm(P[:3, 3] - tt) / L)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--poses", type=int, default=100)
    ap.add_argument("--first", type=int, default=1, help="the first pose's seed")
    ap.add_argument("--points", type=int, default=3000, help="surface samples")
    ap.add_argument("--score", nargs="+", default=["coverage", "rho"])
    ap.add_argument("--body", default="surface", choices=["surface", "copy", "nodes", "coarse", "resample"])
    ap.add_argument("--quiet", action="store_true", help="no line per pose")
    a = ap.parse_args()

    fine = softhd.read_mesh(os.path.join(ROOT, "data/meshes/finger_fine.msh"), order=2)
    bent, _ = softhd.read_cloud(os.path.join(ROOT, "data/targets/finger_target.ply"))
    tri = fine.boundary_triangles
    S, V = surface_samples(bent, tri, a.points, 0)
    tris = None
    if a.body == "surface":
        body, vol, tris = bent, None, tri
    elif a.body == "copy":
        body, vol = S, V
    elif a.body == "nodes":
        body, vol = bent, None
    elif a.body == "coarse":
        scene = softhd.Scene.load(os.path.join(ROOT, "data/scenes/finger.json"))
        body, vol = synthetic.matched_nodes(scene.mesh.nodes, fine.nodes, bent), None
    else:
        body, vol = surface_samples(bent, tri, a.points, 1)
    L = float(np.linalg.norm(body.max(0) - body.min(0)))
    print(f"body: {a.body}, {len(body)} points; scan: {len(S)} surface samples; L = {L:.6g}; "
          f"load {os.getloadavg()[0]:.1f}", flush=True)
    for score in a.score:
        rows = []
        t0 = time.time()
        for k in range(a.first, a.first + a.poses):
            R, t = random_pose(k, L)
            scan = S @ R.T + t
            r = softhd.align(body, scan, vol, score=score, body_triangles=tris)
            er, et = errors(r["matrix"], R, t, L)
            rows.append((k, er, et, r["overlap"], r["seconds"]))
            if not a.quiet:
                print(f"{score} pose {k:3d}: rotation error {er:.3e} rad ({np.degrees(er):8.3f} "
                      f"deg), translation error {et:.3e} L, overlap {r['overlap']:.3f}, "
                      f"{r['seconds']:.2f} s", flush=True)
        er = np.array([x[1] for x in rows])
        et = np.array([x[2] for x in rows])
        ok = (er <= 1e-6) & (et <= 1e-6)
        print(f"{score}: {ok.sum()}/{len(rows)} within 1e-6 rad and 1e-6 L; worst rotation error "
              f"{er.max():.3e} rad ({np.degrees(er.max()):.3f} deg, pose "
              f"{rows[int(er.argmax())][0]}), worst translation error {et.max():.3e} L, median "
              f"{np.median(er):.3e} rad / {np.median(et):.3e} L; {time.time() - t0:.1f} s in all, "
              f"load {os.getloadavg()[0]:.1f}", flush=True)


if __name__ == "__main__":
    main()
