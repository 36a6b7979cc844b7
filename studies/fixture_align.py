#!/usr/bin/env python3
"""The pose of a depth view with and without the fixture (docs/formulation.md section 8.12).

    PYTHONPATH=build/python OMP_NUM_THREADS=1 /usr/bin/python3 studies/fixture_align.py \
        [--seeds 1 2 ... 8] [--views full half] [--plane 0.02] [--csv FILE]

For each seed and view: the finger of data/scenes/finger.json bent by m* = -1.5 X3 (the 2x finer
mesh's deformed nodes, data/targets/finger_target.ply) seen by softhd.synthetic.view (noise
0.5 % L, 3 % outliers, a table plane, a random camera pose), the scan in the camera's frame.
Clean-up as studies/track_scan.py: the table (find_dominant_plane / remove_dominant_plane within
--plane L), then the statistical outliers (k = 20, ratio 2). Then softhd.align with the distance
scan_to_body, against the body at rest (the scene's mesh nodes), three ways:

  free:         no fixture (the global start over SO(3)),
  fixture:      the fixture (synthetic.table_plane of the deformed body: the table 1 % L under
                its lowest point, normal +z) and the table found in the scan; the pose keeps
                the table's tilt and height throughout,
  fixture+clamp: the fixture and the clamp's side: the base (x = 0) seen from the body's centre
                in the camera's frame, rounded to the nearest of the image's left, right, up or
                down (a user's hint: "the clamp is on the left"),
  fixture+clamp, free: that pose as the only start (global_start=False) of an unconstrained
                refinement: the fixture used as a start, not as a constraint,
  ladder+fixture+clamp: fixture+clamp against the body under the uniform controls 0, -2.5, -5,
                -10, -20 (studies/track_scan.py's ladder), the lowest rho kept,

and, as a reference for what the data allow, "fixture, true body": the fixture against the true
deformed body's nodes (the scene mesh's nodes at m*). Prints one line per alignment: the rotation
error (degrees), the error at the scan's centroid (a fraction of L), the tilt of the table's
normal after the pose (degrees) and the seconds; then a table of the medians and counts.
--tilt DEG and --height F give the fixture an error (its normal turned by DEG about x, its offset
moved by F L), with --only-fixture: the fixture + clamp runs only.
"""

import argparse
import os
import sys
import time

import numpy as np

import softhd
from softhd import synthetic

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)


def rotation_error(R, P_true):
    c = (np.trace(R @ P_true[:3, :3].T) - 1) / 2
    return float(np.degrees(np.arccos(np.clip(c, -1, 1))))


def errors(P, P_true, scan, L, table):
    """(rotation error in degrees, error at the scan's centroid / L, the angle between the
    body's +z and the scan table's normal after P, in degrees)."""
    centre = scan.mean(0)
    shift = np.linalg.norm((P[:3, :3] - P_true[:3, :3]) @ centre + P[:3, 3] - P_true[:3, 3])
    n = np.asarray(table["normal"])
    n = n if np.median(scan @ n - table["offset"]) > 0 else -n
    tilt = float(np.degrees(np.arccos(np.clip((P[:3, :3] @ n)[2], -1, 1))))
    return rotation_error(P[:3, :3], P_true), shift / L, tilt


METHODS = ("free", "fixture", "fixture+clamp", "fixture+clamp, free", "ladder+fixture+clamp",
           "fixture, true body")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--seeds", type=int, nargs="+", default=list(range(1, 9)))
    ap.add_argument("--views", nargs="+", default=["full", "half"])
    ap.add_argument("--plane", type=float, default=0.02, help="the table's threshold, x L")
    ap.add_argument("--csv", default=None)
    ap.add_argument("--tilt", type=float, default=0.0,
                    help="the fixture's error: its normal turned by this many degrees about x")
    ap.add_argument("--height", type=float, default=0.0,
                    help="the fixture's error: its offset moved by this fraction of L")
    ap.add_argument("--only-fixture", action="store_true",
                    help="only the fixture + clamp runs (at rest and the true body)")
    a = ap.parse_args()
    log = lambda s: print(s, flush=True)  # noqa: E731

    scene = softhd.Scene.load(os.path.join(ROOT, "data/scenes/finger.json"))
    nodes = scene.mesh.nodes
    deformed, _ = softhd.read_cloud(os.path.join(ROOT, "data/targets/finger_target.ply"))
    fine = softhd.read_mesh(os.path.join(ROOT, "data/meshes/finger_fine.msh"), order=2)
    fine_rest = fine.nodes
    true_body = synthetic.matched_nodes(nodes, fine_rest, deformed)
    normal, offset = synthetic.table_plane(deformed)
    th = np.radians(a.tilt)  # a fixture known with an error
    normal = np.array([0.0, -np.sin(th), np.cos(th)])
    offset += a.height * synthetic.body_size(deformed)
    fixture = (normal, offset)
    log(f"fixture: the table n.x = {offset:.4g}, n = {normal} (body frame)")
    ladder = []  # the body under uniform controls 0, -2.5, -5, -10, -20 (track_scan.ladder_align)
    for m in () if a.only_fixture else (0.0, -2.5, -5.0, -10.0, -20.0):
        u = scene.forward(np.full(scene.num_controls, m)).displacements
        ladder.append((m, nodes + u))
    rows = []
    for view in a.views:
        for seed in a.seeds:
            scan, P_true, info = synthetic.view(deformed, fine.boundary_triangles, seed, view,
                                                noise=0.005, outliers=0.03, table=True)
            L = info["size"]
            table = softhd.find_dominant_plane(scan, distance=a.plane * L)
            off = softhd.remove_dominant_plane(scan, distance=a.plane * L)
            kept = scan[off]
            kept = kept[softhd.remove_statistical_outliers(kept, k=20, ratio=2.0)]
            # The clamp's side: the base (x = 0) seen from the body's centre, in the camera's
            # frame, rounded to the nearest of the image's left, right, up, down (a user's hint).
            seen = P_true[:3, :3].T @ np.array([-1.0, 0.0, 0.0])
            k = int(np.argmax(np.abs(seen[:2])))
            hint = np.zeros(3)
            hint[k] = np.sign(seen[k])
            clamp = (np.array([-1.0, 0.0, 0.0]), hint)
            runs = {}
            if not a.only_fixture:
                t = time.time()
                runs["free"] = softhd.align(nodes, kept, distance="scan_to_body")
                runs["free"]["wall"] = time.time() - t
                t = time.time()
                runs["fixture"] = softhd.align(nodes, kept, distance="scan_to_body",
                                               fixture=fixture, table=table)
                runs["fixture"]["wall"] = time.time() - t
            t = time.time()
            runs["fixture+clamp"] = softhd.align(nodes, kept, distance="scan_to_body",
                                                 fixture=fixture, table=table, clamp=clamp)
            runs["fixture+clamp"]["wall"] = time.time() - t
            if a.only_fixture:
                t = time.time()
                runs["fixture, true body"] = softhd.align(
                    true_body, kept, distance="scan_to_body", fixture=fixture, table=table,
                    clamp=clamp)
                runs["fixture, true body"]["wall"] = time.time() - t
                for name, r in runs.items():
                    rot, shift, tilt = errors(r["matrix"], P_true, kept, L, table)
                    rows.append((view, seed, name, rot, shift, tilt, r["wall"], r["overlap"]))
                    log(f"{view} seed {seed} {name:21s}: rotation {rot:8.3f} deg, centroid "
                        f"{100 * shift:7.3f} % L")
                continue
            t = time.time()
            runs["fixture+clamp, free"] = softhd.align(nodes, kept, distance="scan_to_body",
                                                       global_start=False,
                                                       initial=runs["fixture+clamp"]["matrix"])
            runs["fixture+clamp, free"]["wall"] = time.time() - t + runs["fixture+clamp"]["wall"]
            t = time.time()
            best = None
            for m, body in ladder:  # the lowest rho over the ladder (track_scan.ladder_align)
                r = softhd.align(body, kept, distance="scan_to_body", fixture=fixture,
                                 table=table, clamp=clamp)
                if best is None or r["rho"] < best["rho"]:
                    best = dict(r, m=m)
            runs["ladder+fixture+clamp"] = best
            best["wall"] = time.time() - t
            t = time.time()
            runs["fixture, true body"] = softhd.align(true_body, kept, distance="scan_to_body",
                                                      fixture=fixture, table=table, clamp=clamp)
            runs["fixture, true body"]["wall"] = time.time() - t
            for name, r in runs.items():
                rot, shift, tilt = errors(r["matrix"], P_true, kept, L, table)
                rows.append((view, seed, name, rot, shift, tilt, r["wall"], r["overlap"]))
                log(f"{view} seed {seed} {name:21s}: rotation {rot:8.3f} deg, centroid "
                    f"{100 * shift:7.3f} % L, table tilt {tilt:8.3g} deg, overlap "
                    f"{r['overlap']:.3f}, {r['wall']:.1f} s"
                    + (f", ladder m = {r['m']:g}" if "m" in r else ""))
    if a.csv:
        with open(a.csv, "w") as f:
            f.write("view,seed,method,rotation_deg,centroid_error_L,table_tilt_deg,seconds,"
                    "overlap\n")
            for r in rows:
                f.write(",".join(str(x) for x in r) + "\n")
    log("")
    log("view  method                 median rot  max rot  < 2 deg  < 10 deg  "
        "median centroid (% L)")
    for view in a.views:
        for name in METHODS:
            sel = [r for r in rows if r[0] == view and r[2] == name]
            if not sel:
                continue
            rot = np.array([r[3] for r in sel])
            sh = np.array([r[4] for r in sel])
            log(f"{view:5s} {name:21s} {np.median(rot):10.2f} {rot.max():8.2f} "
                f"{(rot < 2).sum():4d}/{len(sel)} {(rot < 10).sum():5d}/{len(sel)} "
                f"{100 * np.median(sh):10.3f}")


if __name__ == "__main__":
    main()
