"""Synthetic depth views of a body, for tests, examples and benchmarks of scan tracking.

view(body_points, triangles, seed, ...) returns the points one random camera sees, in the
camera's frame, with the true pose (camera frame -> body frame):
  1. a random camera: direction uniform on the upper half sphere (z > 0.2: a table lies under
     the body) around the body's centre, at `distance` times the body's size L, looking at
     the centre (random roll);
  2. optionally a table: a plane under the body (its lowest z minus L/100, table_plane) over its
     footprint inflated 1.3 times, a jittered triangulated grid of about half as many points
     as the body;
  3. visibility by softhd.visible_points, the library's ray cast (docs/formulation.md section
     8.7) against the body's boundary triangles (and the table's): a point is kept when a
     triangle through it faces the camera and the segment from the camera meets no other
     triangle (interior nodes, on no triangle, and the far side drop out); view_kind "half"
     keeps only the left half of the image (half the body out of frame);
  4. `points`: a random subsample of the visible points;
  5. noise: Gaussian, standard deviation `noise` L per coordinate; outliers: `outliers`
     times the count, uniform in the body's bounding box inflated 1.5 times.
The pose P is a 4x4 matrix with x = R y + t (softhd.align's pose form).

matched_nodes(nodes, fine_rest, fine_deformed) gives the true deformed positions of a coarse
mesh's nodes from a finer mesh that contains them (the reference of a node error), and
node_errors(...) the largest and RMS distance to them.

perturbed_pose(P_true, scan_centre, L, seed, degrees, fraction) stands for a calibrated camera's
pose: the true one off by a rotation about a random axis through the body's centre and a shift.

box_surface(shape) gives the boundary triangles of a structured grid of points (a box's
nodes in NumPy's "ij" ravel order), for bodies made without a mesh.

Deterministic for a fixed seed (NumPy's default_rng).
"""
import numpy as np

import softhd


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


def box_surface(shape):
    """(T, 3) int64 outward triangles of the boundary of a structured n1 x n2 x n3 grid of
    points indexed i3 + n3 (i2 + n2 i1) (np.meshgrid(..., indexing="ij") raveled), each boundary
    quadrilateral cut by a diagonal. Outward for a grid whose axes are right-handed."""
    n = tuple(int(k) for k in shape)
    if len(n) != 3 or min(n) < 2:
        raise ValueError(f"box_surface: shape must be 3 counts >= 2, got {shape}")
    idx = np.arange(n[0] * n[1] * n[2]).reshape(n)
    tri = []
    for axis in range(3):
        # a face's quad (i, j), (i+1, j), (i+1, j+1), (i, j+1) over the other two axes turns
        # by e_a x e_b: +e0, -e1, +e2 for axis 0, 1, 2; flipped where that points inward
        for side, face in ((0, np.take(idx, 0, axis)), (1, np.take(idx, -1, axis))):
            p, q, r, s = face[:-1, :-1], face[1:, :-1], face[1:, 1:], face[:-1, 1:]
            out = (side == 1) == (axis != 1)
            quad = [p, q, r, s] if out else [p, s, r, q]
            tri.append(np.stack([quad[0], quad[1], quad[2]], -1).reshape(-1, 3))
            tri.append(np.stack([quad[0], quad[2], quad[3]], -1).reshape(-1, 3))
    return np.vstack(tri).astype(np.int64)


def table_plane(body):
    """(normal, offset) of the table view(..., table=True) puts under `body`: the plane
    z = offset, offset = the body's lowest z minus 1 % of its size L, normal (0, 0, 1) (towards
    the body). A fixture that holds the body over a table at a known height, in the body's
    frame: softhd.align's ``fixture``."""
    body = np.asarray(body, dtype=float)
    return np.array([0.0, 0.0, 1.0]), float(body[:, 2].min() - 0.01 * body_size(body))


def table_surface(rng, body, L, count):
    """(points, triangles): a jittered n x n grid (n^2 >= count) in the plane under the body,
    triangles facing up (+z)."""
    lo, hi = body.min(0), body.max(0)
    mid, half = (lo + hi) / 2, 0.65 * (hi - lo)
    n = max(2, int(np.ceil(np.sqrt(count))))
    g = (np.arange(n) + 0.5) / n  # cell centres, jittered by under a third of a cell
    u = g[:, None] + rng.uniform(-0.3, 0.3, (n, n)) / n
    v = g[None, :] + rng.uniform(-0.3, 0.3, (n, n)) / n
    p = np.empty((n * n, 3))
    p[:, 0] = (mid[0] - half[0] + 2 * half[0] * u).ravel()
    p[:, 1] = (mid[1] - half[1] + 2 * half[1] * v).ravel()
    p[:, 2] = table_plane(body)[1]
    idx = np.arange(n * n).reshape(n, n)  # idx[i, j]: x index i, y index j
    a, b, c, d = idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]
    tri = np.vstack([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    return p, tri


def visible(world, triangles, camera):
    """Mask of the points `world` (K, 3) the camera sees: softhd.visible_points."""
    return softhd.visible_points(world, triangles, camera)


def view(body, triangles, seed, view_kind="full", noise=0.005, outliers=0.03, table=False,
         points=0, distance=3.0):
    """(scan in the camera frame (M, 3), P (4, 4): camera -> body, info dict). body (N, 3)
    points; triangles (T, 3) the boundary's outward triangles over them (e.g.
    Mesh.boundary_triangles, or box_surface for a grid)."""
    rng = np.random.default_rng(seed)
    body = np.ascontiguousarray(body, dtype=float)
    L = body_size(body)
    centre = (body.min(0) + body.max(0)) / 2
    R, c = camera_pose(rng, centre, distance * L)
    world, tri = body, np.asarray(triangles, dtype=np.int64)
    is_table = np.zeros(len(body), bool)
    if table:
        t, t_tri = table_surface(rng, body, L, len(body) // 2)
        world = np.vstack([body, t])
        tri = np.vstack([tri, t_tri + len(body)])
        is_table = np.concatenate([is_table, np.ones(len(t), bool)])
    keep = visible(world, tri, c)
    cam = (world - c) @ R.T
    if view_kind == "half":
        u = cam[:, 0] / cam[:, 2]
        keep &= u <= np.median(u[keep])
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


def perturbed_pose(P_true, scan_centre, size, seed, degrees=3.0, fraction=0.02):
    """What a calibrated camera gives: the true pose P_true (camera -> body, 4x4) followed by a
    rotation of `degrees` about a random axis through the body's centre (the camera-frame point
    `scan_centre` moved by P_true) and a shift of `fraction` x `size` in a random direction
    (numpy's default_rng(1000 + seed): the same axis and direction whatever the sizes)."""
    rng = np.random.default_rng(1000 + seed)
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    shift = rng.normal(size=3)
    shift *= fraction * size / np.linalg.norm(shift)
    th = np.radians(degrees)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    R = np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K  # Rodrigues
    c = P_true[:3, :3] @ np.asarray(scan_centre, dtype=float) + P_true[:3, 3]
    E = np.eye(4)
    E[:3, :3], E[:3, 3] = R, c - R @ c + shift
    return E @ P_true


def node_errors(nodes, displacements, truth):
    """(max, rms) of |nodes + displacements - truth| over the nodes."""
    e = np.linalg.norm(nodes + displacements - truth, axis=1)
    return float(e.max()), float(np.sqrt((e ** 2).mean()))
