"""softhd.distance / Target against an independent NumPy oracle of docs/formulation.md §2 and against the
command-line tool (the same library call: equal to 1e-14)."""

import numpy as np
import pytest

import softhd
from conftest import random_cloud
from spec_reference import hausdorff_numpy, rho_numpy


@pytest.mark.parametrize("d", [2, 3])
@pytest.mark.parametrize("params", [dict(), dict(alpha=8.0, beta=2.0, gamma=3.0, eps=0.05)])
def test_value_matches_the_spec_formula(rng, d, params):
    X, VX = random_cloud(rng, 40, d)
    Y, VY = random_cloud(rng, 57, d, shift=0.3)
    rho, A, B = rho_numpy(X, Y, VX, VY, **params)
    r = softhd.distance(X, Y, VX, VY, **params)
    assert r.rho == pytest.approx(rho, rel=1e-12)
    assert r.A == pytest.approx(A, rel=1e-12)
    assert r.B == pytest.approx(B, rel=1e-12)
    assert r.gradient is None and r.field_target is None  # nothing computed unasked


def test_tree_method_within_its_tolerance(rng):
    X, _ = random_cloud(rng, 300)
    Y, _ = random_cloud(rng, 250, shift=0.2)
    exact = softhd.distance(X, Y).rho
    tree = softhd.distance(X, Y, method="tree", tol=1e-8).rho
    assert tree == pytest.approx(exact, rel=1e-8)


def test_nearest_is_the_hausdorff_distance(rng):
    X, _ = random_cloud(rng, 50)
    Y, _ = random_cloud(rng, 30, shift=0.5)
    H, a, b = hausdorff_numpy(X, Y)
    for r in (softhd.hausdorff_nearest(X, Y), softhd.distance(X, Y, method="nearest")):
        assert (r.rho, r.A, r.B) == pytest.approx((H, a, b), rel=1e-14)


def test_gradient_matches_finite_differences(rng):
    X, VX = random_cloud(rng, 12, 2)
    Y, VY = random_cloud(rng, 9, 2, shift=0.4)
    r = softhd.distance(X, Y, VX, VY, eps=0.05, gradient=True, gradient_volumes=True,
                        gradient_target=True)
    h = 1e-6

    def fd(array, index):
        plus, minus = array.copy(), array.copy()
        plus[index] += h
        minus[index] -= h
        args = {"X": X, "Y": Y, "VX": VX, "VY": VY}
        name = next(k for k, v in args.items() if v is array)
        lo = rho_numpy(**{**args, name: minus}, eps=0.05)[0]
        hi = rho_numpy(**{**args, name: plus}, eps=0.05)[0]
        return (hi - lo) / (2 * h)

    for idx in [(0, 0), (5, 1), (11, 0)]:
        assert r.gradient[idx] == pytest.approx(fd(X, idx), rel=1e-6, abs=1e-9)
    for idx in [(0, 1), (8, 0)]:
        assert r.gradient_target[idx] == pytest.approx(fd(Y, idx), rel=1e-6, abs=1e-9)
    for i in [0, 7]:
        assert r.gradient_volumes[i] == pytest.approx(fd(VX, (i,)), rel=1e-6, abs=1e-9)


def test_target_reused_equals_one_shot(rng):
    Y, VY = random_cloud(rng, 80)
    target = softhd.Target(Y, VY, alpha=6.0, eps=1e-2)
    assert (target.size, target.dim) == (80, 3)
    for shift in (0.0, 0.5):
        X, VX = random_cloud(rng, 60, shift=shift)
        a = target.evaluate(X, VX, fields=True, gradient=True)
        b = softhd.distance(X, Y, VX, VY, alpha=6.0, eps=1e-2, fields=True, gradient=True)
        assert a.rho == b.rho
        np.testing.assert_array_equal(a.gradient, b.gradient)
        np.testing.assert_array_equal(a.field_moving, b.field_moving)
        assert a.field_target.shape == (80,) and a.field_moving.shape == (60,)


def test_threads_do_not_change_the_value(rng):
    X, _ = random_cloud(rng, 200)
    Y, _ = random_cloud(rng, 150)
    one = softhd.distance(X, Y, threads=1).rho
    two = softhd.distance(X, Y, threads=2).rho
    assert two == pytest.approx(one, rel=1e-14)


def test_equals_the_command_line_tool(rng, tmp_path, cli):
    X, VX = random_cloud(rng, 300)
    Y, VY = random_cloud(rng, 200, shift=0.25)
    softhd.write_cloud(tmp_path / "x.ply", X, VX)
    softhd.write_cloud(tmp_path / "y.txt", Y, VY)
    for method in ("exact", "tree", "nearest"):
        j = cli("distance", tmp_path / "x.ply", tmp_path / "y.txt", "--method", method,
                "--alpha", 6, "--eps", 0.01, "--threads", 1)
        r = softhd.distance(X, Y, VX, VY, method=method, alpha=6, eps=0.01, threads=1)
        assert (r.rho, r.A, r.B) == pytest.approx((j["rho"], j["A"], j["B"]), rel=1e-14)


def test_gradient_equals_the_command_line_tool(rng, tmp_path, cli):
    X, VX = random_cloud(rng, 100)
    Y, VY = random_cloud(rng, 70, shift=0.25)
    softhd.write_cloud(tmp_path / "x.ply", X, VX)
    softhd.write_cloud(tmp_path / "y.ply", Y, VY)
    cli("distance", tmp_path / "x.ply", tmp_path / "y.ply", "--grad", tmp_path / "g.txt",
        "--threads", 1)
    g = np.loadtxt(tmp_path / "g.txt")  # x y z drho/dx drho/dy drho/dz drho/dV
    r = softhd.distance(X, Y, VX, VY, gradient=True, gradient_volumes=True, threads=1)
    np.testing.assert_allclose(r.gradient, g[:, 3:6], rtol=1e-14, atol=0)
    np.testing.assert_allclose(r.gradient_volumes, g[:, 6], rtol=1e-14, atol=0)


def test_clouds_round_trip_through_files(rng, tmp_path):
    X, VX = random_cloud(rng, 33, 2)
    for name in ("c.ply", "c.txt"):
        softhd.write_cloud(tmp_path / name, X, VX)
        P, V = softhd.read_cloud(tmp_path / name, dim=2)
        np.testing.assert_array_equal(P, X)
        np.testing.assert_array_equal(V, VX)
        assert P.flags.c_contiguous and P.dtype == np.float64
    softhd.write_cloud(tmp_path / "ones.ply", X)
    assert np.all(softhd.read_cloud(tmp_path / "ones.ply")[1] == 1.0)


def test_the_gil_is_released_during_the_computation(rng):
    # With a huge switch interval Python threads trade the GIL only when its holder lets it
    # go: the main loop below (which lets go at every sleep(0)) can run while the worker is
    # inside softhd only if softhd released the GIL; otherwise it counts a handful at most.
    import sys
    import threading
    import time

    X, _ = random_cloud(rng, 3000)
    Y, _ = random_cloud(rng, 3000)
    done = threading.Event()
    result = []

    def work():
        result.append(softhd.distance(X, Y, gradient=True, threads=1).rho)
        done.set()

    interval = sys.getswitchinterval()
    sys.setswitchinterval(1000.0)
    try:
        t = threading.Thread(target=work)
        t.start()
        count = 0
        while not done.is_set():
            count += 1
            time.sleep(0)
        t.join()
    finally:
        sys.setswitchinterval(interval)
    assert result and count > 100


# --- The distance forms of docs/formulation.md §8, against the NumPy oracle written from the
# formulas (fields from spec_reference's directed mean, the cap and the masks applied here). ---

def _fields_numpy(P, VP, Q, alpha=4.0, eps=1e-3):
    """d~_P(q) for every q of Q (docs/formulation.md §2.1), NumPy float64."""
    r = np.sqrt(((Q[:, None, :] - P[None, :, :]) ** 2).sum(axis=2))
    s = ((VP / VP.sum())[None, :] * (r + eps) ** (-alpha)).sum(axis=1)
    return s ** (-1.0 / alpha) - eps


def _cap_numpy(d, c, q):
    return d if c == 0.0 else (d ** -q + c ** -q) ** (-1.0 / q)


def _mean_numpy(d, w, beta=4.0):
    return ((w / w.sum()) * d ** beta).sum() ** (1.0 / beta)


@pytest.mark.parametrize("distance", ["symmetric", "scan_to_body", "visible"])
@pytest.mark.parametrize("cap", [0.0, 0.3])
def test_forms_match_their_formulas(rng, distance, cap):
    X, VX = random_cloud(rng, 30)
    Y, VY = random_cloud(rng, 25, shift=0.4)
    visible = rng.random(30) < 0.6 if distance == "visible" else None
    r = softhd.distance(X, Y, VX, VY, distance=distance, cap=cap, cap_q=3.0, camera_mask=visible,
                        fields=True)
    dy, dx = _fields_numpy(X, VX, Y), _fields_numpy(Y, VY, X)
    assert r.field_target == pytest.approx(dy, rel=1e-12)  # raw fields, before the cap
    A = _mean_numpy(_cap_numpy(dy, cap, 3.0), VY)
    assert r.A == pytest.approx(A, rel=1e-12)
    if distance == "scan_to_body":
        assert r.B == 0.0 and r.rho == pytest.approx(A, rel=1e-12)
        return
    mask = visible if distance == "visible" else np.ones(30, bool)
    B = _mean_numpy(_cap_numpy(dx[mask], cap, 3.0), VX[mask])
    assert r.B == pytest.approx(B, rel=1e-12)
    assert r.rho == pytest.approx(np.sqrt((A ** 2 + B ** 2) / 2), rel=1e-12)


def test_forms_refused_naming_the_option(rng):
    X, _ = random_cloud(rng, 10)
    Y, _ = random_cloud(rng, 12)
    with pytest.raises(softhd.InvalidArgument, match="distance"):
        softhd.distance(X, Y, distance="both")
    with pytest.raises(softhd.InvalidArgument, match="cap.c"):
        softhd.distance(X, Y, cap=-1.0)
    with pytest.raises(softhd.InvalidArgument, match="cap.q"):
        softhd.distance(X, Y, cap=1.0, cap_q=0.0)
    with pytest.raises(softhd.InvalidArgument, match="visible"):
        softhd.distance(X, Y, distance="visible")
    with pytest.raises(softhd.InvalidArgument, match="visible: the camera_mask has 3 entries"):
        softhd.distance(X, Y, distance="visible", camera_mask=[True, False, True])
    # the retired keyword is refused naming the new one
    with pytest.raises(TypeError, match="visible is now camera_mask"):
        softhd.distance(X, Y, distance="visible", visible=np.ones(10, bool))
    # below the accepted ranges of docs/formulation.md §8.3: rho was 0 or the constant cap
    with pytest.raises(softhd.InvalidArgument, match=r"cap.q must be finite and >= 0.001"):
        softhd.distance(X, Y, cap=1.0, cap_q=1e-300)
    with pytest.raises(softhd.InvalidArgument, match=r"cap \(cap.c\) 1e-300 is below"):
        softhd.distance(X, Y, cap=1e-300)
    # camera_mask holds booleans or 0/1; 0.5 or 2 is not read as True
    with pytest.raises(softhd.InvalidArgument, match="camera_mask must hold booleans"):
        softhd.distance(X, Y, distance="visible", camera_mask=np.r_[0.5, np.ones(9)])


def test_forms_equal_the_command_line(rng, tmp_path, cli):
    X, VX = random_cloud(rng, 20)
    Y, VY = random_cloud(rng, 15, shift=0.3)
    softhd.write_cloud(tmp_path / "x.txt", X, VX)
    softhd.write_cloud(tmp_path / "y.txt", Y, VY)
    visible = rng.random(20) < 0.5
    visible[0] = True
    (tmp_path / "seen.txt").write_text("".join(f"{int(v)}\n" for v in visible))
    j = cli("distance", tmp_path / "x.txt", tmp_path / "y.txt", "--distance", "visible",
            "--camera-mask", tmp_path / "seen.txt", "--cap", 0.2, "--cap-q", 2)
    r = softhd.distance(X, Y, VX, VY, distance="visible", camera_mask=visible, cap=0.2,
                        cap_q=2.0)
    assert (j["rho"], j["A"], j["B"]) == pytest.approx((r.rho, r.A, r.B), rel=1e-14)
    assert j["distance"] == "visible" and j["cap"] == 0.2


@pytest.mark.parametrize("distance", ["symmetric", "scan_to_body"])
def test_hessian_product_matches_differences_of_the_gradient(rng, distance):
    X, VX = random_cloud(rng, 15, 3)
    Y, VY = random_cloud(rng, 20, 3, shift=0.3)
    target = softhd.Target(Y, VY, alpha=3.0, beta=2.5, gamma=1.5, eps=0.02)
    r = target.evaluate(X, VX, hessian=True, distance=distance, cap=0.4)
    assert r.gradient is None  # kept for the products, not returned unasked
    V = rng.standard_normal(X.shape)
    HV = target.hessian_product(r, V)
    assert HV.shape == X.shape
    h = 1e-5

    def grad(Z):
        return target.evaluate(Z, VX, gradient=True, distance=distance, cap=0.4).gradient

    fd = (grad(X + h * V) - grad(X - h * V)) / (2 * h)
    assert np.linalg.norm(HV - fd) < 1e-6 * np.linalg.norm(HV)
    GV = target.hessian_product(r, V, part="gauss_newton")
    assert np.sum(V * GV) >= 0.0 and np.sum(V * (GV - HV)) >= 0.0
    with pytest.raises(softhd.InvalidArgument, match="gauss_newton"):
        target.hessian_product(r, V, part="newton")
