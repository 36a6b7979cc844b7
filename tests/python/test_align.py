"""softhd.align: the pose of an exactly moved subset recovered (rigid and similarity), the
result's fields against an independent NumPy check, refusals."""

import numpy as np
import pytest

import softhd
from softhd import synthetic


def random_rotation(rng):
    q = rng.normal(size=4)
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def body_cloud(rng, n=400):
    """An asymmetric body: a slab with a block on one corner (no self-symmetry)."""
    p = rng.uniform(size=(n, 3)) * [1.0, 0.6, 0.3]
    k = n // 6
    p[:k] = [0.8, 0.4, 0.3] + rng.uniform(size=(k, 3)) * [0.2, 0.2, 0.25]
    return p


def angle(Ra, Rb):
    return np.arccos(np.clip((np.trace(Ra @ Rb.T) - 1) / 2, -1, 1))


@pytest.mark.parametrize("scale", [None, 1.2])
def test_moved_subset_recovered(rng, scale):
    body = body_cloud(rng)
    R, t, s = random_rotation(rng), rng.normal(size=3), 1.0 if scale is None else scale
    scan = ((body[::2] - t) @ R) / s  # P^-1(y) = R^T (y - t) / s
    r = softhd.align(body, scan, similarity=scale is not None)
    M = r["matrix"]
    assert angle(M[:3, :3] / r["scale"], R) < 1e-6
    assert np.linalg.norm(M[:3, 3] - t) < 1e-6
    assert r["scale"] == pytest.approx(s, rel=1e-6)
    assert r["overlap"] == 1.0
    # the residuals are the true nearest distances of the moved scan (brute force)
    moved = scan @ M[:3, :3].T + M[:3, 3]
    brute = np.sqrt(((moved[:, None, :] - body[None, :, :]) ** 2).sum(-1)).min(1)
    assert np.allclose(r["residuals"], brute, atol=1e-12)
    assert r["twist"].shape == (7,) and r["twist"][6] == pytest.approx(np.log(s), abs=1e-6)


def test_search_counts_follow_the_options(rng):
    """starts = rotations + 4 (0 without the global start), candidates = keep (plus initial),
    refine_points = the refinement's points of body and scan (all of a smaller cloud)."""
    body = body_cloud(rng, 120)
    scan = body[:90] + [0.1, 0.2, -0.1]
    r = softhd.align(body, scan, threads=1)
    assert (r["starts"], r["candidates"], r["refine_points"]) == (52, 4, (120, 90))
    r = softhd.align(body, scan, threads=1, rotations=6, keep=2, refine_points=50,
                     initial=np.eye(4))
    assert (r["starts"], r["candidates"], r["refine_points"]) == (10, 3, (50, 50))
    r = softhd.align(body, scan, threads=1, global_start=False)
    assert (r["starts"], r["candidates"]) == (0, 1)
    with pytest.raises(softhd.InvalidArgument, match=r"inlier_distance must be in \(0, 1\)"):
        softhd.align(body, scan, inlier=1.5)


def test_bad_input_refused(rng):
    body = body_cloud(rng, 60)
    with pytest.raises(softhd.InvalidArgument, match="scale_min"):
        softhd.align(body, body, similarity=True, scale_min=1.5)
    with pytest.raises(softhd.InvalidArgument, match=r"\(4, 4\)"):
        softhd.align(body, body, initial=np.eye(3))
    with pytest.raises(softhd.InvalidArgument, match="last row"):
        bad = np.eye(4)
        bad[3, 0] = 1.0
        softhd.align(body, body, initial=bad)
    with pytest.raises(softhd.InvalidArgument, match="distance"):
        softhd.align(body, body, distance="both")
    # the candidate score's retired spelling names the new one
    with pytest.raises(softhd.InvalidArgument, match='"visible" is now "coverage"'):
        softhd.align(body, body, score="visible")
    # clouds that fix no pose: a single point, points on a line; a body of coincident points
    # (its default eps, L/1000, is 0) is named as such
    with pytest.raises(softhd.InvalidArgument, match="the scan: it has a single point"):
        softhd.align(body, body[:1])
    with pytest.raises(softhd.InvalidArgument, match="the scan: its 5 points are collinear"):
        softhd.align(body, np.outer(np.arange(5.0), [1.0, 2.0, 3.0]))
    with pytest.raises(softhd.InvalidArgument, match="the body: its 4 points coincide"):
        softhd.align(np.ones((4, 3)), body)
    with pytest.raises(softhd.InvalidArgument, match="initial pose has scale 2"):
        softhd.align(body, body, initial=np.diag([2.0, 2.0, 2.0, 1.0]))


def test_fixture_keeps_the_table_and_recovers_a_turn_about_it(rng):
    """The fixture (docs/formulation.md section 8.12): the body on a table z = -0.05, every other
    body point and the table moved into the camera's frame by a turn about the table's normal
    after a tilt; the table found by find_dominant_plane and removed: align with the fixture
    (and the clamp's side, seen where it is) gives the pose back and keeps the table's tilt."""
    body = body_cloud(rng, 300)
    g = np.stack(np.meshgrid(np.linspace(-0.3, 1.3, 30), np.linspace(-0.3, 0.9, 25)), -1)
    table = np.column_stack([g.reshape(-1, 2), np.full(g.shape[0] * g.shape[1], -0.05)])
    c, s = np.cos(2.5), np.sin(2.5)
    turn = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    R, t = turn @ random_rotation(rng), rng.normal(size=3)  # P: x = R y + t
    raw = (np.vstack([body[::2], table]) - t) @ R
    plane = softhd.find_dominant_plane(raw, distance=0.01)
    assert plane["inliers"] == len(table)
    scan = raw[softhd.remove_dominant_plane(raw, distance=0.01)]
    assert len(scan) == len(body[::2])
    clamp = (np.array([-1.0, 0, 0]), R.T @ np.array([-1.0, 0, 0]))
    r = softhd.align(body, scan, fixture=([0, 0, 1], -0.05), table=plane, clamp=clamp)
    M = r["matrix"]
    assert angle(M[:3, :3], R) < 1e-9
    assert np.linalg.norm(M[:3, 3] - t) < 1e-9
    n = np.asarray(plane["normal"]) * np.sign(np.median(scan @ plane["normal"] - plane["offset"]))
    assert np.linalg.norm(M[:3, :3] @ n - [0, 0, 1]) < 1e-12
    with pytest.raises(softhd.InvalidArgument, match="fixture needs the scan's table plane"):
        softhd.align(body, scan, fixture=([0, 0, 1], -0.05))
    with pytest.raises(softhd.InvalidArgument, match="fixture.normal has zero length"):
        softhd.align(body, scan, fixture=([0, 0, 0], -0.05), table=plane)
    with pytest.raises(softhd.InvalidArgument, match="clamp is the fixture's clamp side"):
        softhd.align(body, scan, table=plane, clamp=clamp)


def bent_bar_surface(rng, count=300):
    """(nodes, triangles, samples): a 1 x 0.2 x 0.1 bar's 11 x 3 x 3 grid bent by a cubic
    (Jacobian determinant 1), its boundary triangles, and `count` points uniform in area on them."""
    n = (11, 3, 3)
    g = np.meshgrid(*[np.linspace(0, s, k) for s, k in zip((1.0, 0.2, 0.1), n)], indexing="ij")
    nodes = np.stack([x.ravel() for x in g], 1)
    nodes[:, 2] += 0.4 * nodes[:, 0] ** 3
    tri = synthetic.box_surface(n)
    a, b, c = (nodes[tri[:, k]] for k in range(3))
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    k = rng.choice(len(tri), count, p=area / area.sum())
    r, w = np.sqrt(rng.random(count)), rng.random(count)
    samples = a[k] * (1 - r)[:, None] + b[k] * (r * (1 - w))[:, None] + c[k] * (r * w)[:, None]
    return nodes, tri, samples


def test_surface_points_between_the_nodes_recovered_with_body_triangles():
    """A scan of points on a bent bar's surface but between its nodes (300 area-weighted
    samples), moved: with body_triangles the pose to rounding (asserted 1e-9, the finish's step
    tolerance 1e-10 L with room) and the residuals are distances to the surface (0); with the
    nodes alone only to their spacing. Bad triangles are refused naming the argument."""
    rng = np.random.default_rng(4)
    nodes, tri, samples = bent_bar_surface(rng)
    R, t = random_rotation(rng), np.array([0.3, -0.2, 0.4])
    scan = (samples - t) @ R  # P^-1(y) = R^T (y - t)
    res = softhd.align(nodes, scan, body_triangles=tri, threads=2)
    assert angle(res["matrix"][:3, :3], R) < 1e-9
    assert np.linalg.norm(res["matrix"][:3, 3] - t) < 1e-9
    assert res["residuals"].max() < 1e-9
    bare = softhd.align(nodes, scan, threads=2)
    assert angle(bare["matrix"][:3, :3], R) > 1e-6
    with pytest.raises(TypeError, match="body_triangles must hold integers"):
        softhd.align(nodes, scan, body_triangles=tri.astype(float))
    with pytest.raises(softhd.InvalidArgument, match="body_triangles must name the body's points"):
        softhd.align(nodes, scan, body_triangles=tri + len(nodes))


def test_surface_with_the_fixture_recovered_on_the_constraint():
    """The same bent bar's surface samples over a table (z = -0.05), turned about the table and
    tilted: with the fixture and body_triangles the constrained point-to-plane fit recovers the
    pose to rounding (asserted 1e-9) and keeps the table's normal (asserted 1e-12); the fixture
    with the nodes alone does not (its pairs are nodes up to L/20 away)."""
    rng = np.random.default_rng(1)
    nodes, tri, samples = bent_bar_surface(rng)
    table = np.c_[rng.uniform(-0.2, 1.2, 300), rng.uniform(-0.2, 0.4, 300), np.full(300, -0.05)]
    th = 1.1
    turn = np.array([[np.cos(th), -np.sin(th), 0], [np.sin(th), np.cos(th), 0], [0, 0, 1]])
    R, t = turn @ random_rotation(rng), np.array([0.3, 0.1, 0.0])
    scan = (np.vstack([samples, table]) - t) @ R  # body = R scan + t
    plane = softhd.find_dominant_plane(scan, distance=1e-3)
    kept = scan[softhd.remove_dominant_plane(scan, distance=1e-3)]
    fixture = (np.array([0.0, 0.0, 1.0]), -0.05)
    res = softhd.align(nodes, kept, fixture=fixture, table=plane, body_triangles=tri, threads=2)
    M = res["matrix"]
    assert angle(M[:3, :3], R) < 1e-9
    assert np.linalg.norm(M[:3, 3] - t) < 1e-9
    ns = np.asarray(plane["normal"]) * np.sign(np.median(kept @ plane["normal"] - plane["offset"]))
    assert np.linalg.norm(M[:3, :3] @ ns - [0, 0, 1]) < 1e-12
    bare = softhd.align(nodes, kept, fixture=fixture, table=plane, threads=2)
    assert angle(bare["matrix"][:3, :3], R) > 1e-6
