"""The array rule: C-contiguous float64 inputs reach the library without a copy; other real
inputs are converted once to float64; non-real data is refused."""

import tracemalloc

import numpy as np
import pytest

import softhd
from softhd import _core
from conftest import random_cloud


def test_contiguous_float64_is_handed_over_in_place(rng):
    X, VX = random_cloud(rng, 100)
    passed = softhd._as_float64(X, "X")
    assert passed is X  # the Python layer passes the array itself ...
    # ... and the argument caster of every cloud argument gives C++ the caller's memory.
    assert _core._data_address(passed) == X.ctypes.data
    assert _core._data_address(VX) == VX.ctypes.data


def test_the_core_refuses_to_convert(rng):
    X, _ = random_cloud(rng, 10)
    Y, _ = random_cloud(rng, 10)
    t = _core.Target(Y, None, alpha=4, beta=4, gamma=2, eps=1e-3, method="exact", tol=1e-6,
                     threads=0)
    for bad in (X.astype(np.float32), np.asfortranarray(X), X[::2]):
        with pytest.raises(TypeError):  # a copy would be needed: the core never makes one
            t.evaluate(bad, None, fields=False, gradient=False, gradient_volumes=False,
                       gradient_target=False)
        with pytest.raises(TypeError):
            _core._data_address(bad)


def test_no_numpy_copy_of_a_large_float64_input():
    # A 2e6 x 3 cloud is 48 MB: a copy made in Python would show in the traced peak.
    X = np.zeros((2_000_000, 3))
    X[:, 0] = np.arange(2_000_000)
    tracemalloc.start()
    softhd._as_float64(X, "X")
    _core._data_address(softhd._as_float64(X, "X"))
    peak = tracemalloc.get_traced_memory()[1]
    converted = softhd._as_float64(X.astype(np.float32), "X")
    peak_converted = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 1_000_000
    assert peak_converted >= X.nbytes  # the conversion is visible, so the check can fail
    assert converted.dtype == np.float64


@pytest.mark.parametrize("convert", [
    lambda a: a.astype(np.float32).astype(np.float64),  # float64 values of float32 data
    lambda a: np.asfortranarray(a),
    lambda a: a.tolist(),
])
def test_other_layouts_give_the_same_value(rng, convert):
    X, _ = random_cloud(rng, 40)
    Y, _ = random_cloud(rng, 30)
    X32 = X.astype(np.float32)
    want = softhd.distance(X32.astype(np.float64), Y).rho
    assert softhd.distance(X32, Y).rho == want  # float32 converted exactly to float64
    assert softhd.distance(convert(X), Y).rho == pytest.approx(softhd.distance(X, Y).rho,
                                                               rel=1e-7)


def test_integer_points_are_converted():
    X = np.array([[0, 0], [1, 0], [0, 1]])
    Y = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    assert softhd.distance(X, Y).rho == softhd.distance(Y, Y).rho


@pytest.mark.parametrize("bad", [np.zeros((3, 2), dtype=bool), np.zeros((3, 2), dtype=complex),
                                 np.array([["a", "b"]] * 3)])
def test_non_real_data_is_refused(bad):
    with pytest.raises(TypeError, match="real numbers"):
        softhd.distance(bad, np.zeros((3, 2)))


def test_result_arrays_are_views_of_the_result(rng):
    X, _ = random_cloud(rng, 20)
    Y, _ = random_cloud(rng, 20)
    r = softhd.distance(X, Y, gradient=True)
    g = r.gradient
    assert g.shape == (20, 3) and not g.flags.owndata  # no copy on the way out either
    assert r.gradient.ctypes.data == g.ctypes.data
