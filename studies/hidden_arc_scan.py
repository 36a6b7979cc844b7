#!/usr/bin/python3
"""A scan-like target the project's scenes do not hold (issue 31's hidden targets, a stand-in):
the bending plate (data/scenes/bending.json) against a 120-degree arc seen by one synthetic
camera (softhd.synthetic: 6000 visible points, noise 0.5 % of the body's size, no
outliers), put back into the body's frame. Runs `softhd optimise` on it and prints one JSON
line: the final rho, the iterations, the time and the node error (largest and rms) against
the exact arc map (docs/formulation.md §5.2). Used for the §4.8 table (one level by default
for a cloud without a known map).

    PYTHONPATH=build/python /usr/bin/python3 studies/hidden_arc_scan.py [--seed S]
        [--distance symmetric|scan_to_body] [--max-iter N] [--out DIR] [-- OPTIMISE_OPTIONS...]

e.g. `... --seed 2 --distance scan_to_body -- --levels 2` against `-- --levels 1`.
"""
import argparse
import json
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
import softhd  # noqa: E402
from softhd import synthetic as synthetic_scan  # noqa: E402

THETA, LENGTH, WIDTH, THICK = 2 * np.pi / 3, 10.0, 2.0, 0.1


def arc(X):
    """The arc map T of docs/formulation.md §5.2 for the plate [0,10]x[0,2]x[0,0.1]."""
    R = LENGTH / THETA
    z = X[:, 2] - THICK / 2
    return np.stack([(R - z) * np.sin(X[:, 0] / R), X[:, 1],
                     THICK / 2 + R - (R - z) * np.cos(X[:, 0] / R)], 1)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seed", type=int, default=2)
    ap.add_argument("--distance", choices=["symmetric", "scan_to_body"], default="scan_to_body")
    ap.add_argument("--max-iter", type=int, default=100)
    ap.add_argument("--out", default="results/hidden_arc_scan")
    ap.add_argument("--cli", default=os.path.join(ROOT, "build/apps/softhd"))
    ap.add_argument("options", nargs="*", help="more softhd optimise options (after --)")
    a = ap.parse_args()
    g = np.meshgrid(np.linspace(0, LENGTH, 201), np.linspace(0, WIDTH, 41),
                    np.linspace(0, THICK, 3), indexing="ij")
    body = arc(np.stack([c.ravel() for c in g], 1))
    scan, P, _ = synthetic_scan.view(body, synthetic_scan.box_surface(g[0].shape), a.seed, "full",
                                     noise=0.005, outliers=0.0, points=6000)
    Y = scan @ P[:3, :3].T + P[:3, 3]  # back into the body's frame
    os.makedirs(a.out, exist_ok=True)
    softhd.write_cloud(os.path.join(a.out, "scan.ply"), Y, np.ones(len(Y)))
    with open(os.path.join(ROOT, "data/scenes/bending.json")) as f:
        scene = json.load(f)
    scene["target"] = {"kind": "cloud", "file": os.path.abspath(os.path.join(a.out, "scan.ply")),
                       "distance": a.distance}
    with open(os.path.join(a.out, "scene.json"), "w") as f:
        json.dump(scene, f)
    t0 = time.time()
    subprocess.run([a.cli, "optimise", os.path.join(a.out, "scene.json"), "--out", a.out,
                    "--max-iter", str(a.max_iter), "--method", "tree", "--threads", "1",
                    "--vtu-every", "0", "--quiet"] + a.options, check=True)
    x, _ = softhd.read_cloud(os.path.join(a.out, "body_final.ply"))
    with open(os.path.join(a.out, "summary.json")) as f:
        summary = json.load(f)
    nodes = softhd.Scene.load(os.path.join(a.out, "scene.json")).mesh.nodes
    err = np.linalg.norm(x - arc(nodes), axis=1)
    print(json.dumps(dict(seed=a.seed, distance=a.distance, options=a.options,
                          rho=summary.get("rho_final"), iterations=summary.get("iterations"),
                          seconds=round(time.time() - t0, 1), err_max=float(err.max()),
                          err_rms=float(np.sqrt((err ** 2).mean())))))


if __name__ == "__main__":
    main()
