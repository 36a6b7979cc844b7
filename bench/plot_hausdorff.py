#!/usr/bin/python3
"""Plots of bench_hausdorff's CSV: time against measured error, and time against N.

Usage: /usr/bin/python3 bench/plot_hausdorff.py CSV [CSV ...] --out docs
Writes <out>/hausdorff_time_vs_error.png, <out>/hausdorff_time_vs_n.png and prints the
Markdown tables used in docs/benchmarks.md. Needs Debian's python3-matplotlib.
"""
import argparse
import csv
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def load(paths):
    rows = []
    for path in paths:
        with open(path, newline="") as f:
            for r in csv.DictReader(f):
                for key in ("N", "M", "kernel_evaluations", "runs"):
                    r[key] = int(r[key])
                for key in ("tau", "median_s", "min_s", "cpu_s", "rho", "err_rho", "err_S", "err_field",
                            "err_grad"):
                    r[key] = float(r[key]) if r.get(key) else math.nan
                rows.append(r)
    # A later file wins for the same configuration.
    unique = {}
    for r in rows:
        unique[(r["shape"], r["N"], r["method"], r["tau"] if r["method"] == "tree" else 0,
                r["mode"])] = r
    return list(unique.values())


def label(r):
    return "tree τ=%g" % r["tau"] if r["method"] == "tree" else r["method"]


def time_vs_error(rows, out):
    shapes = sorted({r["shape"] for r in rows})
    fig, axes = plt.subplots(1, len(shapes), figsize=(4.2 * len(shapes), 4), squeeze=False)
    for ax, shape in zip(axes[0], shapes):
        sel = [r for r in rows if r["shape"] == shape and r["method"] == "tree"
               and r["mode"] == "value+grad" and not math.isnan(r["err_S"])]
        for n in sorted({r["N"] for r in sel}):
            pts = sorted((r["err_S"], r["median_s"], r["tau"]) for r in sel if r["N"] == n)
            ax.plot([max(p[0], 1e-17) for p in pts], [p[1] for p in pts], "o-", label="N=%d" % n)
            exact = [r for r in rows if r["shape"] == shape and r["N"] == n
                     and r["method"] == "exact" and r["mode"] == "value+grad"]
            if exact:
                ax.axhline(exact[0]["median_s"], ls=":", color=ax.lines[-1].get_color())
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("measured max relative error of S")
        ax.set_ylabel("median time [s] (value+gradient)")
        ax.set_title("%s (dotted: exact)" % shape)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "hausdorff_time_vs_error.png"), dpi=110)


def time_vs_n(rows, out):
    shapes = sorted({r["shape"] for r in rows})
    fig, axes = plt.subplots(1, len(shapes), figsize=(4.2 * len(shapes), 4), squeeze=False)
    for ax, shape in zip(axes[0], shapes):
        sel = [r for r in rows if r["shape"] == shape and
               (r["mode"] == "value+grad" or r["method"] == "nearest")]
        for key in sorted({label(r) for r in sel}):
            pts = sorted((r["N"], r["median_s"]) for r in sel if label(r) == key)
            ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", label=key)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("N = M (points per cloud)")
        ax.set_ylabel("median time [s]")
        ax.set_title("%s, value+gradient (nearest: value)" % shape)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "hausdorff_time_vs_n.png"), dpi=110)


def fmt(x):
    return "" if math.isnan(x) else "%.3g" % x


def tables(rows):
    for shape in sorted({r["shape"] for r in rows}):
        print("\n#### %s\n" % shape)
        print("| N | M | method | mode | median s | CPU s | kernel evals | err S | err ρ̃ | err grad"
              " | reference |")
        print("|---|---|---|---|---|---|---|---|---|---|---|")
        order = {"nearest": 0, "exact": 1, "tree": 2}
        sel = sorted((r for r in rows if r["shape"] == shape),
                     key=lambda r: (r["N"], order[r["method"]], -r["tau"] if r["tau"] == r["tau"]
                                    else 0, r["mode"]))
        for r in sel:
            print("| %d | %d | %s | %s | %s | %s | %.3g | %s | %s | %s | %s |" % (
                r["N"], r["M"], label(r), r["mode"], fmt(r["median_s"]), fmt(r["cpu_s"]),
                r["kernel_evaluations"], fmt(r["err_S"]), fmt(r["err_rho"]), fmt(r["err_grad"]),
                r["error_reference"]))


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("csv", nargs="+")
    parser.add_argument("--out", default="docs")
    args = parser.parse_args()
    rows = load(args.csv)
    time_vs_error(rows, args.out)
    time_vs_n(rows, args.out)
    tables(rows)


if __name__ == "__main__":
    main()
