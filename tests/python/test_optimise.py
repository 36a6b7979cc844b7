"""softhd.optimise: the callback sees every iteration and can end the run; results equal the
command-line tool's."""

import csv
import inspect
import json
import math
import os
import re
import subprocess

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


def test_distance_form_from_the_scene_or_the_keywords(scene_file):
    """The target block's "distance"/"cap" keys, replaced as a whole by optimise's keywords
    (docs/formulation.md §8); the run's target line names the form."""
    spec = dict(SMALL_ARC, target=dict(SMALL_ARC["target"], distance="scan_to_body", cap=5.0))
    scene = softhd.Scene.load(scene_file(spec))
    r = softhd.optimise(scene, max_iter=1)
    assert "distance scan_to_body, cap c = 5" in r.target
    assert all(it.B == 0.0 and it.rho == it.A for it in r.history)
    r = softhd.optimise(scene, max_iter=1, distance="symmetric")
    assert "distance" not in r.target and r.history[-1].B > 0.0
    with pytest.raises(softhd.InvalidArgument, match="distance visible needs the camera"):
        softhd.optimise(scene, max_iter=1, distance="visible")


SMALL_PLATE = {
    "name": "small_plate",
    "mesh": {"type": "box", "lower": [0, 0, 0], "upper": [2, 0.4, 0.2], "cells": [8, 2, 2],
             "order": 1},
    "material": {"model": "mooney_rivlin", "a": 1e5, "b": 2e4, "c": 3e5},
    "fibers": [1, 0, 0], "clamp": ["x0"],
    "control": {"space": "vertex", "lower": -1e5, "upper": 0, "initial": 0},
    "target": {"kind": "arc", "angle": 1.2, "cells": [16, 4, 4]},
}

HISTORY_COLUMNS = ["iteration", "evaluation", "J", "rho", "A", "B", "rho_over_floor",
                   "projected_gradient_norm", "newton_iterations", "factorizations"]


def as_in_the_csv(value):
    """A number as history.csv writes it: 10 significant digits (C++ precision 10, %.10g), a
    non-finite one (a ratio without a floor) empty."""
    return format(value, ".10g") if math.isfinite(value) else ""


@pytest.mark.parametrize("cli_options, py_options", [
    ([], {}),  # the defaults on both sides
    (["--alpha", 5, "--eps", 2e-3, "--move-limit", 0.2, "--volumes", "deformed",
      "--tikhonov-mass", 1e-12, "--rel-tol", 0, "--coarse-levels", 0],
     dict(alpha=5, eps=2e-3, move_limit=0.2, volumes="deformed", tikhonov_mass=1e-12,
          rel_tol=0, coarse_levels=0)),
    (["--levels", 2], dict(levels=2)),  # a coarse level's rows first, then 8 on the mesh
    (["--levels", 2, "--coarse-iterations", 2, "--switch-decrease", 0, "--coarse-tol", 0.1],
     dict(levels=2, coarse_iterations=2, switch_decrease=0, coarse_tol=0.1)),
])
def test_history_equals_the_command_line_tools(scene_file, cli, tmp_path, cli_options,
                                               py_options):
    """The same scene and options through softhd optimise and softhd.optimise: history.csv
    holds Python's iterations, number for number as written there (the timings aside). Eight
    iterations: past the solver's renewal after the fifth (docs/formulation.md §4.6), which
    the command line tool makes as it saves its checkpoint and Python without saving one."""
    path = scene_file(SMALL_PLATE)
    cli("optimise", path, "--max-iter", 8, "--threads", 1, "--out", tmp_path / "run",
        "--vtu-every", 0, "--quiet", *cli_options)
    with open(tmp_path / "run" / "history.csv") as f:
        rows = list(csv.DictReader(f))
    r = softhd.optimise(softhd.Scene.load(path), max_iter=8, threads=1, **py_options)
    assert len(rows) == len(r.history)
    assert [it.level for it in r.history].count(0) == 8
    assert ("levels" in py_options) == (r.history[0].level == 1)
    if "coarse_iterations" in py_options:  # the keyword reaches the coarse level
        assert [it.level for it in r.history].count(1) == py_options["coarse_iterations"]
    for row, it in zip(rows, r.history):
        for column in HISTORY_COLUMNS + ["level"]:
            assert row[column] == as_in_the_csv(getattr(it, column)), (column, row, it)


def test_coarse_level_keywords_act_on_the_coarse_level(scene_file):
    """levels=2: switch_decrease=0 runs the coarse level's min(coarse_iterations, max_iter) = 6
    iterations, 0.9 ends it earlier (rho decreasing by less than 90 % twice); coarse_iterations
    caps it. coarse_tol reaches the run's validation (its effect on the coarse level's tree
    tolerance: tests/test_optimise_cli.cpp, where the level's checkpoint records it)."""
    scene = softhd.Scene.load(scene_file(SMALL_PLATE))

    def coarse_iterations(**kw):
        r = softhd.optimise(scene, max_iter=6, rel_tol=0, threads=1, levels=2, **kw)
        return [it.level for it in r.history].count(1)

    assert coarse_iterations(switch_decrease=0) == 6
    assert coarse_iterations(switch_decrease=0.9) < 6
    assert coarse_iterations(switch_decrease=0, coarse_iterations=3) == 3
    for keyword, value, message in (("alpha", 0.0, "^alpha: Hausdorff parameter alpha must be"),
                                    ("rel_tol", -1.0, "^rel_tol: optimizer: relative_change"),
                                    ("switch_decrease", 1.0, r"switch_decrease must be in \[0, 1\)"),
                                    ("coarse_tol", 1.0, r"coarse_tol must be in \(0, 1\)"),
                                    ("coarse_iterations", 0, "coarse_iterations must be >= 1")):
        with pytest.raises(softhd.InvalidArgument, match=message):
            softhd.optimise(scene, max_iter=1, **{keyword: value})


@pytest.fixture
def cli_help():
    """The help text of a softhd command."""
    def run(command):
        p = subprocess.run([os.environ["SOFTHD_CLI"], command, "--help"], capture_output=True,
                           text=True)
        assert p.returncode == 0, p.stderr
        return p.stdout

    return run


def test_defaults_are_the_command_line_tools(cli_help):
    """optimise_defaults() names every option of optimise, and each default is the one
    softhd optimise --help states."""
    defaults = softhd.optimise_defaults()
    keywords = [p.name for p in inspect.signature(softhd.optimise).parameters.values()
                if p.kind == p.KEYWORD_ONLY and p.name != "callback"]
    assert sorted(defaults) == sorted(keywords)
    text = " ".join(cli_help("optimise").split())
    flags = {"max_iter": "--max-iter N iterations", "rel_tol": "--rel-tol R stop when J changes "
             "by less than R relative", "algorithm": "--algorithm A mma | ccsaq | lbfgs | "
             "slsqp | newton", "hessian": "--hessian H newton's Hessian-vector product: full | "
             "gauss_newton",
             "move_limit": "bound range", "particles": "--particles P nodes | quadrature | boundary: "
             "the moving cloud", "volumes": "--volumes V reference | deformed particle volumes",
             "method": "--method M exact | tree: the distance's pair sums",
             "tol": "relative error bound on every kernel sum", "tikhonov_mass":
             "--tikhonov-mass M (M/2) int m^2", "tikhonov_grad": "--tikhonov-grad E (E/2) int "
             "|grad m|^2", "coarse_levels": "mesh file of order 2 as P1/Q1 on its vertices",
             "levels": "then the next finer level from its control",
             "refined_move_limit": "the move limit of each level started from a coarser "
             "level's control", "coarse_iterations": "--coarse-iterations K",
             "switch_decrease": "--switch-decrease S", "coarse_tol": "--coarse-tol T",
             "pose_move": "as a fraction of the control's, in (0, 1]",
             "pose_method": "--pose-method joint|projection how the pose is refined"}
    for name, before in flags.items():
        m = re.search(re.escape(before) + r" \(default ([^;,:)]+)", text)
        assert m, name
        given = m.group(1).strip()
        expected = defaults[name]
        if isinstance(expected, str):
            assert given == expected, name
        else:
            assert float(given) == expected, name
    m = re.search(r"functional parameters \(default (\S+) (\S+) (\S+) ([^\s;)]+)[;)]", text)
    assert [float(v) for v in m.groups()] == [defaults[k] for k in ("alpha", "beta", "gamma",
                                                                   "eps")]


def test_keywords_are_the_fields_of_the_table():
    """Every keyword of optimise sets a field of the run's options table (the one `softhd
    optimise --help` is checked against in tests/test_run_fields.cpp), and every field of the
    table has a keyword or says why not; callback is Python's own."""
    fields = softhd._core.optimise_fields()
    keywords = {p.name for p in inspect.signature(softhd.optimise).parameters.values()
                if p.name != "scene"}
    table = {f["keyword"] for f in fields if f["keyword"]}
    assert keywords - {"callback"} == table
    for f in fields:
        assert f["keyword"] or f["why_not"], f["path"]
    # The keyword is the flag without its dashes, with underscores (where both exist).
    for f in fields:
        if f["keyword"] and f["flag"]:
            assert f["flag"] == "--" + f["keyword"].replace("_", "-"), f


def test_camera_frame_target_returns_the_pose(scene_file, tmp_path):
    """A scene target in the camera's frame (docs/formulation.md §8.10): the body at rest moved by
    a rigid motion, the start pose 0.1 rad off; result.pose (None for a body-frame target) is the
    4x4 pose found with the control, nearer the true one than the start (its recovery to 0.01
    rad: tests/test_optimise_cli.cpp)."""
    scene = softhd.Scene.load(scene_file(SMALL_ARC))
    c, s = np.cos(0.5), np.sin(0.5)
    G = np.array([[c, -s, 0, 1.0], [s, c, 0, -2.0], [0, 0, 1, 0.5], [0, 0, 0, 1]])
    softhd.write_cloud(tmp_path / "seen.ply", scene.nodes @ G[:3, :3].T + G[:3, 3])
    truth = np.linalg.inv(G)
    c, s = np.cos(0.1), np.sin(0.1)
    off = np.array([[1, 0, 0, 0.02], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1]])
    np.savetxt(tmp_path / "start.txt", truth @ off, fmt="%.17g")
    spec = dict(SMALL_ARC, target={"kind": "cloud", "file": "seen.ply", "frame": "camera",
                                   "pose": "start.txt"})
    r = softhd.optimise(softhd.Scene.load(scene_file(spec, "camera.json")), max_iter=4)
    assert r.pose.shape == (4, 4)

    def angle(P):
        return np.arccos(np.clip((np.trace(P[:3, :3] @ truth[:3, :3].T) - 1) / 2, -1, 1))

    assert angle(r.pose) < angle(truth @ off)
    # pose_move: the pose's move limit as a fraction of the control's; 0.05 moves the pose less
    # in the first iteration than the default 1.
    def first_step(**kw):
        P = softhd.optimise(softhd.Scene.load(scene_file(spec, "camera.json")), max_iter=1,
                            **kw).pose
        return np.linalg.norm(P - truth @ off)

    assert first_step(pose_move=0.05) < 0.5 * first_step()
    # pose_method "projection": every evaluation fits the pose on its state; the body at rest
    # is an exact moved copy of the target, so the first evaluation recovers the pose.
    r = softhd.optimise(softhd.Scene.load(scene_file(spec, "camera.json")), max_iter=1,
                        pose_method="projection")
    assert angle(r.pose) < 1e-6
    with pytest.raises(softhd.InvalidArgument, match="unknown pose_method 'both'"):
        softhd.optimise(softhd.Scene.load(scene_file(spec, "camera.json")), max_iter=1,
                        pose_method="both")
    assert softhd.optimise(scene, max_iter=1).pose is None
    bad = dict(spec, target=dict(spec["target"], frame="world"))
    with pytest.raises(softhd.InvalidArgument, match='target.frame must be "body" or "camera"'):
        softhd.optimise(softhd.Scene.load(scene_file(bad, "bad.json")), max_iter=1)


def test_initial_control_starts_there(scene_file):
    """initial: the run starts at the given control (an earlier run's: its final rho is the next
    run's start); a control of the wrong size is refused."""
    scene = softhd.Scene.load(scene_file(SMALL_ARC))
    r1 = softhd.optimise(scene, max_iter=2)
    r2 = softhd.optimise(scene, max_iter=1, initial=r1.control)
    assert r2.rho_start == pytest.approx(r1.rho_final, rel=1e-6)
    assert r2.rho_start < softhd.optimise(scene, max_iter=1).rho_start
    with pytest.raises(softhd.InvalidArgument, match="initial has 3 values, expected"):
        softhd.optimise(scene, max_iter=1, initial=[0.0, 0.0, 0.0])
    # An empty control is not None; values outside the bounds [-1e5, 0] are refused, not clipped.
    with pytest.raises(softhd.InvalidArgument, match="initial is empty"):
        softhd.optimise(scene, max_iter=1, initial=np.empty(0))
    for k, value, text in ((0, 5.0, "5"), (3, -1e9, "-1000000000")):
        m = np.array(r1.control)
        m[k] = value
        with pytest.raises(softhd.InvalidArgument,
                           match=rf"initial\[{k}\] = {text} is outside its bounds "
                                 r"\[-100000, 0\]"):
            softhd.optimise(scene, max_iter=1, initial=m)
    # pose_move moves a camera-frame target's pose: refused for this body-frame target.
    with pytest.raises(softhd.InvalidArgument, match="pose_move moves the pose of a target"):
        softhd.optimise(scene, max_iter=1, pose_move=0.5)
    with pytest.raises(softhd.InvalidArgument, match=r"pose_move must be in \(0, 1\]"):
        softhd.optimise(scene, max_iter=1, pose_move=0.0)
    with pytest.raises(softhd.InvalidArgument, match="pose_method finds the pose of a target"):
        softhd.optimise(scene, max_iter=1, pose_method="projection")


def test_quadrature_cells_from_the_keyword_or_the_scene(scene_file):
    """quadrature="cells" integrates the distance over the body's and the arc's cells, as the
    scene target's "quadrature" does; an unknown name is refused naming the keyword."""
    small = {**SMALL_ARC, "mesh": {**SMALL_ARC["mesh"], "cells": [4, 1, 1], "order": 1},
             "target": {"kind": "arc", "angle": 1.0, "cells": [8, 2, 2]}}
    scene = softhd.Scene.load(scene_file(small))
    r = softhd.optimise(scene, max_iter=1, quadrature="cells")
    assert r.target.endswith("; quadrature cells")
    plain = softhd.optimise(scene, max_iter=1)
    assert "quadrature" not in plain.target and plain.rho_start != r.rho_start
    keyed = {**small, "target": {**small["target"], "quadrature": "cells"}}
    s = softhd.optimise(softhd.Scene.load(scene_file(keyed, "keyed.json")), max_iter=1)
    assert s.rho_start == r.rho_start and s.rho_final == r.rho_final
    with pytest.raises(softhd.InvalidArgument, match="unknown quadrature 'points'"):
        softhd.optimise(scene, max_iter=1, quadrature="points")
