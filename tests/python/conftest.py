"""Shared fixtures of the Python tests. CTest runs them with PYTHONPATH pointing at the build
tree's package (build/python) and SOFTHD_CLI, SOFTHD_SOURCE_DIR set (tests/CMakeLists.txt)."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

sys.path.insert(0, os.path.dirname(__file__))  # spec_reference


@pytest.fixture(scope="session")
def source_dir():
    return os.environ.get("SOFTHD_SOURCE_DIR",
                          os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..")))


@pytest.fixture(scope="session")
def cli():
    """Runs the softhd command-line tool; returns its parsed --json output."""
    exe = os.environ.get("SOFTHD_CLI")
    if not exe or not os.path.exists(exe):
        pytest.fail("SOFTHD_CLI must name the built softhd tool (CTest sets it)")

    def run(*args):
        p = subprocess.run([exe, *map(str, args), "--json"], capture_output=True, text=True)
        assert p.returncode == 0, p.stderr
        return json.loads(p.stdout)

    return run


def random_cloud(rng, n, d=3, scale=1.0, shift=0.0):
    """n points uniform in [shift, shift + scale]^d and volumes in [0.5, 1.5]."""
    return shift + scale * rng.random((n, d)), 0.5 + rng.random(n)


@pytest.fixture
def rng():
    return np.random.default_rng(20261130)


SMALL_2D = {
    "name": "small_2d",
    "mesh": {"type": "box", "lower": [0, 0], "upper": [2, 0.4], "cells": [4, 2], "order": 2},
    "material": {"model": "mooney_rivlin", "a": 1e5, "b": 2e4, "c": 3e5},
    "fibers": [1, 0, 0], "clamp": ["x0"],
    "control": {"space": "vertex", "lower": -1e5, "upper": 0, "initial": 0},
}

SMALL_ARC = {
    "name": "small_arc",
    "mesh": {"type": "box", "lower": [0, 0, 0], "upper": [10, 2, 0.1], "cells": [8, 2, 2],
             "order": 2},
    "material": {"model": "mooney_rivlin", "a": 1e5, "b": 2e4, "c": 3e5},
    "fibers": [1, 0, 0], "clamp": ["x0"],
    "control": {"space": "vertex", "lower": -1e5, "upper": 0, "initial": 0},
    "target": {"kind": "arc", "angle": 1.0, "cells": [16, 4, 2]},
}


@pytest.fixture
def scene_file(tmp_path):
    """Writes a scene dict as JSON in tmp_path and returns its path."""

    def write(scene, name="scene.json"):
        path = tmp_path / name
        path.write_text(json.dumps(scene))
        return str(path)

    return write
