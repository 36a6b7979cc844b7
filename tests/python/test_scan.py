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


def test_synthetic_view_is_a_rigidly_moved_visible_subset(rng):
    """Without noise or outliers a view is a subset of the body moved by the inverse of the
    pose it returns; with them, the counts and noise level are the ones asked for."""
    from softhd import synthetic
    body = rng.uniform([0, 0, 0], [4, 1, 0.5], size=(3000, 3))
    scan, P, info = synthetic.view(body, seed=3, noise=0.0, outliers=0.0)
    R, t = P[:3, :3], P[:3, 3]
    assert np.allclose(R.T @ R, np.eye(3), atol=1e-12) and np.linalg.det(R) > 0
    back = scan @ R.T + t  # x = R y + t
    d = np.sqrt(((back[:, None, :] - body[None, :, :]) ** 2).sum(-1)).min(1)
    assert d.max() < 1e-9 * synthetic.body_size(body)
    assert 0 < len(scan) == info["kept"] == info["visible"] < len(body)
    again, P2, _ = synthetic.view(body, seed=3, noise=0.0, outliers=0.0)
    assert np.array_equal(scan, again) and np.array_equal(P, P2)  # deterministic
    noisy, P3, info3 = synthetic.view(body, seed=3, noise=0.01, outliers=0.1, points=400)
    assert info3["kept"] == 400 and info3["outliers"] == 40 and len(noisy) == 440
    back = noisy[:400] @ P3[:3, :3].T + P3[:3, 3]
    d = np.sqrt(((back[:, None, :] - body[None, :, :]) ** 2).sum(-1)).min(1)
    L = synthetic.body_size(body)
    # noise 0.01 L per coordinate: the distance to the body is at most about 4 sigma sqrt(3)
    assert 0.002 * L < np.median(d) and d.max() < 0.08 * L


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
