"""The examples run end to end on small inputs (a few seconds each)."""

import os
import subprocess
import sys

import pytest


def run(source_dir, name, *args, cwd):
    script = os.path.join(source_dir, "examples", name)
    p = subprocess.run([sys.executable, script, *map(str, args)], capture_output=True, cwd=cwd,
                       env={**os.environ, "MPLBACKEND": "Agg"})  # bytes: keep the \r
    out, err = p.stdout.decode(), p.stderr.decode()
    assert p.returncode == 0, out + err
    return out, err


def test_compare_scans(source_dir, tmp_path):
    out, _ = run(source_dir, "compare_scans.py", "--sizes", 200, 800, "--out", tmp_path,
                 cwd=tmp_path)
    rows = [line.split() for line in out.splitlines() if line.strip()[:1].isdigit()]
    assert [int(r[0]) for r in rows] == [200, 800]
    for n, rho, floor, hausdorff, _ in rows:
        assert 0.0 < float(floor) < float(rho)  # the rescan differs from the scan
    pytest.importorskip("matplotlib")
    assert (tmp_path / "compare_scans.png").stat().st_size > 1000


def test_optimise_live(source_dir, tmp_path):
    out, err = run(source_dir, "optimise_live.py", "--cells", 10, 2, 2, "--max-iter", 3,
                   cwd=tmp_path)
    assert "\r  iteration    3" in err  # the live line, rewritten in place
    assert "the iteration limit was reached after 3 iterations" in out
    assert "shape error" in out


def test_convergence_plot_without_a_floor(source_dir, tmp_path):
    """scripts/plot_convergence.py draws a run whose summary has no self floor (quadrature cells
    against a large target skip it: null in summary.json) or no matched floor."""
    pytest.importorskip("matplotlib")
    (tmp_path / "history.csv").write_text(
        "iteration,rho,projected_gradient_norm,seconds,level\n1,0.5,1.0,0.1,0\n2,0.3,0.5,0.2,0\n")
    (tmp_path / "summary.json").write_text(
        '{"floor_matched": 0.15, "floor_self": null, "termination": "the iteration limit"}')
    script = os.path.join(source_dir, "scripts", "plot_convergence.py")
    p = subprocess.run([sys.executable, "-c", "import runpy, sys; sys.argv = ['x']; "
                        f"m = runpy.run_path({script!r}); m['main']({str(tmp_path)!r})"],
                       capture_output=True, text=True, env={**os.environ, "MPLBACKEND": "Agg"})
    assert p.returncode == 0, p.stdout + p.stderr
    assert (tmp_path / "convergence.png").stat().st_size > 1000
