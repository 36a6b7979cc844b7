#!/usr/bin/python3
"""A synthetic depth view of a body (issue 32): the points a camera sees, in its frame.

From a body cloud (text or PLY; e.g. a deformed body's nodes, data/targets/finger_target.ply,
or `softhd forward --write-cloud`), with a deterministic seed:
  1. a random camera: direction uniform on the upper half sphere (z > 0.2: a table lies under
     the body) around the body's centre, at --distance times the body's size L, looking at
     the centre (random roll);
  2. optionally a table: a plane under the body (its lowest z minus L/100) over its
     footprint inflated 1.3 times, sampled as densely as the body's points;
  3. visibility by a z-buffer: the points projected (pinhole) onto a --pixels square
     image that frames the body; a point is kept when its depth is within --depth-tol L of
     the nearest depth in its pixel (interior nodes and the far side drop out);
     --view half keeps only the left half of the image (half the body out of frame);
  4. --points: a random subsample of the visible points;
  5. noise: Gaussian, standard deviation --noise L per coordinate; outliers: --outliers
     times the count, uniform in the body's bounding box inflated 1.5 times;
  6. the scan is written in the camera's frame (PLY, volumes 1), the true pose P (camera
     frame -> body frame, x = R y + t) as a 4x4 text matrix (softhd align's pose.txt form).

Usable as a module: view(body_points, seed, ...) returns (scan, P, info).

  bench/synthetic_scan.py BODY --out-scan SCAN.ply --out-pose POSE.txt [--seed S]
      [--view full|half] [--noise F] [--outliers F] [--table] [--points N] [--pixels P]
"""
import argparse
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def body_size(points):
    return float(np.linalg.norm(points.max(0) - points.min(0)))


def camera_pose(rng, centre, distance):
    """(R, c): the camera at c, R's rows its axes (x right, y down, z forward) in the body
    frame, so y_cam = R (x - c)."""
    while True:
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        if d[2] > 0.2:
            break
    c = centre + distance * d
    z = (centre - c) / np.linalg.norm(centre - c)
    a = rng.normal(size=3)  # a random roll
    x = np.cross(a, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    return np.vstack([x, y, z]), c


def table_points(rng, body, L, count):
    lo, hi = body.min(0), body.max(0)
    mid, half = (lo + hi) / 2, 0.65 * (hi - lo)
    p = np.empty((count, 3))
    p[:, 0] = rng.uniform(mid[0] - half[0], mid[0] + half[0], count)
    p[:, 1] = rng.uniform(mid[1] - half[1], mid[1] + half[1], count)
    p[:, 2] = lo[2] - 0.01 * L
    return p


def visible(cam, pixels, depth_tol, L, half):
    """Mask of the camera-frame points `cam` (K, 3) that a z-buffer keeps."""
    u = cam[:, 0] / cam[:, 2]
    v = cam[:, 1] / cam[:, 2]
    lo_u, hi_u, lo_v, hi_v = u.min(), u.max(), v.min(), v.max()
    span = max(hi_u - lo_u, hi_v - lo_v) * (1 + 1e-9)
    iu = np.minimum(((u - lo_u) / span * pixels).astype(int), pixels - 1)
    iv = np.minimum(((v - lo_v) / span * pixels).astype(int), pixels - 1)
    pix = iv * pixels + iu
    zbuf = np.full(pixels * pixels, np.inf)
    np.minimum.at(zbuf, pix, cam[:, 2])
    keep = cam[:, 2] <= zbuf[pix] + depth_tol * L
    if half:
        keep &= u <= np.median(u[keep])
    return keep


def view(body, seed, view_kind="full", noise=0.005, outliers=0.03, table=False, points=0,
         pixels=120, depth_tol=0.01, distance=3.0):
    """(scan in the camera frame (M, 3), P (4, 4): camera -> body, info dict)."""
    rng = np.random.default_rng(seed)
    L = body_size(body)
    centre = (body.min(0) + body.max(0)) / 2
    R, c = camera_pose(rng, centre, distance * L)
    world = body
    is_table = np.zeros(len(body), bool)
    if table:
        t = table_points(rng, body, L, len(body) // 2)
        world = np.vstack([body, t])
        is_table = np.concatenate([is_table, np.ones(len(t), bool)])
    cam = (world - c) @ R.T
    keep = visible(cam, pixels, depth_tol, L, view_kind == "half")
    idx = np.flatnonzero(keep)
    if points and len(idx) > points:
        idx = np.sort(rng.choice(idx, points, replace=False))
    scan = cam[idx] + rng.normal(scale=noise * L, size=(len(idx), 3))
    n_out = int(round(outliers * len(idx)))
    lo, hi = body.min(0), body.max(0)
    mid, half = (lo + hi) / 2, 0.75 * (hi - lo)
    out_world = rng.uniform(mid - half, mid + half, size=(n_out, 3))
    scan = np.vstack([scan, (out_world - c) @ R.T])
    P = np.eye(4)
    P[:3, :3] = R.T  # x = Rᵀ y + c
    P[:3, 3] = c
    info = dict(size=L, visible=int(keep.sum()), kept=len(idx), outliers=n_out,
                table=int(is_table[idx].sum()), camera=c.tolist())
    return scan, P, info


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("body")
    ap.add_argument("--out-scan", required=True)
    ap.add_argument("--out-pose", required=True)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--view", choices=["full", "half"], default="full")
    ap.add_argument("--noise", type=float, default=0.005)
    ap.add_argument("--outliers", type=float, default=0.03)
    ap.add_argument("--table", action="store_true")
    ap.add_argument("--points", type=int, default=0)
    ap.add_argument("--pixels", type=int, default=120)
    a = ap.parse_args()
    sys.path.insert(0, os.environ.get("SOFTHD_PYTHONPATH", os.path.join(HERE, "..", "build", "python")))
    import softhd
    body, _ = softhd.read_cloud(a.body)
    if body.shape[1] != 3:
        sys.exit(f"synthetic_scan: '{a.body}' is {body.shape[1]}D, a view needs 3D")
    scan, P, info = view(body, a.seed, a.view, a.noise, a.outliers, a.table, a.points, a.pixels)
    softhd.write_cloud(a.out_scan, scan)
    np.savetxt(a.out_pose, P, fmt="%.17g")
    print(f"wrote {a.out_scan} ({len(scan)} points: {info['kept']} visible of {info['visible']},"
          f" {info['table']} on the table, {info['outliers']} outliers), {a.out_pose}")


if __name__ == "__main__":
    main()
