#!/usr/bin/env python3
"""Quadrature degree of simplices: accuracy against cost (issue 30 item 5).

The same forward solve at every quadrature degree the scene accepts (mesh.quadrature_degree
1 to 8): the finger of data/scenes/finger.json (two materials, clamped base) as P1 and as
straight-sided P2 tetrahedra under a uniform m, and a 2D plate of triangles (P1, P2) made
here with the gmsh program, bent by m on its upper half. Per degree: quadrature points
per element, Newton iterations, solve seconds, seconds per Newton iteration, the energy
and the tip displacement, and their relative differences from degree 8 (the reference:
the integrands are not polynomials, so no degree is exact). A degree at which the solve
fails or inverts an element is reported as such.

  studies/bench_quadrature.py BUILD_DIR [--csv FILE] [--threads T]

Prints a CSV: case, degree, points (per element), converged, newton (iterations), seconds
(solve), s_per_newton, energy, tip (|u| at the probe), rel_energy, rel_tip (|u - u_8| /
|u_8|). A failed solve has its message in the last column.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
DEGREES = range(1, 9)  # the scene's mesh.quadrature_degree range

PLATE_GEO = """
Point(1) = {0, 0, 0}; Point(2) = {10, 0, 0}; Point(3) = {10, 1, 0}; Point(4) = {0, 1, 0};
Line(1) = {1, 2}; Line(2) = {2, 3}; Line(3) = {3, 4}; Line(4) = {4, 1};
Curve Loop(1) = {1, 2, 3, 4}; Plane Surface(1) = {1};
Physical Surface("body") = {1};
Physical Curve("left") = {4};
Mesh.MeshSizeMax = 0.25;
"""


def finger_scene(order, degree, work):
    with open(os.path.join(ROOT, "data", "scenes", "finger.json")) as f:
        s = json.load(f)
    s["name"] = "finger_q%d_p%d" % (degree, order)
    s["mesh"]["file"] = os.path.join(ROOT, "data", "meshes", "finger.msh")
    s["mesh"]["order"] = order
    s["mesh"]["quadrature_degree"] = degree
    s.pop("target", None)
    path = os.path.join(work, s["name"] + ".json")
    with open(path, "w") as f:
        json.dump(s, f)
    return path


def plate_scene(order, degree, work, msh):
    s = {"name": "plate_q%d_p%d" % (degree, order),
         "mesh": {"type": "gmsh", "file": msh, "order": order, "quadrature_degree": degree},
         "material": {"model": "mooney_rivlin", "a": 1e5, "b": 2e4, "c": 3e5},
         "fibers": [1, 0, 0], "clamp": ["left"],
         "control": {"space": "element", "lower": -1e5, "upper": 0}}
    path = os.path.join(work, s["name"] + ".json")
    with open(path, "w") as f:
        json.dump(s, f)
    return path


def run(build, scene, threads, uniform, probe, control_file=None):
    cmd = [os.path.join(build, "apps", "softhd"), "forward", scene, "--json",
           "--threads", str(threads), "--probe", probe,
           "--out", os.path.join(os.path.dirname(scene), "out")]
    cmd += ["--control", control_file] if control_file else ["--control-uniform", str(uniform)]
    r = subprocess.run(cmd, capture_output=True, text=True)
    if r.returncode not in (0, 1) or not r.stdout.strip():
        return {"error": (r.stderr.strip().splitlines() or ["exit %d" % r.returncode])[-1]}
    return json.loads(r.stdout)


def plate_control(build, scene, path):
    """Element controls: m = -2e4 on the upper half (X2 > 0.5), 0 below: it bends."""
    nodes = path + ".nodes"
    subprocess.run([os.path.join(build, "apps", "softhd"), "forward", scene,
                    "--write-control-nodes", nodes], check=True, capture_output=True)
    with open(nodes) as f, open(path, "w") as out:
        for line in f:
            if line.startswith("#") or not line.strip():
                out.write(line)
                continue
            x = line.split()
            out.write("%s %s %s\n" % (x[0], x[1], -2e4 if float(x[1]) > 0.5 else 0.0))
    return path


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("build")
    p.add_argument("--csv")
    p.add_argument("--threads", type=int, default=2)
    a = p.parse_args()
    work = tempfile.mkdtemp(prefix="softhd-quadrature-")
    try:
        geo = os.path.join(work, "plate.geo")
        with open(geo, "w") as f:
            f.write(PLATE_GEO)
        msh = os.path.join(work, "plate.msh")
        subprocess.run(["gmsh", geo, "-2", "-format", "msh41", "-o", msh, "-v", "0"], check=True)
        cases = []
        for order in (1, 2):
            cases.append(("finger_tet%d" % (4 if order == 1 else 10),
                          lambda d, o=order: finger_scene(o, d, work), -10.0, "60,6,11.5", None))
        for order in (1, 2):
            cases.append(("plate_tri%d" % (3 if order == 1 else 6),
                          lambda d, o=order: plate_scene(o, d, work, msh), None, "10,0.5", "plate"))
        rows = []
        for name, make, uniform, probe, control in cases:
            results = {}
            for d in DEGREES:
                scene = make(d)
                cfile = None
                if control:
                    cfile = plate_control(a.build, scene, os.path.join(work, name + "_%d.ctl" % d))
                results[d] = run(a.build, scene, a.threads, uniform, probe, cfile)
            ref = results[max(DEGREES)]
            for d in DEGREES:
                r = results[d]
                if "error" in r or not r.get("converged"):
                    rows.append([name, d, "", 0, r.get("newton_iterations", ""), "", "", "", "",
                                 "", r.get("error", r.get("status", ""))])
                    continue
                tip = r["probes"][0]["u"]
                tip_ref = ref["probes"][0]["u"]
                norm = sum(t * t for t in tip) ** 0.5
                dtip = (sum((x - y) ** 2 for x, y in zip(tip, tip_ref)) ** 0.5 /
                        sum(t * t for t in tip_ref) ** 0.5)
                de = abs(r["energy"] - ref["energy"]) / abs(ref["energy"])
                n = max(1, r["newton_iterations"])
                rows.append([name, d, r.get("quadrature_points_per_element", ""), 1,
                             r["newton_iterations"], "%.3f" % r["seconds_solve"],
                             "%.4f" % (r["seconds_solve"] / n), "%.12e" % r["energy"],
                             "%.9e" % norm, "%.2e" % de, "%.2e" % dtip])
        header = ["case", "degree", "points", "converged", "newton", "seconds", "s_per_newton",
                  "energy", "tip", "rel_energy", "rel_tip"]
        lines = [",".join(header)] + [",".join(str(x) for x in r) for r in rows]
        print("\n".join(lines))
        if a.csv:
            with open(a.csv, "w") as f:
                f.write("\n".join(lines) + "\n")
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
