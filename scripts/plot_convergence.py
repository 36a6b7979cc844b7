#!/usr/bin/env python3
"""Draws convergence.png from a softhd optimise output directory (history.csv and
summary.json): rho per level against the run's clock, with the floors, and the
projected-gradient norm."""
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
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(11, 4))
    # Against the run's clock, one series per level (a multilevel run's coarse levels first:
    # their rho is against their own coarse target; level 0 is the user's mesh).
    levels = sorted({r.get("level", "0") or "0" for r in rows}, key=int, reverse=True)
    for k, level in enumerate(levels):
        mine = [r for r in rows if (r.get("level", "0") or "0") == level]
        t = [float(r["seconds"]) for r in mine]
        rho = [float(r["rho"]) for r in mine]
        pg = [float(r["projected_gradient_norm"]) for r in mine]
        name = "your mesh" if level == "0" else "coarse level %s" % level
        a1.semilogy(t, rho, "o-", ms=3, color="C%d" % (3 + k), label="rho, " + name)
        a2.semilogy(t, pg, "o-", ms=3, color="C%d" % (3 + k), label=name)
    if summary.get("floor_matched") is not None:
        a1.axhline(summary["floor_matched"], color="C1", ls="--", label="matched floor")
    if summary.get("floor_self") is not None:  # quadrature cells skip it on large targets
        a1.axhline(summary["floor_self"], color="C2", ls=":", label="self floor")
    a1.set_xlabel("seconds (the run's clock)")
    a1.set_ylabel("rho")
    a1.set_title(os.path.basename(os.path.abspath(directory)) + ": " + summary["termination"],
                 fontsize=9)
    a1.legend(fontsize=8)
    a2.set_xlabel("seconds (the run's clock)")
    a2.set_ylabel("projected gradient norm (scaled)")
    if len(levels) > 1:
        a2.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(directory, "convergence.png"), dpi=110)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: plot_convergence.py OUTPUT_DIR")
    main(sys.argv[1])
