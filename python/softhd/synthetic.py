"""Synthetic depth views of a body, for tests, examples and benchmarks of scan tracking.

view(body_points, seed, ...) returns the points one random camera sees, in the camera's frame,
with the true pose (camera frame -> body frame):
  1. a random camera: direction uniform on the upper half sphere (z > 0.2: a table lies under
     the body) around the body's centre, at `distance` times the body's size L, looking at
     the centre (random roll);
  2. optionally a table: a plane under the body (its lowest z minus L/100) over its
     footprint inflated 1.3 times, with half as many points as the body;
  3. visibility by a z-buffer: the points projected (pinhole) onto a `pixels` square image
     that frames the body; a point is kept when its depth is within `depth_tol` L of the
     nearest depth in its pixel (interior nodes and the far side drop out); view_kind
     "half" keeps only the left half of the image (half the body out of frame);
  4. `points`: a random subsample of the visible points;
  5. noise: Gaussian, standard deviation `noise` L per coordinate; outliers: `outliers`
     times the count, uniform in the body's bounding box inflated 1.5 times.
The pose P is a 4x4 matrix with x = R y + t (softhd.align's pose form).

matched_nodes(nodes, fine_rest, fine_deformed) gives the true deformed positions of a coarse
mesh's nodes from a finer mesh that contains them (the reference of a node error), and
node_errors(...) the largest and RMS distance to them.

Deterministic for a fixed seed (NumPy's default_rng).
"""
import numpy as np


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


def matched_nodes(nodes, fine_rest, fine_deformed):
    """The deformed positions of `nodes` (N, d) taken from a finer mesh: its rest nodes
    `fine_rest` (M, d) and deformed nodes `fine_deformed` (M, d), matched by the nearest rest
    node. Raises ValueError if some node is not a node of the fine mesh (gap over 1e-6 of its
    size): the fine mesh must be the coarse one refined."""
    nodes = np.asarray(nodes, dtype=float)
    fine_rest = np.asarray(fine_rest, dtype=float)
    nearest = np.empty(len(nodes), dtype=np.int64)
    gap = 0.0
    for s in range(0, len(nodes), 100):  # brute force in blocks of 100 nodes
        d2 = ((nodes[s:s + 100, None, :] - fine_rest[None, :, :]) ** 2).sum(-1)
        nearest[s:s + 100] = d2.argmin(1)
        gap = max(gap, float(np.sqrt(d2.min(1)).max()))
    if gap > 1e-6 * body_size(fine_rest):
        raise ValueError(f"matched_nodes: the fine mesh does not hold the nodes (gap {gap:g})")
    return np.asarray(fine_deformed, dtype=float)[nearest]


def node_errors(nodes, displacements, truth):
    """(max, rms) of |nodes + displacements - truth| over the nodes."""
    e = np.linalg.norm(nodes + displacements - truth, axis=1)
    return float(e.max()), float(np.sqrt((e ** 2).mean()))
