"""Scene.load / Scene.forward against physics that needs no solver and against the
command-line tool (the same library call, fe::solve_forward: equal to 1e-14)."""

import numpy as np
import pytest

import softhd
from conftest import SMALL_2D, SMALL_ARC


def test_scene_properties(scene_file):
    scene = softhd.Scene.load(scene_file(SMALL_2D))
    assert scene.name == "small_2d" and scene.dim == 2
    assert scene.nodes.shape == (9 * 5, 2)  # Q2: (2*4+1) x (2*2+1) nodes
    assert scene.num_controls == 5 * 3  # vertex controls: (4+1) x (2+1)
    assert scene.control_bounds == (-1e5, 0.0)
    assert not scene.has_target


def test_rest_state_without_tension(scene_file):
    scene = softhd.Scene.load(scene_file(SMALL_2D))
    f = scene.forward(0.0, probes=[[2.0, 0.4], [1.0, 0.2]])
    assert f.converged
    assert np.all(f.displacements == 0.0) and f.energy == 0.0
    assert f.volume == pytest.approx(2.0 * 0.4, rel=1e-14)  # the undeformed area
    np.testing.assert_array_equal(f.probes, np.zeros((2, 2)))


def test_contraction_shortens_the_fibers(scene_file):
    scene = softhd.Scene.load(scene_file(SMALL_2D))
    f = scene.forward(-2e4, probes=[[2.0, 0.2]])
    assert f.converged and f.displacements.shape == (45, 2)
    assert f.probes[0, 0] < 0.0  # the free end moves towards the clamp
    assert f.min_J > 0.0
    # The same control given per node, and the same state reached by grid sequencing.
    g = scene.forward(np.full(scene.num_controls, -2e4), probes=[[2.0, 0.2]])
    np.testing.assert_array_equal(g.displacements, f.displacements)
    for levels in (1, 2):
        c = scene.forward(-2e4, coarse_levels=levels, probes=[[2.0, 0.2]])
        assert c.converged
        np.testing.assert_allclose(c.probes, f.probes, rtol=1e-7, atol=1e-12)
    # A non-uniform control through the grid sequence reaches the same equilibrium too.
    m = np.linspace(-3e4, 0.0, scene.num_controls)
    np.testing.assert_allclose(scene.forward(m, coarse_levels=1).displacements,
                               scene.forward(m, coarse_levels=0).displacements, rtol=1e-6,
                               atol=1e-12)


@pytest.mark.parametrize("scene_dict, probe", [(SMALL_2D, [2.0, 0.3]),
                                              (SMALL_ARC, [10.0, 1.0, 0.05])])
def test_equals_the_command_line_tool(scene_file, cli, tmp_path, scene_dict, probe):
    path = scene_file(scene_dict)
    j = cli("forward", path, "--control-uniform", -3e4, "--probe", ",".join(map(str, probe)),
            "--threads", 1, "--out", tmp_path / "out")
    f = softhd.Scene.load(path).forward(-3e4, probes=[probe], threads=1)
    assert f.converged and j["converged"]
    assert f.energy == pytest.approx(j["energy"], rel=1e-14)
    assert f.volume == pytest.approx(j["volume"], rel=1e-14)
    assert f.min_J == pytest.approx(j["min_J"], rel=1e-14)
    np.testing.assert_allclose(f.probes[0], j["probes"][0]["u"], rtol=1e-14, atol=1e-300)
    assert f.newton_iterations == j["newton_iterations"]


def test_forward_takes_numpy_scalars(scene_file):
    """A uniform control given as a NumPy scalar or a 0-d array is the same number."""
    scene = softhd.Scene.load(scene_file(SMALL_2D))
    ref = scene.forward(-2e4).displacements
    for m in (np.float32(-2e4), np.float64(-2e4), np.int64(-20000), np.array(-2e4)):
        np.testing.assert_array_equal(scene.forward(m).displacements, ref)


def test_control_at_nodes_reproduces_linear_fields(scene_file):
    scene = softhd.Scene.load(scene_file(SMALL_2D))
    X = scene.control_positions
    m = -1e4 * (1.0 + X[:, 0] + 2.0 * X[:, 1])  # Q1 interpolation is exact for it
    nodes = scene.nodes
    np.testing.assert_allclose(scene.control_at_nodes(m),
                               -1e4 * (1.0 + nodes[:, 0] + 2.0 * nodes[:, 1]), rtol=1e-13)
    with pytest.raises(ValueError, match="controls"):
        scene.control_at_nodes(m[:-1])
