#!/usr/bin/python3
"""Writes the benchmark report (docs/benchmarks.md) from the CSVs of scripts/run_benchmarks.sh.

Usage: /usr/bin/python3 bench/make_report.py OUT_DIR --report FILE [--quick]
Reads OUT_DIR/{kernel,hausdorff_ladder,hausdorff_goals,resolution,control,stability,...}.csv
(and their .meta files), draws PNG plots into OUT_DIR and writes FILE. Every number in the
report comes from those files; sentences that summarise them are computed here.
Needs Debian's python3-matplotlib.
"""
import argparse
import csv
import math
import os
import subprocess
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))


def load(path):
    if not os.path.exists(path):
        return None
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def num(r, key):
    v = r.get(key, "")
    try:
        return float(v) if v not in ("", None) else math.nan
    except ValueError:
        return math.nan


def g(v, digits=3):
    if isinstance(v, str):
        return v
    if isinstance(v, int):
        return str(v)
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "–"
    return "%.*g" % (digits, v)


def table(header, rows):
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for r in rows:
        out.append("| " + " | ".join(g(c) for c in r) + " |")
    return "\n".join(out) + "\n"


def meta(out, name):
    path = os.path.join(out, name + ".meta")
    if not os.path.exists(path):
        return ("    (no run record: this CSV was made before scripts/run_benchmarks.sh wrote "
                "them; see docs/bench_hausdorff.md)\n")
    lines = [l.strip() for l in open(path) if l.strip()]
    return "".join("    %s\n" % l for l in lines)


def wall_times(out, names):
    """The wall time and date of each benchmark's last run, from its run record."""
    rows, total = [], 0
    for name in names:
        path = os.path.join(out, name + ".meta")
        if not os.path.exists(path):
            continue
        rec = dict(l.split(": ", 1) for l in (x.strip() for x in open(path)) if ": " in l)
        if "wall seconds" not in rec:
            continue
        sec = int(rec["wall seconds"])
        total += sec
        rows.append([name, rec.get("date", ""), rec.get("commit", ""), "%.1f" % (sec / 60)])
    if not rows:
        return ""
    rows.append(["**total**", "", "", "**%.1f**" % (total / 60)])
    return ("Wall time of each benchmark's last run (a full `make bench` runs them all in "
            "sequence; its budget is an hour):\n\n"
            + table(["benchmark", "date", "commit", "minutes"], rows) + "\n")


def rel(path, report):
    return os.path.relpath(path, os.path.dirname(os.path.abspath(report)))


def reached(r, k):
    it, t = r.get("it_%s" % k, ""), r.get("t_%s" % k, "")
    return "%s it / %s s" % (it, g(float(t))) if it else "not reached"


# ---------------------------------------------------------------- sections


def section_resolution(rows, out, report):
    s = ["## Differing target resolutions (`bench_resolution`)\n",
         "The bending scene (180° arc, analytic map T) against targets of differing resolution "
         "and regularity, and the state mesh at three refinements against one fixed target. "
         "h is the FE node spacing; `shape error` is |x_i − T(X_i)| over the nodes after the "
         "run (max / RMS); ρ̃/floor is against the matched floor ρ̃(T(Ω₀), Ω_d) of that pair.\n"]
    cols = ["target", "points", "floor self", "floor matched", "ρ̃ final", "ρ̃/floor",
            "shape err max", "shape err RMS", "iterations", "s", "termination"]

    def rowof(r, name):
        return [name, int(num(r, "target_points")), num(r, "floor_self"), num(r, "floor_matched"),
                num(r, "rho_final"), num(r, "rho_over_floor"), num(r, "shape_error_max"),
                num(r, "shape_error_rms"), int(num(r, "iterations")), num(r, "seconds"),
                r["termination"]]

    grid = [r for r in rows if r["study"] == "grid"]
    scan = [r for r in rows if r["study"] == "scan"]
    mesh = [r for r in rows if r["study"] == "mesh"]
    if grid:
        s.append("\n**Target grid spacing** (state mesh %s):\n\n" % grid[0]["mesh"])
        s.append(table(["h_d / h"] + cols, [[r["spacing_over_h"]] + rowof(r, r["variant"])
                                             for r in grid]))
        e = [num(r, "shape_error_rms") for r in grid]
        s.append("\nShape error RMS from the coarsest to the finest target: %s → %s "
                 "(spacings %s h → %s h).\n" % (g(e[0]), g(e[-1]), grid[0]["spacing_over_h"],
                                               grid[-1]["spacing_over_h"]))
    if scan:
        s.append("\n**Scan-like targets** (same mesh):\n\n")
        s.append(table(cols, [rowof(r, r["variant"]) for r in scan]))
        ref = [r for r in grid if r["spacing_over_h"] == "0.5"]
        if ref:
            s.append("\nFor comparison the regular h/2 grid ends at shape error RMS %s.\n"
                     % g(num(ref[0], "shape_error_rms")))
    if mesh:
        s.append("\n**State mesh refinement** (fixed %s):\n\n" % mesh[0]["variant"])
        s.append(table(["mesh", "nodes"] + cols[1:],
                       [[r["mesh"], int(num(r, "nodes"))] + rowof(r, "")[1:] for r in mesh]))
        e = [num(r, "shape_error_rms") for r in mesh]
        s.append("\nShape error RMS by mesh: %s.\n" % ", ".join(
            "%s → %s" % (r["mesh"], g(v)) for r, v in zip(mesh, e)))
    every = grid + scan
    if every:
        e = [num(r, "shape_error_rms") for r in every]
        s.append("\nAcross all %d targets of the state mesh %s (%d to %d points) the final shape "
                 "error RMS lies in [%s, %s].\n" % (
                     len(every), every[0]["mesh"], min(int(num(r, "target_points")) for r in every),
                     max(int(num(r, "target_points")) for r in every), g(min(e)), g(max(e))))
        s.append("\nWhy the shape error stops falling with resolution (a study against a "
                 "reachable target of the same curl): "
                 "[bending_reachability.md](%s).\n"
                 % rel(os.path.join(HERE, "..", "docs", "bending_reachability.md"), report))
    # Plot: shape error against target spacing and against mesh nodes.
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    if grid:
        x = [float(r["spacing_over_h"]) for r in grid]
        ax[0].loglog(x, [num(r, "shape_error_rms") for r in grid], "o-", label="RMS")
        ax[0].loglog(x, [num(r, "shape_error_max") for r in grid], "s--", label="max")
        ax[0].set_xlabel("target spacing h_d / h")
        ax[0].set_ylabel("true shape error")
        ax[0].legend()
        ax[0].set_title("target resolution")
    if mesh:
        x = [num(r, "nodes") for r in mesh]
        ax[1].loglog(x, [num(r, "shape_error_rms") for r in mesh], "o-", label="RMS")
        ax[1].loglog(x, [num(r, "shape_error_max") for r in mesh], "s--", label="max")
        ax[1].set_xlabel("state mesh nodes")
        ax[1].legend()
        ax[1].set_title("state resolution")
    fig.tight_layout()
    png = os.path.join(out, "resolution.png")
    fig.savefig(png, dpi=110)
    plt.close(fig)
    s.append("\n![shape error against resolution](%s)\n" % rel(png, report))
    return "".join(s)


def section_control(rows, out, report):
    s = ["## Run time against error for the whole problem (`bench_control`)\n",
         "Whole optimisations (MMA, move limit 0.1). Time per iteration is split into the state "
         "solve, the functional's value + gradient, the adjoint and the rest (optimiser, "
         "records). `to k×` is the iteration and wall time at which ρ̃ first fell to k × the "
         "matched floor. For torsion `m err` is ‖m − m*‖/‖m*‖ at the control vertices "
         "(m*(X) = −1e6·X3/2, the control that made the target on a 2× finer mesh).\n\n"]
    hdr = ["scene", "mesh", "nodes", "method", "τ", "s/it", "state %", "distance %", "adjoint %",
           "rest %", "to 2×", "to 1.5×", "to 1.25×", "ρ̃/floor", "shape err max",
           "shape err RMS", "m err", "it", "termination"]
    body = []
    for r in rows:
        t = num(r, "seconds")
        pct = lambda k: 100.0 * num(r, k) / t if t > 0 else math.nan  # noqa: E731
        body.append([r["scene"], r["mesh"], int(num(r, "nodes")), r["method"], r["tau"] or "–",
                     num(r, "seconds_per_iteration"), pct("seconds_state"),
                     pct("seconds_distance"), pct("seconds_adjoint"), pct("seconds_optimizer"),
                     reached(r, "2"), reached(r, "1.5"), reached(r, "1.25"),
                     num(r, "rho_over_floor"), num(r, "shape_error_max"),
                     num(r, "shape_error_rms"), r.get("m_error") or "–",
                     int(num(r, "iterations")), r["termination"]])
    s.append(table(hdr, body))
    # The τ trade-off, per scene and mesh that has tree runs.
    for scene in sorted({r["scene"] for r in rows}):
        for mesh in sorted({r["mesh"] for r in rows if r["scene"] == scene}):
            group = [r for r in rows if r["scene"] == scene and r["mesh"] == mesh]
            exact = [r for r in group if r["method"] == "exact"]
            trees = [r for r in group if r["method"] == "tree"]
            if not exact or not trees:
                continue
            e = exact[0]
            s.append("\n%s %s, tree against exact: " % (scene, mesh))
            parts = []
            for r in trees:
                parts.append("τ = %s: distance time per evaluation × %s, final ρ̃/floor %s (exact "
                             "%s), shape error RMS %s (exact %s)" % (
                                 r["tau"],
                                 g((num(r, "seconds_distance") / max(num(r, "evaluations"), 1)) /
                                   (num(e, "seconds_distance") / max(num(e, "evaluations"), 1))),
                                 g(num(r, "rho_over_floor")), g(num(e, "rho_over_floor")),
                                 g(num(r, "shape_error_rms")), g(num(e, "shape_error_rms"))))
            s.append("; ".join(parts) + ".\n")
    fig, ax = plt.subplots(figsize=(7, 4))
    labels, parts = [], {k: [] for k in ("seconds_state", "seconds_distance", "seconds_adjoint",
                                         "seconds_optimizer")}
    for r in rows:
        labels.append("%s %s\n%s%s" % (r["scene"], r["mesh"], r["method"],
                                       (" " + r["tau"]) if r["tau"] else ""))
        for k in parts:
            parts[k].append(num(r, k) / max(num(r, "iterations"), 1))
    bottom = [0.0] * len(labels)
    for k, v in parts.items():
        ax.bar(range(len(labels)), v, bottom=bottom, label=k.replace("seconds_", ""))
        bottom = [a + b for a, b in zip(bottom, v)]
    ax.set_xticks(range(len(labels)))
    ax.set_xticklabels(labels, fontsize=6, rotation=60, ha="right")
    ax.set_ylabel("seconds per iteration")
    ax.legend(fontsize=8)
    fig.tight_layout()
    png = os.path.join(out, "control_split.png")
    fig.savefig(png, dpi=110)
    plt.close(fig)
    s.append("\n![time per iteration by stage](%s)\n" % rel(png, report))
    return "".join(s)


def section_stability(rows):
    s = ["## Numerical stress (`bench_stability`)\n",
         "Every run must end with finite numbers and a termination reason (`finite` = 1). "
         "ρ̃/floor is against the matched floor of the same α, ε.\n\n"]
    grid = [r for r in rows if r["case"] == "alpha-eps"]
    if grid:
        alphas = sorted({float(r["alpha"]) for r in grid})
        epss = sorted({float(r["eps"]) for r in grid}, reverse=True)
        cell = {(float(r["alpha"]), float(r["eps"])): r for r in grid}
        s.append("**Final ρ̃ / matched floor** (shape error RMS; termination) for α × ε:\n\n")
        hdr = ["α \\ ε"] + [g(e) for e in epss]
        body = []
        for a in alphas:
            line = [g(a)]
            for e in epss:
                r = cell.get((a, e))
                line.append("%s (%s; %s)" % (g(num(r, "rho_over_floor")),
                                             g(num(r, "shape_error_rms")),
                                             r["termination"]) if r else "–")
            body.append(line)
        s.append(table(hdr, body))
    other = [r for r in rows if r["case"] != "alpha-eps"]
    if other:
        s.append("\n**Other stress cases** (α = 4, ε = 1e-3):\n\n")
        s.append(table(["case", "bounds", "note", "target points", "ρ̃ start", "ρ̃ final",
                        "ρ̃/floor", "shape err RMS", "it", "failed evals", "finite",
                        "termination"],
                       [[r["case"], r["bounds"], r["note"] or "–", int(num(r, "target_points")),
                         num(r, "rho_start"), num(r, "rho_final"), num(r, "rho_over_floor"),
                         num(r, "shape_error_rms"), int(num(r, "iterations")),
                         int(num(r, "failed_evaluations")), r["finite"], r["termination"]]
                        for r in other]))
    bad = [r for r in rows if r["finite"] != "1"]
    s.append("\n%d of %d runs ended with finite numbers and a termination reason.\n"
             % (len(rows) - len(bad), len(rows)))
    return "".join(s)


def section_kernel(rows):
    s = ["## Pair kernel throughput (`bench_kernel`)\n",
         "Pairs per second of the exact method's pair loop, and the fraction of the measured "
         "per-core ceiling (the rate one core retires the kernel's unavoidable sqrt + divide).\n\n"]
    s.append(table(["work", "threads", "N = M", "seconds", "pairs/s", "of ceiling"],
                   [[r["work"], r["threads"], r["n"], num(r, "seconds"),
                     num(r, "pairs_per_second"), "%.0f %%" % (100 * num(r, "fraction_of_ceiling"))]
                    for r in rows]))
    return "".join(s)


# The goals for the goal cases of scripts/run_benchmarks.sh: (case, alpha, tau)
# -> (what is compared, the goal).
GOALS = {("asym", 4, 1e-4): ("exact/tree", 20.0),
         ("room", 4, 1e-4): ("exact/tree", 30.0),
         ("cube", 4, 1e-6): ("exact/tree", 1.5),
         ("cube", 64, 1e-6): ("tree/nearest", 5.0)}


def load_goals(path):
    """bench_hausdorff --goal appends a header per case: keep the data lines."""
    if not os.path.exists(path):
        return []
    with open(path, newline="") as f:
        lines = [line for i, line in enumerate(f) if i == 0 or not line.startswith("case,")]
    return list(csv.DictReader(lines))


def goal_row(rows):
    """One table row for the rows of one goal case (one per method)."""
    by = {r["method"]: r for r in rows}
    r0 = rows[0]
    key = (r0["case"], int(num(r0, "alpha")), num(r0, "tau"))
    what, goal = GOALS.get(key, ("", math.nan))
    tree, exact, near = by.get("tree"), by.get("exact"), by.get("nearest")
    t = num(tree, "seconds") if tree else math.nan
    ratio_wall = ratio_cpu = math.nan
    if what == "exact/tree" and tree and exact:
        ratio_wall, ratio_cpu = num(tree, "speedup"), num(tree, "cpu_speedup")
    elif what == "tree/nearest" and tree and near:
        ratio_wall = t / num(near, "seconds")
        ratio_cpu = num(tree, "cpu_seconds") / num(near, "cpu_seconds")
    if math.isnan(goal):
        met = "–"
    elif what == "exact/tree":
        met = "yes" if ratio_wall >= goal else "no"
    else:
        met = "yes" if ratio_wall <= goal else "no"
    basis = exact["exact_basis"] if exact else "–"
    return [r0["case"], "%d × %d" % (int(num(r0, "N")), int(num(r0, "M"))), g(num(r0, "alpha")),
            g(num(r0, "tau")), num(exact, "seconds") if exact else math.nan, basis, t,
            num(near, "seconds") if near else math.nan, what, ratio_wall, ratio_cpu,
            num(tree, "err_S_sample") if tree else math.nan,
            ("≥ " if what == "exact/tree" else "≤ ") + g(goal) if what else "–", met]


def section_goals(path):
    rows = load_goals(path)
    if not rows:
        return ""
    cases = []
    for r in rows:
        key = (r["case"], r["N"], r["M"], r["alpha"], r["tau"])
        if not cases or cases[-1][0] != key:
            cases.append((key, []))
        cases[-1][1].append(r)
    header = ["case", "N × M", "α", "τ", "exact s", "exact timed on", "tree s", "nearest s",
              "ratio", "wall", "CPU", "err_S (sample)", "goal", "met?"]
    return ("### The goal cases (value + gradient, medians of %s interleaved runs)\n\n"
            % rows[0].get("repeats", "?") +
            ("`exact timed on` sample:K means the exact sums were timed on K target points and "
            "scaled by M/K; `room` is a synthetic indoor scan standing in for a real "
            "room scan. err_S is the largest relative error of the tree's kernel sums on 500 "
            "sampled points, against exact sums.\n\n"
             + table(header, [goal_row(rows) for _, rows in cases]) + "\n"))


def section_hausdorff(out, report):
    paths = [p for p in (os.path.join(out, "hausdorff_ladder.csv"),) if os.path.exists(p)]
    if not paths:
        return ""
    tables = subprocess.run([sys.executable, os.path.join(HERE, "plot_hausdorff.py")] + paths +
                            ["--out", out], check=True, capture_output=True, text=True).stdout
    s = ["## The regularised Hausdorff distance alone (`bench_hausdorff`)\n",
         "Exact, tree (τ) and nearest on synthetic clouds; what is measured and the history "
         "of the tree's goals: [bench_hausdorff.md](%s).\n\n"
         % rel(os.path.join(HERE, "..", "docs", "bench_hausdorff.md"), report),
         section_goals(os.path.join(out, "hausdorff_goals.csv")),
         "### The ladder (one run per size)\n\n",
         "![time against error](%s)\n\n![time against N](%s)\n\n" % (
             rel(os.path.join(out, "hausdorff_time_vs_error.png"), report),
             rel(os.path.join(out, "hausdorff_time_vs_n.png"), report)),
         tables]
    return "".join(s)


def section_forward(rows):
    """softhd forward against FEniCS on the torsion beam (bench/bench_forward_fenics.py)."""
    best = {}
    for r in rows:
        code = r["code"]
        t = num(r, "solve_seconds")
        if code not in best or t < num(best[code], "solve_seconds"):
            best[code] = r
    text = ("## Forward solve against FEniCS\n\n"
            "Torsion beam, Q2 50x4x2 (13 635 dofs), uniform m = -5e5 from rest; softhd as "
            "`softhd forward` runs by default (grid sequencing: the 25x2x1 mesh solved "
            "first, then Newton with PCG on a kept Cholesky factorisation on the fine mesh; "
            "Newton its are coarse+fine, solve time includes both), the same from rest "
            "(`--coarse-levels 0`), from rest with a factorisation of every tangent "
            "(`classical`), and the independent FEniCS 2019 solver "
            "`bench/peers/fenics_forward.py` (Q2, MUMPS, load stepping), run alternately. "
            "Best solve time of the repeats (FEniCS: its `wall_solve_s`, JIT excluded), and "
            "the largest displacement difference from FEniCS at three probes.\n\n")
    f = best.get("fenics")
    rows_out = []
    for code in ("softhd", "softhd-from-rest", "softhd-classical", "fenics"):
        if code not in best:
            continue
        r = best[code]
        speed = (num(f, "solve_seconds") / num(r, "solve_seconds")) if f else math.nan
        rows_out.append([code, num(r, "solve_seconds"), r["newton_iterations"],
                         r["factorizations"], speed, num(r, "max_abs_diff_vs_fenics")])
    text += table(["code", "solve s", "Newton its", "factorisations", "x FEniCS speed",
                   "max abs diff vs FEniCS"], rows_out)
    if not f:
        text += "\nFEniCS was not installed for this run (apt-get install python3-dolfin).\n"
    return text


def section_finger(rows, out):
    """The Gmsh finger's state solve against FEniCS (bench/bench_finger.py)."""
    text = ("## The Gmsh finger against FEniCS\n\n"
            "`data/scenes/finger.json`'s body (P2 on the straight-sided tetrahedra of a "
            "first-order Gmsh file, two materials, clamped base) from rest under a uniform "
            "m, softhd (`softhd forward` as it runs by default: the P1 problem on the vertices "
            "first, then P2 from it) "
            "and the independent FEniCS 2019 solver (`bench/peers/fenics_forward.py scene`, "
            "P2, MUMPS, load stepping) on the same mesh and quadrature degree. At degree 7 "
            "both codes use the same 64-point rule (the discrete problems are the same); at "
            "degree 4 (softhd's default) both use 14 points but not the same ones, so the "
            "difference there is quadrature error. `finger50k` is finger.geo meshed finer "
            "by gmsh. Best solve time of the repeats (FEniCS: `wall_solve_s`, JIT "
            "excluded); differences are relative (probes: max |u − u_F|∞/|u_F| over three "
            "probes; nodes: max over every P2 node / max |u_F|, softhd's VTU has 12 "
            "digits).\n\n")
    best = {}
    for r in rows:
        key = (r["case"], r["code"])
        if key not in best or num(r, "solve_seconds") < num(best[key], "solve_seconds"):
            best[key] = r
    body = []
    for case in dict.fromkeys(r["case"] for r in rows):
        s, f = best.get((case, "softhd")), best.get((case, "fenics"))
        diffs = [r for r in rows if r["case"] == case and r["code"] == "softhd"]
        worst = lambda k: max(num(r, k) for r in diffs)  # noqa: E731
        body.append([case, s["dofs"] or "–", s["quadrature_degree"],
                     s["quadrature_points"] or "–", num(s, "solve_seconds"),
                     "%s / %s" % (s["newton_iterations"], s["factorizations"]),
                     num(f, "solve_seconds") if f else math.nan,
                     "%s / %s" % (f["newton_iterations"], f["factorizations"]) if f else "–",
                     num(f, "solve_seconds") / num(s, "solve_seconds") if f else math.nan,
                     worst("probe_rel_diff"), worst("energy_rel_diff"),
                     worst("volume_rel_diff"), worst("nodal_rel_diff")])
    text += table(["case", "dofs", "q degree", "points/tet", "softhd s", "softhd its / fact",
                   "FEniCS s", "FEniCS its / fact", "x FEniCS speed", "probes diff",
                   "energy diff", "volume diff", "nodes diff"], body)
    if not any(c == "fenics" for _, c in best):
        text += "\nFEniCS was not installed for this run (apt-get install python3-dolfin).\n"
    return text


def section_python(rows):
    """The Python module against C++ and plain PyTorch (bench/bench_python.py)."""
    text = ("## Python module\n\n"
            "`softhd.distance` against the same `softhd::hausdorff` call from C++ (exact, value "
            "+ gradient; goal: overhead <= 5 %), and `softhd.torch.HausdorffLoss` value + "
            "backward against a plain PyTorch implementation of formulation.md §2 (float64, "
            "chunked `cdist` + `logsumexp`, autograd; goal >= 30x, values equal to 1e-12 "
            "relative). Minimum and median seconds of the repeats (plain PyTorch: one run).\n\n")
    out = []
    by = {}
    for r in rows:
        by.setdefault(r["benchmark"], []).append(r)
    for bench, rs in by.items():
        base = num(rs[0], "min_seconds")
        for r in rs:
            ratio = num(r, "min_seconds") / base
            out.append([bench, r["n"], r["implementation"], num(r, "min_seconds"),
                        num(r, "median_seconds"), ratio, num(r, "relative_difference"),
                        num(r, "overhead_inside_call")])
    return text + table(["benchmark", "N = M", "implementation", "min s", "median s",
                         "time / first row", "value rel. diff.",
                         "Python wall − C++ time, within one call (fraction)"], out)


def section_align(rows):
    """softhd align against Open3D (bench/bench_align.py)."""
    text = ("## Pose of a scan: softhd align against Open3D\n\n"
            "The deformed finger (data/targets/finger_target.ply, 4000 of its points as the "
            "body), random cameras (softhd.synthetic), views full and half (the left "
            "half of the image), 2000 visible points, noise 0.5 % of the body's size L, 3 % "
            "outliers. softhd: `softhd.align` (distance, cap and candidate score in align.log; "
            "the default score is the coverage score of docs/formulation.md §8.5); Open3D: "
            "FPFH + RANSAC + point-to-plane ICP, voxel L/40 (bench/peers/open3d_align.py). "
            "Success: rotation error < 2 degrees; translation error of the body's centre / L.\n\n")
    out = []
    for m in sorted({r["method"] for r in rows}):
        for v in ("full", "half"):
            sel = [r for r in rows if r["method"] == m and r["view"] == v]
            if not sel:
                continue
            med = lambda k: sorted(num(r, k) for r in sel)[len(sel) // 2]
            out.append([m, v, "%d/%d" % (sum(int(r["success"]) for r in sel), len(sel)),
                        med("rotation_deg"), med("translation_rel"), med("seconds"),
                        sum(num(r, "seconds") for r in sel)])
    return text + table(["method", "view", "success", "median rotation error (deg)",
                         "median translation error / L", "median seconds", "total seconds"],
                        out)


def section_time_to_floor(rows):
    """softhd optimise on the reference scenes, MMA and newton side by side
    (bench/bench_time_to_floor.py)."""
    text = ("## Time to the floor (`bench_time_to_floor.py`)\n\n"
            "`softhd optimise` on each reference scene with MMA (the paper's method) and with "
            "the trust-region Newton–CG (`--algorithm newton`), one run at a time on 2 cores, "
            "each from its own clock (all levels). `to k×`: the first accepted iteration on the "
            "user's mesh with ρ̃ ≤ k × the matched floor, and the run's time then (a multilevel "
            "run's start on the user's mesh may already be below k: it is not counted). `pg to "
            "k`: the first such iteration at which the projected-gradient norm fell to k × its "
            "value at the first iteration on the user's mesh; `pg end` that ratio at the end. "
            "`CG/step`: newton's CG iterations per Newton step. Run with `--mesh-independence` "
            "(not by `make bench`), rows follow that run newton on one level on the plate at "
            "three resolutions (the Newton iterations to the gradient goal should not grow with "
            "the mesh). Goals: bending ≤ 1.01× within "
            "40 s and the projected gradient ≤ 1e-4 × within 120 s; finger ≤ 1.01× within 20 s; "
            "torsion ≤ 1.5× within 30 s.\n\n")
    out = []
    for r in rows:
        def to(k, key="%g"):
            it = r.get(("it_to_" + key) % k, "")
            return "%s it / %s s" % (it, r[("s_to_" + key) % k]) if it else "not reached"
        out.append([r["case"], r["flags"], to(1.25), to(1.05), to(1.01),
                    to(1e-2, "pg_%g"), to(1e-4, "pg_%g"), r.get("pg_final_over_first", ""),
                    r["ratio_final"], r["iterations"], r.get("cg_per_step", "") or "–",
                    r["seconds"], r["seconds_state"], r["seconds_distance"],
                    r["seconds_adjoint"], r["levels"], r["termination"]])
    return text + table(["case", "limits", "to 1.25×", "to 1.05×", "to 1.01×", "pg to 1e-2",
                         "pg to 1e-4", "pg end", "ρ̃/floor at the end", "it", "CG/step", "s",
                         "state s", "distance s", "adjoint s", "per level", "termination"], out)


def section_cells(rows):
    s = ["## Quadrature: the distance integrated over cells (`bench_cells`)\n\n",
         "ρ̃ (ε = 1e-3, α = β = 4, γ = 2) of two bodies of hexahedra, integrated over their cells "
         "(`--quadrature cells`), against the paper's collocation at the cells' nodes (lumped "
         "volumes) and at their centres, and against the continuum value (docs/formulation.md "
         "§2.8, an independent high-order quadrature). Seconds of one ρ̃, both directions.\n\n"]
    by = {}
    for r in rows:
        by[(r["section"], r["case"], r["pair"], r["quadrature"])] = r

    def err(r):
        return "%+.3f %%" % (100 * (num(r, "rho") / num(r, "reference") - 1))

    for section, title in (("cube", "**The unit cube** (n_X³ against n_Y³ cells)"),
                           ("plate", "**The plate 10 × 2 × 0.1 against itself** (J and the "
                                     "collocation by the tree at τ = 1e-2)")):
        keys = []
        for r in rows:
            k = (r["case"], r["pair"])
            if r["section"] == section and k not in keys:
                keys.append(k)
        if not keys:
            continue
        s.append(title + ":\n\n")
        out = []
        for case, pair in keys:
            c, n, m = (by.get((section, case, pair, q)) for q in ("cells", "nodes", "centres"))
            if not (c and n and m):
                continue
            out.append([case, pair, "%.9f" % num(c, "reference"), "%.9f" % num(c, "rho"), err(c),
                        err(n), err(m), num(c, "seconds"), num(n, "seconds")])
        s.append(table(["case", "n_X × n_Y", "continuum", "cells", "error", "collocation, nodes",
                        "collocation, centres", "s (cells)", "s (nodes)"], out))
        s.append("\n")
    # The shift curve and the ranking, from the cube rows.
    shifts = [("shift 0.0025", 0.0025), ("shift 0.005", 0.005), ("shift 0.01", 0.01),
              ("shift 0.02", 0.02)]
    out = []
    for pair in ("8x8", "12x16"):
        base = {q: by.get(("cube", "self", pair, q)) for q in ("cells", "nodes", "centres")}
        for case, d in shifts:
            row = [pair, d]
            have = True
            for q in ("cells", "nodes", "centres"):
                r = by.get(("cube", case, pair, q))
                if not (r and base[q]):
                    have = False
                    break
                if q == "cells":
                    row.append("%+.5f" % (num(r, "reference") - num(base[q], "reference")))
                row.append("%+.5f" % (num(r, "rho") - num(base[q], "rho")))
            if have:
                out.append(row)
    if out:
        s.append("**Translation** (Δρ̃ from the same pair untranslated):\n\n")
        s.append(table(["n_X × n_Y", "shift", "continuum", "cells", "collocation, nodes",
                        "collocation, centres"], out))
        s.append("\n")
    out = []
    for pair in sorted({r["pair"] for r in rows if r["section"] == "cube"}):
        for q in ("cells", "nodes", "centres"):
            v = [by.get(("cube", c, pair, q)) for c in ("self", "side 0.875", "shift 1/16")]
            if not all(v):
                continue
            rho = [num(r, "rho") for r in v]
            out.append([pair, q] + ["%.4f" % x for x in rho] +
                       ["yes" if rho[0] < min(rho[1:]) else "**no**"])
    if out:
        s.append("**Ranking** (the correct shape must score lowest; continuum 0.1242 / 0.2014 / "
                 "0.1818):\n\n")
        s.append(table(["n_X × n_Y", "quadrature", "correct", "side 0.875", "shifted 1/16",
                        "correct first"], out))
        s.append("\n")
    out = []
    for r in rows:
        if r["section"] != "loop" or r["quadrature"] != "cells":
            continue
        n = by.get(("loop", r["case"], r["pair"], "nodes"))
        if n:
            out.append([r["case"], r["pair"], "%.6f" % num(n, "rho"), "%.6f" % num(r, "rho"),
                        num(n, "seconds"), num(r, "seconds"),
                        "%.0f×" % (num(r, "seconds") / num(n, "seconds"))])
    if out:
        s.append("**The bending loop** (data/scenes/bending.json at the bent control "
                 "m = −2.6e4 X₃/0.1: the body's 4 000 hexahedra against the arc target's cells, "
                 "the scene's 200 × 20 × 8 and the body's 100 × 10 × 4; the distance's seconds "
                 "in one objective evaluation, the tree at τ = 1e-2 for both; the goal is "
                 "3×):\n\n")
        s.append(table(["target", "evaluation", "ρ̃ (nodes)", "ρ̃ (cells)", "s (nodes)",
                        "s (cells)", "cells / nodes"], out))
    return "".join(s)


def main():
    p = argparse.ArgumentParser(description=__doc__)
    p.add_argument("out")
    p.add_argument("--report", required=True)
    p.add_argument("--quick", action="store_true")
    a = p.parse_args()
    out = a.out
    parts = ["# Benchmarks\n\n",
             "Generated by `make bench` (`scripts/run_benchmarks.sh build docs/bench "
             "docs/benchmarks.md`) from the CSV files in `%s/`; every number below comes from "
             "them. The machine is a shared 2-core VM: compare ratios within one run. "
             "`scripts/run_benchmarks.sh --only NAME,...` re-runs some benchmarks and "
             "rebuilds the report from all CSVs present.\n\n"
             % os.path.normpath(out)]
    if a.quick:
        parts.append("**Smoke run (`make bench-quick`)**: tiny meshes and a few iterations; "
                     "the numbers only show that every benchmark runs end to end.\n\n")
    parts.append(wall_times(out, ["kernel", "hausdorff", "resolution", "control", "stability",
                                  "time_to_floor", "forward_fenics", "finger", "align",
                                  "python", "cells"]))
    sections = [("resolution", lambda r: section_resolution(r, out, a.report)),
                ("control", lambda r: section_control(r, out, a.report)),
                ("stability", section_stability),
                ("time_to_floor", section_time_to_floor),
                ("kernel", section_kernel),
                ("forward_fenics", section_forward),
                ("finger", lambda r: section_finger(r, out)),
                ("align", section_align),
                ("python", section_python),
                ("cells", section_cells)]
    for name, make in sections:
        rows = load(os.path.join(out, name + ".csv"))
        if rows:
            parts.append(make(rows))
            parts.append("\nRun:\n\n" + meta(out, name) + "\n")
    h = section_hausdorff(out, a.report)
    if h:
        parts.append(h + "\nRun:\n\n" + meta(out, "hausdorff") + "\n")
    with open(a.report, "w") as f:
        f.write("".join(parts))


if __name__ == "__main__":
    main()
