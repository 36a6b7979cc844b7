"""softhd.optimise: the callback sees every iteration and can end the run; results equal the
command-line tool's."""

import json

import numpy as np
import pytest

import softhd
from conftest import SMALL_2D, SMALL_ARC


@pytest.fixture
def manufactured(scene_file, tmp_path):
    """The small 2D scene and a target made by a known control (its deformed nodes)."""
    scene = softhd.Scene.load(scene_file(SMALL_2D))
    f = scene.forward(-2e4)
    target = scene.nodes + f.displacements
    softhd.write_cloud(tmp_path / "t.ply", target)
    path = scene_file({**SMALL_2D, "target": {"kind": "cloud", "file": "t.ply"}}, "with_t.json")
    return softhd.Scene.load(path), path, target


def test_callback_returning_false_stops_the_run(manufactured):
    scene, _, target = manufactured
    seen = []

    def callback(record):
        seen.append((record.iteration, record.J, record.control.shape))
        return record.iteration < 2  # False at the second iteration

    r = softhd.optimise(scene, target, max_iter=20, callback=callback)
    assert r.iterations == 2 and len(r.history) == 2
    assert r.termination == "stopped by the caller" and not r.converged
    assert r.status == "stopped"
    assert [s[0] for s in seen] == [1, 2]
    assert seen[0][2] == (scene.num_controls,)
    assert r.J_final == seen[1][1] and r.J_final < r.rho_start
    assert r.displacements.shape == scene.nodes.shape


def test_callback_returning_none_continues(manufactured):
    scene, _, target = manufactured
    calls = []
    r = softhd.optimise(scene, target, max_iter=3, callback=lambda rec: calls.append(rec))
    assert r.iterations == 3 == len(calls)
    assert r.termination == "the iteration limit was reached"
    assert r.status == "iteration_limit"
    assert "iteration_limit (the iteration limit was reached): 3 iterations" in repr(r)


def test_callback_exception_propagates(manufactured):
    scene, _, target = manufactured

    class Boom(Exception):
        pass

    def callback(record):
        raise Boom(f"at iteration {record.iteration}")

    with pytest.raises(Boom, match="at iteration 1"):
        softhd.optimise(scene, target, max_iter=5, callback=callback)


def test_target_forms_agree(manufactured, tmp_path):
    scene, path, target = manufactured
    a = softhd.optimise(scene, max_iter=2)  # the scene's own target (t.ply)
    b = softhd.optimise(scene, str(tmp_path / "t.ply"), max_iter=2)
    c = softhd.optimise(scene, (target, np.ones(len(target))), max_iter=2)
    assert a.rho_final == b.rho_final == c.rho_final


def test_equals_the_command_line_tool(manufactured, cli, tmp_path):
    scene, path, _ = manufactured
    j = cli("optimise", path, "--max-iter", 4, "--threads", 1, "--out", tmp_path / "run",
            "--vtu-every", 0, "--quiet")
    r = softhd.optimise(scene, max_iter=4, threads=1)
    assert r.iterations == j["iterations"] and r.termination == j["termination"]
    assert r.rho_final == pytest.approx(j["rho_final"], rel=1e-14)
    assert r.J_final == pytest.approx(j["J_final"], rel=1e-14)
    assert r.rho_start == pytest.approx(j["rho_start"], rel=1e-14)


def test_arc_target_has_a_known_map(scene_file):
    scene = softhd.Scene.load(scene_file(SMALL_ARC))
    assert scene.has_target
    r = softhd.optimise(scene, max_iter=2)
    assert r.floor_matched is not None and r.floor_matched > 0.0
    assert r.shape_error_max is not None and r.shape_error_rms <= r.shape_error_max
    assert "arc" in r.target
