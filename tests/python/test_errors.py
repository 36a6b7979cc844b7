"""Every C++ error reaches Python as softhd.Error with the C++ message: InvalidArgument is a
ValueError, FileError an OSError."""

import json
import os

import numpy as np
import pytest

import softhd
from conftest import SMALL_2D


def test_hierarchy():
    assert issubclass(softhd.InvalidArgument, softhd.Error)
    assert issubclass(softhd.InvalidArgument, ValueError)
    assert issubclass(softhd.FileError, softhd.Error) and issubclass(softhd.FileError, OSError)
    assert issubclass(softhd.ResourceError, softhd.Error)
    assert issubclass(softhd.NumericalError, softhd.Error)
    assert softhd.Error.__module__ == "softhd"


P = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])


@pytest.mark.parametrize("kwargs, message", [
    (dict(alpha=0.0), "alpha"),
    (dict(beta=-1.0), "beta"),
    (dict(gamma=float("nan")), "gamma"),
    (dict(eps=0.0), "eps"),
    (dict(method="fast"), "fast"),
    (dict(tol=2.0, method="tree"), "tolerance"),
    (dict(threads=-1), "threads"),
    (dict(method="nearest", gradient=True), "nearest"),
])
def test_invalid_options(kwargs, message):
    with pytest.raises(softhd.InvalidArgument, match=message) as e:
        softhd.distance(P, P, **kwargs)
    assert isinstance(e.value, ValueError)


@pytest.mark.parametrize("X, VX, message", [
    (np.zeros((3, 4)), None, "dimension|d "),
    (np.zeros(3), None, "dimensions"),
    (np.array([[0.0, np.nan, 0.0]]), None, "finite|NaN|nan"),
    (P, np.array([1.0]), "volumes"),
    (P, np.array([1.0, -1.0]), "volume"),
    (np.zeros((2, 2)), None, "dimension|2D|3D"),  # 2D moving cloud, 3D target
])
def test_invalid_clouds(X, VX, message):
    with pytest.raises(ValueError, match=message):
        softhd.distance(X, P, VX)


def test_file_errors(tmp_path):
    with pytest.raises(softhd.FileError, match="missing.ply") as e:
        softhd.read_cloud(tmp_path / "missing.ply")
    assert isinstance(e.value, OSError)
    bad = tmp_path / "bad.txt"
    bad.write_text("0 0 0\n1 abc 0\n")
    with pytest.raises(OSError, match="bad.txt:2"):
        softhd.read_cloud(bad)
    with pytest.raises(softhd.InvalidArgument, match="dim"):
        softhd.read_cloud(bad, dim=5)
    with pytest.raises(softhd.FileError):
        softhd.write_cloud(tmp_path / "no" / "dir" / "c.ply", P)
    with pytest.raises(softhd.FileError, match="missing.json"):
        softhd.Scene.load(tmp_path / "missing.json")
    broken = tmp_path / "broken.json"
    broken.write_text(json.dumps({**SMALL_2D, "material": {"model": "rubber"}}))
    with pytest.raises(softhd.FileError, match="rubber"):
        softhd.Scene.load(broken)


def test_resource_limit(scene_file):
    with pytest.raises(softhd.ResourceError, match="memory"):
        softhd.Scene.load(scene_file(SMALL_2D), max_memory_gib=1e-6)
    with pytest.raises(ValueError, match="max_memory_gib"):
        softhd.Scene.load(scene_file(SMALL_2D), max_memory_gib=0)


def test_a_body_that_nothing_holds_is_refused_on_load(tmp_path, scene_file, source_dir):
    # One tetrahedron clamped at a vertex: free to turn about it, refused before any solve.
    (tmp_path / "tet.msh").write_text(
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n0 1 \"tip\"\n"
        "3 2 \"body\"\n$EndPhysicalNames\n$Nodes\n4\n1 0 0 0\n2 1 0 0\n3 0 1 0\n"
        "4 0 0 1\n$EndNodes\n$Elements\n2\n1 15 2 1 1 1\n2 4 2 2 2 1 2 3 4\n$EndElements\n")
    tet = dict(SMALL_2D, mesh={"type": "gmsh", "file": "tet.msh"}, clamp=["tip"])
    with pytest.raises(softhd.FileError, match="'tip' leaves region 'body' free to move rigidly"):
        softhd.Scene.load(scene_file(tet))
    # Two volumes meshed without BooleanFragments.
    apart = dict(tet, clamp=["base"], mesh={"type": "gmsh", "file": os.path.join(
        source_dir, "tests", "data", "meshes", "two_boxes_nonconforming.msh")})
    with pytest.raises(softhd.FileError, match="regions 'left' and 'right' touch at"):
        softhd.Scene.load(scene_file(apart))


def test_forward_errors(scene_file):
    scene = softhd.Scene.load(scene_file(SMALL_2D))
    with pytest.raises(ValueError, match="outside the scene's bounds"):
        scene.forward(10.0)
    with pytest.raises(ValueError, match="controls"):
        scene.forward(np.zeros(scene.num_controls + 1))
    with pytest.raises(ValueError, match="not a point of the 2D body"):
        scene.forward(0.0, probes=[[5.0, 0.1]])
    with pytest.raises(ValueError, match="can be halved"):  # 4x2 cells: 2x1, 1x1, then none
        scene.forward(-1.0, coarse_levels=3)
    with pytest.raises(ValueError, match="levels must be >= -1"):
        scene.forward(-1.0, coarse_levels=-2)
    with pytest.raises(ValueError, match="threads"):
        scene.forward(0.0, threads=-2)


def test_optimise_errors(scene_file):
    scene = softhd.Scene.load(scene_file(SMALL_2D))
    with pytest.raises(ValueError, match="no \"target\""):
        softhd.optimise(scene)
    target = np.array([[0.0, 0.0], [2.0, 0.4]])
    with pytest.raises(ValueError, match="algorithm|nelder"):
        softhd.optimise(scene, target, algorithm="nelder-mead")
    with pytest.raises(ValueError, match="max_iter"):
        softhd.optimise(scene, target, max_iter=0)
    with pytest.raises(ValueError, match=r"unknown coarse_levels 'on' \(expected auto or 0\)"):
        softhd.optimise(scene, target, coarse_levels="on")
    with pytest.raises(ValueError, match="3D but the scene's body is 2D"):
        softhd.optimise(scene, np.zeros((4, 3)))
    with pytest.raises(OSError, match="nothing.ply"):
        softhd.optimise(scene, "nothing.ply")


@pytest.mark.parametrize("kwargs, field", [
    (dict(tikhonov_mass=-1.0), "tikhonov_mass"),
    (dict(tikhonov_grad=float("nan")), "tikhonov_gradient"),
    (dict(rel_tol=-1.0), "relative_change"),
    (dict(move_limit=-0.5), "move_limit"),
    (dict(gamma=0.0), "gamma"),
])
def test_optimise_options_name_the_field(scene_file, kwargs, field):
    scene = softhd.Scene.load(scene_file(SMALL_2D))
    with pytest.raises(softhd.InvalidArgument, match=field):
        softhd.optimise(scene, np.array([[0.0, 0.0], [2.0, 0.4]]), **kwargs)


CAP = r"threads must be from 0 to 1024 \(0: OMP_NUM_THREADS, else all cores\), got "


@pytest.mark.parametrize("threads", [1025, 100000, 2**31 - 1])
def test_thread_counts_above_the_cap_are_refused_not_crashed(scene_file, threads):
    """Issue 29 item 2: these segfaulted inside GOMP_parallel (2**31-1 aborted)."""
    with pytest.raises(softhd.InvalidArgument, match=CAP + str(threads)):
        softhd.distance(P, P, threads=threads)
    with pytest.raises(softhd.InvalidArgument, match=CAP):
        softhd.Target(P, threads=threads)
    scene = softhd.Scene.load(scene_file(SMALL_2D))
    with pytest.raises(softhd.InvalidArgument, match=CAP):
        scene.forward(0.0, threads=threads)
    with pytest.raises(softhd.InvalidArgument, match=CAP):
        softhd.optimise(scene, np.array([[0.0, 0.0], [2.0, 0.4]]), max_iter=1, threads=threads)
    assert softhd.distance(P, P, threads=1024).rho > 0.0  # the cap itself is allowed


def test_a_large_omp_num_threads_is_clamped_not_crashed(scene_file):
    """OMP_NUM_THREADS=100000 made every call segfault; softhd uses 1024 threads at most."""
    import os
    import subprocess
    import sys
    code = (
        "import numpy as np, softhd\n"
        "P = np.random.default_rng(1).random((3000, 3))\n"
        "for m in ('exact', 'tree', 'nearest'):\n"
        "    r = softhd.distance(P, P[::-1] * 1.1, method=m, gradient=m != 'nearest')\n"
        "    assert np.isfinite(r.rho)\n"
        f"s = softhd.Scene.load({scene_file(SMALL_2D)!r})\n"
        "print(s.forward(-1e4).newton_iterations > 0)\n")
    env = dict(os.environ, OMP_NUM_THREADS="100000")
    p = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                       timeout=120)
    assert p.returncode == 0, p.stderr
    assert p.stdout.strip() == "True"


@pytest.mark.parametrize("eps", [1e-320, 1e-310, 1e-305])
def test_eps_below_the_bound_is_refused_with_the_bound(eps):
    """Issue 29 item 8: eps=1e-320 gave NaN gradients for coincident clouds."""
    message = "epsilon must be at least 1e-300, got"
    with pytest.raises(softhd.InvalidArgument, match=message):
        softhd.distance(P, P, eps=eps, gradient=True)
    with pytest.raises(softhd.InvalidArgument, match=message):
        softhd.Target(P, eps=eps)
    r = softhd.distance(P, P, eps=1e-300, gradient=True, gradient_volumes=True,
                        gradient_target=True)
    assert np.isfinite(r.gradient).all() and np.isfinite(r.gradient_volumes).all()
    assert np.isfinite(r.gradient_target).all()


def test_optimise_refuses_eps_below_the_bound(scene_file):
    scene = softhd.Scene.load(scene_file(SMALL_2D))
    with pytest.raises(softhd.InvalidArgument, match="epsilon must be at least 1e-300"):
        softhd.optimise(scene, np.array([[0.0, 0.0], [2.0, 0.4]]), eps=1e-320)
