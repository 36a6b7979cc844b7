"""Ctrl-C reaches long calls (issue 29, item 5): a SIGINT raises KeyboardInterrupt within a
fraction of a second of the next poll (between passes and blocks of a distance, between an
optimiser's evaluations), not when the call would have ended."""

import json
import os
import signal
import threading
import time

import numpy as np
import pytest

import softhd
from conftest import SMALL_ARC


def _sigint_after(seconds):
    """Sends this process SIGINT after `seconds` (as Ctrl-C does); returns the timer."""
    timer = threading.Timer(seconds, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    return timer


def _interrupted(call, exception=KeyboardInterrupt, after=1.0):
    """Runs call() with a SIGINT `after` seconds in; returns the seconds until `exception`."""
    timer = _sigint_after(after)
    start = time.monotonic()
    try:
        with pytest.raises(exception):
            call()
    finally:
        timer.cancel()
    return time.monotonic() - start


@pytest.fixture(scope="module")
def big_pair():
    # 2 passes of 150 000^2 pairs: about 20 s on 2 idle cores (exact), 40 s on busy ones.
    rng = np.random.default_rng(29)
    return rng.random((150_000, 3)), rng.random((150_000, 3))


def test_ctrl_c_stops_a_long_distance(big_pair):
    X, Y = big_pair
    elapsed = _interrupted(lambda: softhd.distance(X, Y))
    assert elapsed < 5.0, f"KeyboardInterrupt came {elapsed:.1f} s after the call began"


def test_a_signal_handlers_own_exception_is_raised(big_pair):
    X, Y = big_pair

    class Stop(Exception):
        pass

    def handler(signum, frame):
        raise Stop("from the handler")

    previous = signal.signal(signal.SIGINT, handler)
    try:
        target = softhd.Target(Y)
        elapsed = _interrupted(lambda: target.evaluate(X, gradient=True), exception=Stop)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert elapsed < 5.0
    # The target is still usable after the interruption.
    assert np.isfinite(target.evaluate(X[:100]).rho)


def test_ctrl_c_stops_optimise_between_evaluations(tmp_path):
    path = tmp_path / "arc.json"
    path.write_text(json.dumps(SMALL_ARC))
    scene = softhd.Scene.load(str(path))
    # 200 iterations take about 40-90 s here (0.2-0.45 s each); no callback, which would
    # let Python itself raise KeyboardInterrupt at the next iteration.
    elapsed = _interrupted(lambda: softhd.optimise(scene, max_iter=200, rel_tol=0.0))
    assert elapsed < 5.0, f"KeyboardInterrupt came {elapsed:.1f} s after the call began"
    # The scene is still usable.
    assert softhd.optimise(scene, max_iter=1).iterations == 1
