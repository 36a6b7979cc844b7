#!/usr/bin/env python3
"""Draws the pictures of a softhd optimise output directory: convergence.png (history.csv,
summary.json) and shape.png (the final body against the target: body_final.ply, target.ply).
softhd optimise runs it at the end of every run. Exit status 3: no matplotlib."""
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import plot_convergence  # noqa: E402  (exits 3 without matplotlib)
import plot_shape  # noqa: E402

if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: plot_run.py OUTPUT_DIR")
    plot_convergence.main(sys.argv[1])
    plot_shape.main(sys.argv[1])
