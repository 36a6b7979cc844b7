#!/usr/bin/env python3
"""softhd forward's VTU of a Gmsh body read back by meshio (an independent reader, issue 30):
the node count equals meshio's reading of the same .msh, the cells are VTK's quadratic
tetrahedra with every midside node at the midpoint of VTK's edge (0,1), (1,2), (2,0), (0,3),
(1,3), (2,3) in the reference configuration, their volume sums to the body's, and the region
ids are cell data.

    vtu_meshio.py SOFTHD MESH_DIR WORK_DIR
"""
import json
import os
import subprocess
import sys

try:
    import meshio
    import numpy as np
except ImportError:
    print("skipped: python3-meshio is missing")
    sys.exit(0)

VTK_TET10_EDGES = [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)]


def main(softhd, mesh_dir, work):
    os.makedirs(work, exist_ok=True)
    msh = os.path.abspath(os.path.join(mesh_dir, "cube_tet10_v41.msh"))
    scene = {"name": "cube", "mesh": {"type": "gmsh", "file": msh},
             "material": {"model": "mooney_rivlin", "a": 1, "b": 0.2, "c": 3},
             "fibers": [1, 0, 0], "clamp": ["base"],
             "control": {"space": "vertex", "lower": -1, "upper": 0}}
    path = os.path.join(work, "cube.json")
    with open(path, "w") as f:
        json.dump(scene, f)
    out = os.path.join(work, "out")
    subprocess.run([softhd, "forward", path, "--out", out], check=True, stdout=subprocess.DEVNULL)
    vtu = meshio.read(os.path.join(out, "forward.vtu"))
    ref = meshio.read(msh)
    failures = []
    n_ref = len(np.unique(np.concatenate([c.data.ravel() for c in ref.cells if c.type == "tetra10"])))
    if vtu.points.shape[0] != n_ref:
        failures.append(f"{vtu.points.shape[0]} points, the .msh has {n_ref}")
    cells = [c for c in vtu.cells if c.type == "tetra10"]
    if len(cells) != 1:
        failures.append(f"cell blocks {[c.type for c in vtu.cells]}, expected tetra10 only")
    tets = cells[0].data
    X = vtu.points  # zero control: the reference configuration (u = 0)
    mid_err = max(np.abs(X[t[4 + k]] - 0.5 * (X[t[a]] + X[t[b]])).max()
                  for t in tets for k, (a, b) in enumerate(VTK_TET10_EDGES))
    if mid_err > 1e-12:
        failures.append(f"a midside node is {mid_err} off its VTK edge's midpoint")
    v = X[tets[:, 1:4]] - X[tets[:, [0]]]
    volume = np.abs(np.linalg.det(v)).sum() / 6.0  # straight-sided cells
    if abs(volume - 1.0) > 1e-12:
        failures.append(f"cell volume {volume}, the unit cube's is 1")
    region = vtu.cell_data.get("region")
    if region is None or sorted(set(np.asarray(region[0]).astype(int).ravel().tolist())) != [0, 1]:
        failures.append("no region cell data with ids 0 and 1")
    for f in failures:
        print("FAIL:", f)
    print(f"{vtu.points.shape[0]} points, {len(tets)} tetra10 cells, volume {volume:.15f}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:4]))
