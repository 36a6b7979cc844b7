// softhd._core.Mesh and read_mesh: a body's mesh (fe::Mesh) as NumPy arrays, read from a Gmsh
// file by fe::read_gmsh_mesh or taken from a loaded scene.

#include <pybind11/eigen.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "mesh.hpp"
#include "scene.hpp"
#include "softhd/fe/boundary.hpp"
#include "softhd/fe/gmsh_mesh.hpp"

namespace softhd::python {

namespace {

/// A new C-order int64 array with the entries of an integer matrix (any storage order).
template <class Matrix>
py::array_t<std::int64_t> int_rows(const Matrix& m) {
  py::array_t<std::int64_t> out({m.rows(), m.cols()});
  auto view = out.mutable_unchecked<2>();
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j) view(i, j) = m(i, j);
  return out;
}

py::array_t<std::int64_t> int_vector(const Eigen::VectorXi& v) {
  py::array_t<std::int64_t> out(v.size());
  for (Eigen::Index i = 0; i < v.size(); ++i) out.mutable_at(i) = v[i];
  return out;
}

// The boundary triangles over the mesh's node ids (fe::boundary_facets, outward).
py::array_t<std::int64_t> boundary_triangles(const PyMesh& s) {
  const fe::BoundaryFacets b = fe::boundary_facets(s.mesh);
  py::array_t<std::int64_t> out({b.triangles.rows(), Eigen::Index{3}});
  auto view = out.mutable_unchecked<2>();
  for (Eigen::Index t = 0; t < b.triangles.rows(); ++t)
    for (int c = 0; c < 3; ++c) view(t, c) = b.nodes[static_cast<size_t>(b.triangles(t, c))];
  return out;
}

PyMesh read(const std::filesystem::path& path, int order, double scale) {
  fe::GmshMeshOptions options;
  options.order = order;
  options.scale = scale;
  py::gil_scoped_release release;
  PyMesh m;
  m.mesh = fe::read_gmsh_mesh(path.string(), options, &m.volume);
  return m;
}

}  // namespace

PyMesh mesh_of(const fe::Assembler& assembler) {
  PyMesh m;
  m.mesh = assembler.mesh();
  m.volume = assembler.geometry().weights().sum();
  return m;
}

void bind_mesh(py::module_& m) {
  py::class_<PyMesh>(m, "Mesh",
                     "A body's mesh: one cell type, nodes, elements, regions and named boundary "
                     "node sets (the arrays are copies).")
      .def_property_readonly(
          "dim", [](const PyMesh& s) { return s.mesh.dim; }, "2 or 3")
      .def_property_readonly(
          "order", [](const PyMesh& s) { return s.mesh.order; }, "1 (P1/Q1) or 2 (P2/Q2)")
      .def_property_readonly(
          "cell_type", [](const PyMesh& s) { return fe::to_string(s.mesh.cell); },
          "\"tet4\", \"tet10\", \"hex8\", \"hex27\", \"tri3\", \"tri6\", \"quad4\" or \"quad9\"")
      .def_property_readonly(
          "nodes", [](const PyMesh& s) { return to_numpy(s.mesh.nodes); },
          "(N, dim) float64 reference coordinates (scaled by `scale`)")
      .def_property_readonly(
          "elements", [](const PyMesh& s) { return int_rows(s.mesh.elements); },
          "(E, nodes per element) int64 node ids in softhd's local order: as Gmsh's for "
          "triangles and tetrahedra, tensor-product (a = i + (p+1)(j + (p+1)k)) for "
          "quadrilaterals and hexahedra")
      .def_property_readonly(
          "vertex_nodes", [](const PyMesh& s) { return int_vector(s.mesh.vertex_nodes); },
          "(V,) int64 node id of each vertex (element corner; the support of vertex controls)")
      .def_property_readonly(
          "element_vertices", [](const PyMesh& s) { return int_rows(s.mesh.element_vertices); },
          "(E, corners) int64 vertex ids of each element's corners")
      .def_property_readonly(
          "region_names", [](const PyMesh& s) { return s.mesh.region_names; },
          "names of the regions: the file's physical volumes (surfaces in 2D), [\"body\"] for a "
          "box")
      .def_property_readonly(
          "element_region", [](const PyMesh& s) { return int_vector(s.mesh.element_region); },
          "(E,) int64 region of each element, an index into region_names")
      .def_property_readonly(
          "boundary",
          [](const PyMesh& s) {
            py::dict out;
            for (const auto& [name, nodes] : s.mesh.boundary_nodes) {
              py::array_t<std::int64_t> ids(static_cast<py::ssize_t>(nodes.size()));
              for (size_t i = 0; i < nodes.size(); ++i)
                ids.mutable_at(static_cast<py::ssize_t>(i)) = nodes[i];
              out[py::str(name)] = ids;
            }
            return out;
          },
          "dict: boundary name -> sorted int64 node ids (the file's physical groups one "
          "dimension below the body's; a box's faces x0 .. z1)")
      .def_property_readonly("boundary_triangles", &boundary_triangles,
                             "(T, 3) int64 node ids of the boundary surface's triangles, "
                             "outward (3D; each facet cut into flat triangles through its "
                             "nodes, docs/formulation.md §8.6)")
      .def_property_readonly(
          "volume", [](const PyMesh& s) { return s.volume; },
          "|Omega_0| by softhd's quadrature (sum of w_q det J0; area in 2D)")
      .def("__repr__", [](const PyMesh& s) {
        return "Mesh(" + fe::to_string(s.mesh.cell) + ", " + std::to_string(s.mesh.num_nodes()) +
               " nodes, " + std::to_string(s.mesh.num_elements()) + " elements, " +
               std::to_string(s.mesh.region_names.size()) + " regions)";
      });
  m.def("read_mesh", &read, py::arg("path"), py::arg("order") = 0, py::arg("scale") = 1.0,
        "The mesh of a Gmsh file (MSH 4.1 ASCII or binary, MSH 2.2 ASCII) as a scene's "
        "mesh.type \"gmsh\" reads it. order: 0 (the file's), 1 (vertices only) or 2 "
        "(straight-sided midside nodes added to a first-order file); scale multiplies the "
        "coordinates. Raises FileError naming the file for a file softhd cannot solve on, "
        "InvalidArgument for a bad order or scale.");
}

}  // namespace softhd::python
