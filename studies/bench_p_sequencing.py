#!/usr/bin/env python3
"""p-sequencing against the start from rest, on the finger, in one run (issue 30).

The finger of data/scenes/finger.json (straight-sided P2 tetrahedra on data/meshes/finger.msh,
4849 nodes) and the same body meshed finer (finger.geo through gmsh -clscale 0.55, about
50 000 dofs; made in BUILD_DIR/bench-p-sequencing), under uniform controls: `softhd forward`
from rest (`--coarse-levels 0`) and p-sequenced (`--coarse-levels 1`: P1 on the vertices of
the same tetrahedra first, its state interpolated onto the P2 nodes, then the P2 Newton solve
at full load), alternately --repeats times. Prints a CSV row per run (solve seconds, coarse
levels included; the CPU seconds of the whole process, mesh reading and output included;
Newton iterations and factorisations of each level) and, per mesh and control, the median
solve time of each start and their ratio (also the ratio of the best times and of the
median process CPU times, which a loaded machine disturbs less). Both starts must reach the same
equilibrium (energies equal to 1e-9 relative), else the script fails.

  studies/bench_p_sequencing.py BUILD_DIR [--repeats N] [--threads T] [--controls=-5,-10,-20]
                              [--meshes finger,finger50k] [--csv FILE]
"""
import argparse
import csv
import json
import os
import resource
import statistics
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
SCALE_50K = 0.55  # gmsh -clscale on finger.geo: 2751 vertices, 52 755 free P2 dofs


def scene_files(build):
    """The two finger scenes (no target: forward solves only), the finer mesh made here."""
    work = os.path.join(build, "bench-p-sequencing")
    os.makedirs(work, exist_ok=True)
    fine = os.path.join(work, "finger50k.msh")
    if not os.path.exists(fine):
        subprocess.run(["gmsh", os.path.join(ROOT, "data", "meshes", "finger.geo"), "-3",
                        "-clscale", str(SCALE_50K), "-format", "msh41", "-o", fine, "-v", "2"],
                       check=True, capture_output=True)
    with open(os.path.join(ROOT, "data", "scenes", "finger.json")) as f:
        base = json.load(f)
    base.pop("target", None)
    scenes = {}
    for name, mesh in (("finger", os.path.join(ROOT, "data", "meshes", "finger.msh")),
                       ("finger50k", fine)):
        s = dict(base, name=name, mesh=dict(base["mesh"], file=mesh))
        path = os.path.join(work, name + ".json")
        with open(path, "w") as f:
            json.dump(s, f, indent=1)
        scenes[name] = path
    return work, scenes


def run(build, work, scene, m, levels, threads):
    cmd = [os.path.join(build, "apps", "softhd"), "forward", scene, "--control-uniform", str(m),
           "--coarse-levels", str(levels), "--json", "--threads", str(threads),
           "--out", os.path.join(work, "out")]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    d = json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    if not d["converged"]:
        sys.exit("bench_p_sequencing: %s m=%g levels %d did not converge" % (scene, m, levels))
    c = d["coarse_levels"]
    return {"dofs": d["dofs"], "seconds": d["seconds_solve"], "cpu_process": cpu,
            "energy": d["energy"],
            "coarse": c[0]["mesh"] if c else "",
            "coarse_iterations": sum(x["newton_iterations"] for x in c),
            "coarse_factorizations": sum(x["factorizations"] for x in c),
            "coarse_seconds": sum(x["seconds"] for x in c),
            "fine_iterations": d["newton_iterations"], "fine_factorizations": d["factorizations"]}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("build")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--controls", default="-5,-10,-20")
    ap.add_argument("--meshes", default="finger,finger50k")
    ap.add_argument("--csv")
    a = ap.parse_args()
    a.build = os.path.abspath(a.build)
    work, scenes = scene_files(a.build)
    fields = ["mesh", "dofs", "m", "start", "repeat", "seconds", "cpu_process", "coarse",
              "coarse_iterations", "coarse_factorizations", "coarse_seconds", "fine_iterations", "fine_factorizations",
              "energy"]
    out = open(a.csv, "w", newline="") if a.csv else sys.stdout
    w = csv.DictWriter(out, fieldnames=fields)
    w.writeheader()
    runs = {}
    for mesh in a.meshes.split(","):
        for m in [float(v) for v in a.controls.split(",")]:
            energy = {}
            for r in range(a.repeats):
                for start, levels in (("rest", 0), ("p-sequenced", 1)):
                    row = run(a.build, work, scenes[mesh], m, levels, a.threads)
                    row.update(mesh=mesh, m=m, start=start, repeat=r)
                    w.writerow(row)
                    out.flush()
                    energy[start] = row["energy"]
                    runs.setdefault((mesh, m, start), []).append(row)
            e0, e1 = energy["rest"], energy["p-sequenced"]
            if abs(e0 - e1) > 1e-9 * abs(e0):
                sys.exit("bench_p_sequencing: %s m=%g: energies differ (%r, %r)" % (mesh, m, e0, e1))
    print("\nmesh, dofs, m: median solve seconds from rest (its/facts) | p-sequenced (coarse "
          "its/facts, fine its/facts) | ratio of the medians (of the best; of the process CPU "
          "times' medians)", file=sys.stderr)
    med = lambda rows, k: statistics.median(r[k] for r in rows)
    for mesh in a.meshes.split(","):
        for m in [float(v) for v in a.controls.split(",")]:
            r0, r1 = runs[(mesh, m, "rest")], runs[(mesh, m, "p-sequenced")]
            f0, f1 = r0[0], r1[0]  # the counts are the same in every repeat
            print("%s, %d, %g: %.3f (%d/%d) | %.3f (%d/%d, %d/%d) | %.2fx (%.2fx; cpu %.2fx)" % (
                mesh, f0["dofs"], m, med(r0, "seconds"), f0["fine_iterations"],
                f0["fine_factorizations"], med(r1, "seconds"), f1["coarse_iterations"],
                f1["coarse_factorizations"], f1["fine_iterations"], f1["fine_factorizations"],
                med(r0, "seconds") / med(r1, "seconds"),
                min(r["seconds"] for r in r0) / min(r["seconds"] for r in r1),
                med(r0, "cpu_process") / med(r1, "cpu_process")), file=sys.stderr)


if __name__ == "__main__":
    main()
