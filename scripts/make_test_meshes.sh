#!/usr/bin/env bash
# Regenerates the Gmsh meshes of the tests (tests/data/meshes) and of the example body
# (data/meshes) from their .geo sources with the gmsh program (Debian gmsh 4.8.4; the
# library never links libgmsh). The .msh files are committed: the tests do not need gmsh.
# usage: scripts/make_test_meshes.sh
set -euo pipefail
cd "$(dirname "$0")/.."
command -v gmsh >/dev/null || { echo "make_test_meshes: gmsh is missing (apt-get install gmsh)"; exit 1; }
g() { gmsh "$@" -v 2 >/dev/null; }

cd tests/data/meshes
# The same tet4 and tet10 meshes in MSH 4.1 ASCII, 4.1 binary and 2.2 ASCII: meshed once,
# the 4.1 ASCII file converted by gmsh (-save re-reads the mesh, it does not remesh).
for order in 1 2; do
  name=cube_tet$([ $order = 1 ] && echo 4 || echo 10)
  g cube_tet.geo -3 -order $order -format msh41 -o ${name}_v41.msh
  g ${name}_v41.msh -save -format msh41 -bin -o ${name}_v41_bin.msh
  g ${name}_v41.msh -save -format msh22 -o ${name}_v22.msh
done
g box_hex27.geo -3 -format msh41 -o box_hex27_v41.msh
g cylinder_tet.geo -3 -order 2 -format msh41 -o cylinder_tet10_v41.msh  # curved tet10
g save_all.geo -3 -format msh41 -o save_all.msh  # one volume in no physical group
cp save_all.msh ../../../fuzz/corpus/msh/save_all_v41.msh
g plate_2d.geo -2 -format msh41 -o plate_2d_v41.msh
g two_boxes.geo -3 -format msh41 -o two_boxes_nonconforming.msh
g plate_2d.geo -2 -format msh22 -o plate_2d_v22.msh
g sparse.geo -0                       # writes sparse.msh itself (after Coherence Mesh)
g fields.geo -0 && mv fields_bin_0.msh fields_bin.msh   # fields.msh is hand-written
rm -f ./*.geo_unrolled

# The example body (docs/guide.md, "A body from Gmsh"): first-order tetrahedra; the target's
# finer mesh is its uniform refinement (each tetrahedron split in 8, no snapping to the CAD
# surface), so every node of the scene's P2 mesh is a vertex of the finer one.
cd ../../../data/meshes
g finger.geo -3 -format msh41 -o finger.msh
g finger.msh -refine -format msh41 -o finger_fine.msh
