"""softhd.read_cloud on PCD files and the scan clean-up and weights against NumPy oracles
(docs/formulation.md section 8)."""

import os
import pathlib

import numpy as np
import pytest

import softhd

DATA = pathlib.Path(os.environ.get("SOFTHD_SOURCE_DIR", pathlib.Path(__file__).parents[2])) / \
    "tests" / "data" / "pcd"


def test_read_cloud_reads_open3d_pcd_with_a_note():
    expected = np.loadtxt(DATA / "open3d_points.txt")
    with pytest.warns(UserWarning, match="normal_x, normal_y, normal_z, rgb ignored"):
        points, volumes = softhd.read_cloud(DATA / "open3d_binary.pcd")
    assert np.array_equal(points, expected)
    assert np.array_equal(volumes, np.ones(len(expected)))


def test_crop_and_outliers_match_numpy(rng):
    X = rng.uniform(-1, 2, size=(400, 3))
    lo, hi = np.array([0.0, 0.0, 0.0]), np.array([1.0, 0.5, 0.8])
    m = 0.1 * np.linalg.norm(hi - lo)
    inside = np.flatnonzero(np.all((X >= lo - m) & (X <= hi + m), axis=1))
    assert np.array_equal(softhd.crop_to_box(X, lo, hi, 0.1), inside)
    d = np.linalg.norm(X[:, None, :] - X[None, :, :], axis=2)
    mean = np.sort(d, axis=1)[:, 1:9].mean(axis=1)  # column 0 is the point itself
    kept = np.flatnonzero(mean <= mean.mean() + 1.5 * mean.std(ddof=1))
    assert np.array_equal(softhd.remove_statistical_outliers(X, k=8, ratio=1.5), kept)


def test_plane_and_area_weights(rng):
    table = np.c_[rng.uniform(-1, 1, (500, 2)), np.zeros(500)]
    above = rng.uniform([-1, -1, 0.5], [1, 1, 1], size=(100, 3))
    off = softhd.remove_dominant_plane(np.r_[table, above], distance=0.01)
    assert np.array_equal(off, np.arange(500, 600))
    # A unit sphere, uniform: the areas sum to 4 pi within 3 %.
    v = rng.normal(size=(2000, 3))
    sphere = v / np.linalg.norm(v, axis=1, keepdims=True)
    for method in ("knn", "delaunay"):
        assert softhd.area_weights(sphere, method).sum() == pytest.approx(4 * np.pi, rel=0.03)
    with pytest.raises(softhd.InvalidArgument, match="expected knn or delaunay"):
        softhd.area_weights(sphere, "voronoi")
    with pytest.raises(softhd.InvalidArgument, match="k must"):
        softhd.remove_statistical_outliers(sphere, k=0)


def brute_force_visible(points, tri, camera):
    """The rule of softhd.visible_points with every triangle tried, in NumPy: a point is seen
    iff a triangle through it faces the camera and no other triangle meets the segment from
    the camera at t in (0, 1 - 1e-9) (t = 1 the point)."""
    A, B, C = points[tri[:, 0]], points[tri[:, 1]], points[tri[:, 2]]
    n = np.cross(B - A, C - A)
    seen = np.zeros(len(points), bool)
    for i in range(len(points)):
        own = (tri == i).any(1)
        if not (n[own] @ (camera - points[i]) > 0).any():
            continue
        d = points[i] - camera  # camera + t d = A + v (B - A) + w (C - A)
        M = np.stack([-np.broadcast_to(d, A.shape), B - A, C - A], -1)
        ok = np.abs(np.linalg.det(M)) > 1e-14
        tvw = np.linalg.solve(M[ok], (camera - A[ok])[..., None])[..., 0]
        t, v, w = tvw.T
        hit = (t > 0) & (t < 1 - 1e-9) & (v >= 0) & (w >= 0) & (v + w <= 1) & ~own[ok]
        seen[i] = not hit.any()
    return seen


def test_visible_points_matches_a_brute_force_ray_test(rng):
    """A grid box and an L-shaped pair of boxes (one hides part of the other) from cameras
    around them: the library's ray cast agrees with trying every triangle, and points on no
    triangle are never seen."""
    from softhd import synthetic
    g = np.meshgrid(np.linspace(0, 2, 7), np.linspace(0, 1, 4), np.linspace(0, 0.5, 3),
                    indexing="ij")
    box = np.stack([c.ravel() for c in g], 1)
    tri = synthetic.box_surface(g[0].shape)
    # outward: the divergence theorem gives the volume 2 x 1 x 0.5
    A, B, C = box[tri[:, 0]], box[tri[:, 1]], box[tri[:, 2]]
    assert np.einsum("ij,ij->", A, np.cross(B - A, C - A)) / 6 == pytest.approx(1.0)
    two = np.vstack([box, box + [0.5, 0.2, 1.0]])  # a second box above, offset
    tri2 = np.vstack([tri, tri + len(box)])
    inner = np.flatnonzero(np.isin(np.arange(len(box)), tri, invert=True))
    assert len(inner) > 0
    for k in range(8):
        d = rng.normal(size=3)
        camera = 1.0 + 4.0 * d / np.linalg.norm(d)
        for pts, t in ((box, tri), (two, tri2)):
            seen = softhd.visible_points(pts, t, camera)
            assert seen.dtype == bool and seen.shape == (len(pts),)
            assert np.array_equal(seen, brute_force_visible(pts, t, camera)), k
            assert not seen[inner].any()
        assert 0 < softhd.visible_points(two, tri2, camera).sum() < len(two)
    with pytest.raises(softhd.InvalidArgument, match="outside 0"):
        softhd.visible_points(box, tri + 1000, [5.0, 5.0, 5.0])
    with pytest.raises(TypeError, match="integers"):
        softhd.visible_points(box, tri.astype(float), [5.0, 5.0, 5.0])


def test_perturbed_pose_is_off_by_the_angle_and_shift_asked(rng):
    """A calibrated camera's stand-in: the rotation from the true pose is `degrees` exactly (the
    angle of R Rtᵀ), the body's centre moves by exactly `fraction` x size (the rotation is about
    it), and the same seed gives the same pose whatever the sizes."""
    from softhd import synthetic
    A = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    P = np.eye(4)
    P[:3, :3], P[:3, 3] = A * np.sign(np.linalg.det(A)), rng.normal(size=3)
    centre = rng.normal(size=3)
    Q = synthetic.perturbed_pose(P, centre, 50.0, seed=4, degrees=2.5, fraction=0.01)
    R, Rt = Q[:3, :3], P[:3, :3]
    assert np.allclose(R.T @ R, np.eye(3), atol=1e-12) and np.linalg.det(R) > 0
    angle = np.degrees(np.arccos(np.clip((np.trace(R @ Rt.T) - 1) / 2, -1, 1)))
    assert abs(angle - 2.5) < 1e-9
    moved = np.linalg.norm(R @ centre + Q[:3, 3] - Rt @ centre - P[:3, 3])
    assert abs(moved - 0.5) < 1e-12 * 50
    Q2 = synthetic.perturbed_pose(P, centre, 5.0, seed=4, degrees=1.0, fraction=0.02)
    axis = lambda M: np.array([M[2, 1] - M[1, 2], M[0, 2] - M[2, 0], M[1, 0] - M[0, 1]])
    a1, a2 = axis(R @ Rt.T), axis(Q2[:3, :3] @ Rt.T)
    assert np.allclose(a1 / np.linalg.norm(a1), a2 / np.linalg.norm(a2), atol=1e-9)


def test_synthetic_view_is_a_rigidly_moved_visible_subset(rng):
    """Without noise or outliers a view is the body's points the library's ray cast shows the
    camera, moved by the inverse of the pose it returns; with them, the counts and noise level
    are the ones asked for."""
    from softhd import synthetic
    g = np.meshgrid(np.linspace(0, 4, 41), np.linspace(0, 1, 11), np.linspace(0, 0.5, 6),
                    indexing="ij")
    body = np.stack([c.ravel() for c in g], 1)
    tri = synthetic.box_surface(g[0].shape)
    scan, P, info = synthetic.view(body, tri, seed=3, noise=0.0, outliers=0.0)
    R, t = P[:3, :3], P[:3, 3]
    assert np.allclose(R.T @ R, np.eye(3), atol=1e-12) and np.linalg.det(R) > 0
    back = scan @ R.T + t  # x = R y + t
    d = np.sqrt(((back[:, None, :] - body[None, :, :]) ** 2).sum(-1))
    assert d.min(1).max() < 1e-9 * synthetic.body_size(body)
    seen = softhd.visible_points(body, tri, info["camera"])
    assert np.array_equal(np.sort(d.argmin(1)), np.flatnonzero(seen))
    assert 0 < len(scan) == info["kept"] == info["visible"] < len(body)
    again, P2, _ = synthetic.view(body, tri, seed=3, noise=0.0, outliers=0.0)
    assert np.array_equal(scan, again) and np.array_equal(P, P2)  # deterministic
    noisy, P3, info3 = synthetic.view(body, tri, seed=3, noise=0.01, outliers=0.1, points=400)
    assert info3["kept"] == 400 and info3["outliers"] == 40 and len(noisy) == 440
    back = noisy[:400] @ P3[:3, :3].T + P3[:3, 3]
    d = np.sqrt(((back[:, None, :] - body[None, :, :]) ** 2).sum(-1)).min(1)
    L = synthetic.body_size(body)
    # noise 0.01 L per coordinate: the distance to the body is at most about 4 sigma sqrt(3)
    assert 0.002 * L < np.median(d) and d.max() < 0.08 * L
    # a table under the body: some of its points seen, the body's points unchanged
    _, _, info4 = synthetic.view(body, tri, seed=3, noise=0.0, outliers=0.0, table=True)
    assert info4["table"] > 0 and info4["kept"] == info["kept"] + info4["table"]


def test_synthetic_matched_nodes_finds_the_fine_nodes(rng):
    from softhd import synthetic
    fine_rest = rng.uniform(size=(500, 3))
    fine_deformed = fine_rest ** 2 + 1.0
    pick = rng.permutation(500)[:60]
    assert np.array_equal(synthetic.matched_nodes(fine_rest[pick], fine_rest, fine_deformed),
                          fine_deformed[pick])
    with pytest.raises(ValueError, match="does not hold"):
        synthetic.matched_nodes(fine_rest[pick] + 0.01, fine_rest, fine_deformed)
    top, rms = synthetic.node_errors(fine_rest[:2], np.zeros((2, 3)),
                                     fine_rest[:2] + [[3.0, 4.0, 0.0], [0.0, 0.0, 0.0]])
    assert top == 5.0 and abs(rms - np.sqrt(12.5)) < 1e-15
