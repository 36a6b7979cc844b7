"""softhd.read_mesh against an independent reader (python3-meshio) of the same Gmsh files, its
errors, and Scene.load of a Gmsh scene (the finger of data/scenes): forward solve and a short
optimisation from Python, against the command-line tool."""

import os

import numpy as np
import pytest

import softhd

meshio = pytest.importorskip("meshio", reason="python3-meshio is not installed")


def mesh_path(source_dir, name):
    return os.path.join(source_dir, "tests", "data", "meshes", name)


def tet_volumes(points, tets):
    """|det(x1 - x0, x2 - x0, x3 - x0)| / 6 of each tetrahedron's corners."""
    p = points[tets[:, :4]]
    return np.abs(np.linalg.det(p[:, 1:] - p[:, :1])) / 6.0


def meshio_volume_cells(m, kind):
    """The body's cells of meshio's reading: all blocks of `kind` stacked."""
    return np.vstack([c.data for c in m.cells if c.type == kind])


@pytest.mark.parametrize("name, kind, cell_type", [
    ("cube_tet4_v41.msh", "tetra", "tet4"),
    ("cube_tet4_v22.msh", "tetra", "tet4"),
    ("cube_tet10_v41.msh", "tetra10", "tet10"),
    ("cube_tet10_v41_bin.msh", "tetra10", "tet10"),
])
def test_read_mesh_equals_meshio(source_dir, name, kind, cell_type):
    path = mesh_path(source_dir, name)
    mesh = softhd.read_mesh(path)
    ref = meshio.read(path)
    cells = meshio_volume_cells(ref, kind)
    used = np.unique(cells)  # softhd drops nodes no volume element uses
    assert mesh.cell_type == cell_type and mesh.dim == 3
    assert mesh.nodes.shape == (len(used), 3)
    assert mesh.elements.shape == cells.shape
    # The same elements on the same points (softhd keeps the file's node and element order;
    # meshio permutes some local orders to VTK's, hence the sorted rows).
    np.testing.assert_array_equal(mesh.nodes, ref.points[used])
    old_to_new = -np.ones(len(ref.points), dtype=np.int64)
    old_to_new[used] = np.arange(len(used))
    np.testing.assert_array_equal(np.sort(mesh.elements, axis=1),
                                  np.sort(old_to_new[cells], axis=1))
    # softhd's quadrature volume, meshio's corners' tetrahedra (straight-sided), the cube's 1.
    expected = tet_volumes(ref.points, cells).sum()
    assert expected == pytest.approx(1.0, rel=1e-12)
    assert mesh.volume == pytest.approx(expected, rel=1e-12)
    assert tet_volumes(mesh.nodes, mesh.elements).sum() == pytest.approx(expected, rel=1e-12)
    # Regions: the physical volumes by name, one per element, as meshio's gmsh:physical.
    assert mesh.region_names == ["body", "layer"]
    assert mesh.element_region.shape == (len(cells),)
    tags = np.concatenate([d for c, d in zip(ref.cells, ref.cell_data["gmsh:physical"])
                           if c.type == kind])
    names = {int(v[0]): k for k, v in ref.field_data.items() if v[1] == 3}
    assert [names[t] for t in tags] == [mesh.region_names[r] for r in mesh.element_region]
    # Boundary groups: the nodes of meshio's cells of each physical surface.
    assert set(mesh.boundary) == {"base", "tip"}
    for group in ("base", "tip"):
        tag = int(ref.field_data[group][0])
        faces = [c.data[d == tag] for c, d in zip(ref.cells, ref.cell_data["gmsh:physical"])
                 if c.type.startswith("triangle")]
        np.testing.assert_array_equal(mesh.boundary[group], np.unique(old_to_new[np.vstack(faces)]))
        np.testing.assert_allclose(mesh.nodes[mesh.boundary[group], 0],
                                   0.0 if group == "base" else 1.0, atol=1e-12)


def test_read_mesh_order_and_scale(source_dir):
    path = mesh_path(source_dir, "cube_tet4_v41.msh")
    p1 = softhd.read_mesh(path)
    p2 = softhd.read_mesh(path, order=2, scale=1e-3)
    assert p2.cell_type == "tet10" and p2.order == 2 and p2.elements.shape[1] == 10
    # The vertices are the first-order mesh's, scaled; the volume scales by 1e-9.
    np.testing.assert_allclose(p2.nodes[p2.vertex_nodes], 1e-3 * p1.nodes[p1.vertex_nodes],
                               rtol=1e-15)
    assert p2.volume == pytest.approx(1e-9 * p1.volume, rel=1e-12)
    # Order 1 on a second-order file keeps the corners only.
    q = softhd.read_mesh(mesh_path(source_dir, "cube_tet10_v41.msh"), order=1)
    assert q.cell_type == "tet4" and q.nodes.shape[0] == len(q.vertex_nodes)
    assert "tet4" in repr(q)


@pytest.mark.parametrize("name", ["cube_tet4_v41.msh", "cube_tet10_v41.msh"])
def test_boundary_triangles_enclose_the_volume(source_dir, name):
    """Mesh.boundary_triangles: outward triangles over boundary nodes; by the divergence
    theorem, sum over them of a.(b x c) / 6 is the mesh's volume (flat facets: exact)."""
    mesh = softhd.read_mesh(mesh_path(source_dir, name))
    tri = mesh.boundary_triangles
    assert tri.dtype == np.int64 and tri.shape[1] == 3 and len(tri) > 0
    x = mesh.nodes
    a, b, c = x[tri[:, 0]], x[tri[:, 1]], x[tri[:, 2]]
    assert np.einsum("ij,ij->", a, np.cross(b, c)) / 6 == pytest.approx(mesh.volume, rel=1e-12)
    # each edge of a closed surface is shared by two triangles, once in each direction
    e = np.vstack([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]])
    assert len(np.unique(e, axis=0)) == len(e)
    assert np.array_equal(np.unique(e, axis=0), np.unique(e[:, ::-1], axis=0))


def test_read_mesh_errors_name_the_file(source_dir, tmp_path):
    bad = tmp_path / "truncated.msh"
    text = open(mesh_path(source_dir, "cube_tet4_v41.msh")).read()
    bad.write_text(text[: len(text) // 2])
    with pytest.raises(softhd.FileError, match="truncated.msh"):
        softhd.read_mesh(bad)
    with pytest.raises(softhd.FileError, match="missing.msh"):
        softhd.read_mesh(tmp_path / "missing.msh")
    # Mixed cell types (triangles and quadrilaterals): readable by meshio, refused by softhd.
    with pytest.raises(softhd.FileError, match="plate_2d_v41.msh"):
        softhd.read_mesh(mesh_path(source_dir, "plate_2d_v41.msh"))
    for order in (0, 3, True, "2"):
        with pytest.raises(softhd.InvalidArgument, match="order"):
            softhd.read_mesh(mesh_path(source_dir, "cube_tet4_v41.msh"), order=order)
    for scale in (0.0, 1e-200, 1e300):
        with pytest.raises(softhd.InvalidArgument, match=r"scale must be in \[1e-12, 1e12\]"):
            softhd.read_mesh(mesh_path(source_dir, "cube_tet4_v41.msh"), scale=scale)


def test_a_file_mesh_above_max_memory_gib_is_refused(source_dir):
    scene = os.path.join(source_dir, "data", "scenes", "finger.json")
    with pytest.raises(softhd.ResourceError,
                       match=r"finger.msh: the mesh has \d+ nodes and \d+ elements: it needs about"):
        softhd.Scene.load(scene, max_memory_gib=1e-3)


@pytest.fixture(scope="module")
def finger(source_dir):
    return softhd.Scene.load(os.path.join(source_dir, "data", "scenes", "finger.json"))


def test_finger_scene_loads(finger, source_dir):
    mesh = finger.mesh
    assert finger.dim == 3 and finger.has_target
    assert mesh.cell_type == "tet10" and mesh.region_names == ["body", "layer"]
    assert set(np.unique(mesh.element_region)) == {0, 1}
    assert "base" in mesh.boundary and "cavity" in mesh.boundary
    np.testing.assert_array_equal(finger.nodes, mesh.nodes)
    assert finger.num_controls == len(mesh.vertex_nodes)  # vertex controls
    # The scene's mesh is read_mesh's of its file at its order.
    file_mesh = softhd.read_mesh(os.path.join(source_dir, "data", "meshes", "finger.msh"),
                                 order=2)
    np.testing.assert_array_equal(file_mesh.nodes, mesh.nodes)
    np.testing.assert_array_equal(file_mesh.elements, mesh.elements)
    assert file_mesh.volume == mesh.volume


def test_finger_forward_equals_the_command_line_tool(finger, source_dir, cli, tmp_path):
    probe = [60.0, 6.0, 11.5]  # the middle of the tip's top edge
    path = os.path.join(source_dir, "data", "scenes", "finger.json")
    j = cli("forward", path, "--control-uniform", -2, "--probe",
            ",".join(map(str, probe)), "--threads", 1, "--out", tmp_path / "out")
    f = finger.forward(-2.0, probes=[probe], threads=1)
    assert f.converged and j["converged"]
    assert f.displacements.shape == finger.nodes.shape
    assert f.probes[0, 2] > 0.0  # contracting fibres over the stiff layer bend it up
    assert f.energy == pytest.approx(j["energy"], rel=1e-14)
    np.testing.assert_allclose(f.probes[0], j["probes"][0]["u"], rtol=1e-14, atol=1e-300)


def test_finger_optimises_from_python(finger):
    r = softhd.optimise(finger, max_iter=2, threads=1)
    # The default levels on a Gmsh mesh of order 2: its P1 level first (at most max_iter
    # iterations), then the mesh itself.
    assert r.iterations == 2 and [it.level for it in r.history] == [1, 1, 0, 0]
    assert r.J_final < r.rho_start
    assert r.displacements.shape == finger.nodes.shape
    assert r.floor_matched is not None  # the target was solved on a known map
