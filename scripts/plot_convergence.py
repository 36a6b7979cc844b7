#!/usr/bin/env python3
"""Draws convergence.png from a softhd optimise output directory (history.csv and
summary.json): rho and rho/floor against iteration, and the projected-gradient norm."""
import csv
import json
import os
import sys

try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: E402
except ImportError:
    sys.exit(3)  # softhd optimise reports "needs python3-matplotlib" for exit status 3


def main(directory):
    with open(os.path.join(directory, "history.csv")) as f:
        rows = list(csv.DictReader(f))
    with open(os.path.join(directory, "summary.json")) as f:
        summary = json.load(f)
    it = [int(float(r["iteration"])) for r in rows]
    rho = [float(r["rho"]) for r in rows]
    pg = [float(r["projected_gradient_norm"]) for r in rows]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4))
    a1.semilogy([0] + it, [summary["rho_start"]] + rho, "o-", ms=3, label="rho (regularised)")
    if summary.get("floor_matched") is not None:
        a1.axhline(summary["floor_matched"], color="C1", ls="--", label="matched floor")
    a1.axhline(summary["floor_self"], color="C2", ls=":", label="self floor")
    a1.set_xlabel("iteration")
    a1.set_ylabel("rho")
    a1.set_title(os.path.basename(os.path.abspath(directory)) + ": " + summary["termination"],
                 fontsize=9)
    a1.legend()
    a2.semilogy(it, pg, "o-", ms=3, color="C3")
    a2.set_xlabel("iteration")
    a2.set_ylabel("projected gradient norm (scaled)")
    fig.tight_layout()
    fig.savefig(os.path.join(directory, "convergence.png"), dpi=110)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: plot_convergence.py OUTPUT_DIR")
    main(sys.argv[1])
