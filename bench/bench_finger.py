#!/usr/bin/python3
"""The Gmsh finger's state solve: softhd against FEniCS on the same tetrahedra, in one run (its
optimisation is in bench_time_to_floor.py).

Forward cases, each from rest under the uniform control m = --m0 (softhd as `softhd forward` runs
by default: a P1 solve on the vertices first, then P2 from it; FEniCS with load stepping), P2 on straight-sided tetrahedra: the finger's
first-order file with "order": 2 (legacy dolfin has no curved geometry; softhd adds the
same edge midpoints):
  finger_q7     data/meshes/finger.msh (14 547 dofs), quadrature degree 7 on both sides:
                there both codes use the same rule, the 64-point collapsed Gauss-Jacobi
                rule (softhd's quadrature.cpp, FIAT's default above degree 6), so the two
                discrete problems are the same: the agreement test.
  finger_q4     the same mesh at degree 4, softhd's default for P2 tetrahedra: the same
                degree but not the same points (softhd: Walkington's 14 points, exact to
                degree 5; FIAT: Keast's 14 points, degree 4), so the difference is
                quadrature error.
  finger50k_q4  data/meshes/finger.geo meshed by gmsh with Mesh.MeshSizeMax --fine-size
                (Min half of it), about 54 000 dofs, degree 4: the speed case.
softhd runs `softhd forward SCENE --control-uniform M --json`, FEniCS
bench/peers/fenics_forward.py's `scene` mode (P2, exact Newton, MUMPS, load stepping),
alternately --repeats times. Solve seconds: softhd's seconds_solve (Newton), FEniCS's
wall_solve_s (JIT excluded); process CPU seconds of each (setup included) as context.
Differences from FEniCS's run of the same repeat: probes (max over probes of
|u - u_F|_inf / |u_F|), total energy and deformed volume (relative), and every P2 node
(max |u - u_F| / max |u_F|, softhd's nodes read from its VTU, 12 significant digits).

Without python3-dolfin the FEniCS rows are skipped with one line on stderr.

  bench/bench_finger.py BUILD_DIR [--repeats N] [--csv FILE] [--threads T] [--m0 M]
                        [--cases a,b] [--fine-size H]
"""
import argparse
import json
import os
import resource
import shutil
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
SCENE = os.path.join(ROOT, "data", "scenes", "finger.json")
GEO = os.path.join(ROOT, "data", "meshes", "finger.geo")
PROBES = [(60.0, 6.0, 11.5), (60.0, 0.0, 0.0), (30.0, 6.0, 1.5)]
CASES = ["finger_q7", "finger_q4", "finger50k_q4"]


def have(module):
    r = subprocess.run(["/usr/bin/python3", "-c", "import " + module], capture_output=True)
    return r.returncode == 0


def fine_mesh(work, size):
    """finger.geo meshed with Mesh.MeshSizeMax = size (Min size/2), made once per size."""
    msh = os.path.join(work, "finger_h%g.msh" % size)
    if os.path.exists(msh):
        return msh
    geo = os.path.join(work, "finger_h%g.geo" % size)
    with open(geo, "w") as f:
        f.write('Include "%s";\nMesh.MeshSizeMax = %r;\nMesh.MeshSizeMin = %r;\n'
                % (GEO, size, size / 2))
    subprocess.run(["gmsh", geo, "-3", "-format", "msh41", "-o", msh + ".part", "-v", "0"],
                   check=True)
    os.replace(msh + ".part", msh)
    return msh


def write_scene(work, name, mesh_file, qdeg):
    """data/scenes/finger.json on another mesh file with an explicit quadrature degree."""
    with open(SCENE) as f:
        s = json.load(f)
    s["mesh"]["file"] = mesh_file
    s["mesh"]["quadrature_degree"] = qdeg
    s.pop("target", None)  # a forward solve needs none
    path = os.path.join(work, name + ".json")
    with open(path, "w") as f:
        json.dump(s, f, indent=1)
    return path


def child_cpu():
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run_softhd(build, scene, m0, threads, out):
    cmd = [os.path.join(build, "apps", "softhd"), "forward", scene, "--control-uniform",
           str(m0), "--json", "--threads", str(threads), "--out", out]
    for p in PROBES:
        cmd += ["--probe", "%g,%g,%g" % p]
    c0 = child_cpu()
    d = json.loads(subprocess.run(cmd, capture_output=True, text=True, check=True).stdout)
    res = {"seconds": d["seconds_solve"], "cpu": child_cpu() - c0,
           "newton_iterations": d["newton_iterations"], "factorizations": d["factorizations"],
           "energy": d["energy"], "volume": d["volume"], "u": [p["u"] for p in d["probes"]],
           "dofs": None, "qpoints": None}
    try:
        import meshio
        m = meshio.read(d["vtu"])
        U = m.point_data["displacement"]
        res["nodes"] = (m.points - U, U)
    except ImportError:
        res["nodes"] = None
    return res


def run_fenics(scene, m0, npz):
    cmd = ["/usr/bin/python3", os.path.join(HERE, "peers", "fenics_forward.py"), "scene", scene,
           "--m0", str(m0), "--json", "--nodes-out", npz]
    for p in PROBES:
        cmd += ["--probe", "%r,%r,%r" % p]
    c0 = child_cpu()
    out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    d = json.loads(out[out.index("{"):])  # FFC's JIT lines come first on a cold cache
    z = np.load(npz)
    return {"seconds": d["wall_solve_s"], "cpu": child_cpu() - c0,
            "newton_iterations": d["newton_iterations"], "factorizations": d["factorizations"],
            "energy": d["energy_total_W_plus_Wm"], "volume": d["volume_deformed"],
            "u": [p["u"] for p in d["probes"]], "dofs": d["ndofs"],
            "qpoints": d["quadrature_points_per_cell"], "nodes": (z["X"], z["u"])}


def differences(s, f):
    """Relative differences of softhd's run s from FEniCS's run f."""
    probe = max(np.abs(np.subtract(us, uf)).max() / np.linalg.norm(uf)
                for us, uf in zip(s["u"], f["u"]))
    nodal = ""
    if s["nodes"] is not None:
        from scipy.spatial import cKDTree
        (Xs, Us), (Xf, Uf) = s["nodes"], f["nodes"]
        dist, idx = cKDTree(Xs).query(Xf)
        if Xs.shape[0] != Xf.shape[0] or dist.max() > 1e-8 * np.abs(Xf).max():
            raise RuntimeError("the two codes' P2 nodes differ (%d against %d nodes, %.3g apart)"
                               % (Xs.shape[0], Xf.shape[0], dist.max()))
        nodal = np.abs(Us[idx] - Uf).max() / np.abs(Uf).max()
    return [probe, abs(s["energy"] - f["energy"]) / abs(f["energy"]),
            abs(s["volume"] - f["volume"]) / abs(f["volume"]), nodal]


def forward_rows(a, work, fenics):
    scenes = {}
    for case in a.cases:
        if case == "finger50k_q4":
            if shutil.which("gmsh") is None:
                print("bench_finger: gmsh is not installed; finger50k_q4 skipped",
                      file=sys.stderr)
                continue
            mesh, q = fine_mesh(work, a.fine_size), 4
        else:
            mesh, q = os.path.join(ROOT, "data", "meshes", "finger.msh"), int(case[-1])
        scenes[case] = (write_scene(work, case, mesh, q), q)
    rows = []
    for r in range(a.repeats):
        for case, (scene, q) in scenes.items():
            res = [("softhd", run_softhd(a.build, scene, a.m0, a.threads,
                                         os.path.join(work, case)))]
            if fenics:
                res.append(("fenics", run_fenics(scene, a.m0, os.path.join(work, case + ".npz"))))
            f = dict(res).get("fenics")
            for code, x in res:
                diff = [""] * 4 if f is None or code == "fenics" else differences(x, f)
                rows.append([case, code, r, f["dofs"] if f else "", q,
                             f["qpoints"] if f else "", x["seconds"], round(x["cpu"], 2),
                             x["newton_iterations"], x["factorizations"], repr(x["energy"]),
                             repr(x["volume"])] + [repr(v) for v in x["u"][0]] + diff)
            print(",".join(str(v) for v in rows[-1]), file=sys.stderr, flush=True)
    return rows


def write_csv(path, header, rows):
    text = "\n".join([header] + [",".join(str(v) for v in r) for r in rows]) + "\n"
    sys.stdout.write(text)
    if path:
        with open(path, "w") as f:
            f.write(text)


def summary(rows):
    best = {}
    for r in rows:
        key = (r[0], r[1])
        best[key] = min(best.get(key, 1e300), float(r[6]))
    for case in dict.fromkeys(r[0] for r in rows):
        if (case, "fenics") in best:
            diffs = [r for r in rows if r[0] == case and r[1] == "softhd"]
            print("# %s: softhd best %.3f s, FEniCS best %.3f s: %.2fx; largest relative "
                  "differences: probes %.2g, energy %.2g, volume %.2g, nodes %s"
                  % (case, best[(case, "softhd")], best[(case, "fenics")],
                     best[(case, "fenics")] / best[(case, "softhd")],
                     max(float(r[15]) for r in diffs), max(float(r[16]) for r in diffs),
                     max(float(r[17]) for r in diffs),
                     "%.2g" % max(float(r[18]) for r in diffs) if diffs[0][18] != "" else "-"))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("build")
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--m0", type=float, default=-10.0, help="the uniform control (kPa)")
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--fine-size", type=float, default=1.65, help="finger50k's MeshSizeMax")
    ap.add_argument("--csv")
    a = ap.parse_args()
    a.cases = [c for c in a.cases.split(",") if c]
    for c in a.cases:
        if c not in CASES:
            ap.error("--cases: unknown case %r (known: %s)" % (c, ", ".join(CASES)))
    work = os.path.join(os.path.abspath(a.build), "bench-finger")
    os.makedirs(work, exist_ok=True)
    fenics = have("dolfin") and have("meshio")
    if not fenics:
        print("bench_finger: python3-dolfin or python3-meshio is not installed; FEniCS skipped "
              "(apt-get install python3-dolfin python3-meshio)", file=sys.stderr)
    rows = forward_rows(a, work, fenics)
    write_csv(a.csv, "case,code,repeat,dofs,quadrature_degree,quadrature_points,solve_seconds,"
              "process_cpu_seconds,newton_iterations,factorizations,energy,volume,u1_probe,"
              "u2_probe,u3_probe,probe_rel_diff,energy_rel_diff,volume_rel_diff,"
              "nodal_rel_diff", rows)
    summary(rows)

if __name__ == "__main__":
    main()
