#include "softhd/fe/interpolation.hpp"

#include <cmath>
#include <sstream>

#include "softhd/error.hpp"

namespace softhd::fe {

namespace {

// f(X_p) = Σ_a N_a(ξ_p) f(support(e, a)) with the shape functions of `cell`, summed over a
// in local order from zero, each term fused (s = fma(N_a, f_a, s)) or not: as the loops this
// replaced were compiled under -march=native (the nodal ones fused, the vertex-control one
// not), so box results stay bitwise equal. This file is compiled with -ffp-contract=off
// (lib/CMakeLists.txt) so that the compiler fuses nothing else.
Eigen::MatrixXd interpolate(const Mesh& mesh, const PointLocator& locator, CellType cell,
                            const Connectivity& support, const Eigen::MatrixXd& field,
                            const Eigen::MatrixXd& points, bool fused, std::vector<int>* outside) {
  const ReferenceElement& r = reference_element(cell);
  if (points.cols() != mesh.dim)
    throw InvalidArgument("interpolation: points must have " + std::to_string(mesh.dim) +
                          " columns, got " + std::to_string(points.cols()));
  Eigen::MatrixXd values = Eigen::MatrixXd::Zero(points.rows(), field.cols());
  Eigen::VectorXd xi, N(r.nodes), dN(r.nodes * r.dim);
  if (outside) outside->clear();
  for (Eigen::Index p = 0; p < points.rows(); ++p) {
    const int e = locator.locate(points.row(p).transpose(), &xi);
    if (e < 0) {
      if (outside) {
        outside->push_back(static_cast<int>(p));
        continue;
      }
      std::ostringstream os;
      os << "interpolation: the point (" << points.row(p) << ") is outside the body";
      throw InvalidArgument(os.str());
    }
    shape_functions(cell, xi.data(), N.data(), dN.data());
    for (Eigen::Index k = 0; k < field.cols(); ++k) {
      double v = 0.0;
      for (int a = 0; a < r.nodes; ++a) {
        const double f = field(support(e, a), k);
        v = fused ? std::fma(N[a], f, v) : v + N[a] * f;
      }
      values(p, k) = v;
    }
  }
  return values;
}

}  // namespace

Eigen::MatrixXd interpolate_nodal(const Mesh& mesh, const PointLocator& locator,
                                  const Eigen::MatrixXd& nodal_field, const Eigen::MatrixXd& points,
                                  std::vector<int>* outside) {
  if (nodal_field.rows() != mesh.num_nodes())
    throw InvalidArgument("interpolation: the nodal field has " +
                          std::to_string(nodal_field.rows()) + " rows for " +
                          std::to_string(mesh.num_nodes()) + " nodes");
  return interpolate(mesh, locator, mesh.cell, mesh.elements, nodal_field, points, true, outside);
}

Eigen::MatrixXd interpolate_vertex(const Mesh& mesh, const PointLocator& locator,
                                   const Eigen::MatrixXd& vertex_field,
                                   const Eigen::MatrixXd& points, std::vector<int>* outside) {
  if (vertex_field.rows() != mesh.num_vertices())
    throw InvalidArgument("interpolation: the vertex field has " +
                          std::to_string(vertex_field.rows()) + " rows for " +
                          std::to_string(mesh.num_vertices()) + " vertices");
  return interpolate(mesh, locator, reference_element(mesh.cell).linear, mesh.element_vertices,
                     vertex_field, points, false, outside);
}

bool same_cells(const Mesh& a, const Mesh& b) {
  if (a.dim != b.dim || a.num_elements() != b.num_elements() ||
      a.num_vertices() != b.num_vertices() ||
      reference_element(a.cell).linear != reference_element(b.cell).linear ||
      a.element_vertices.cols() != b.element_vertices.cols() ||
      a.element_vertices != b.element_vertices)
    return false;
  for (Eigen::Index k = 0; k < a.num_vertices(); ++k)
    if (a.nodes.row(a.vertex_nodes[k]) != b.nodes.row(b.vertex_nodes[k])) return false;
  return true;
}

Eigen::MatrixXd transfer_nodal(const Mesh& from, const Eigen::MatrixXd& field, const Mesh& to) {
  if (!same_cells(from, to))
    throw InvalidArgument("transfer_nodal: the two meshes are not the same cells");
  if (field.rows() != from.num_nodes())
    throw InvalidArgument("transfer_nodal: the nodal field has " + std::to_string(field.rows()) +
                          " rows for " + std::to_string(from.num_nodes()) + " nodes");
  const ReferenceElement& rf = reference_element(from.cell);
  const ReferenceElement& rt = reference_element(to.cell);
  // N_b(ξ_a) for every local node a of `to`: the same reference cell, corners in the same
  // order, so ξ_a is the same point of element e in both meshes.
  Eigen::MatrixXd T(rt.nodes, rf.nodes);
  Eigen::VectorXd N(rf.nodes), dN(rf.nodes * rf.dim);
  for (int a = 0; a < rt.nodes; ++a) {
    const Eigen::VectorXd xi = rt.node_coordinates.row(a).transpose();
    shape_functions(from.cell, xi.data(), N.data(), dN.data());
    T.row(a) = N.transpose();
  }
  Eigen::MatrixXd values(to.num_nodes(), field.cols());
  Eigen::MatrixXd fe(rf.nodes, field.cols());
  for (Eigen::Index e = 0; e < to.num_elements(); ++e) {
    for (int b = 0; b < rf.nodes; ++b) fe.row(b) = field.row(from.elements(e, b));
    const Eigen::MatrixXd ve = T * fe;  // f(ξ_a) = Σ_b N_b(ξ_a) f_b
    for (int a = 0; a < rt.nodes; ++a) values.row(to.elements(e, a)) = ve.row(a);
  }
  return values;
}

Eigen::VectorXi locate_points(const PointLocator& locator, const Eigen::MatrixXd& points) {
  Eigen::VectorXi e(points.rows());
  Eigen::VectorXd xi;
  for (Eigen::Index p = 0; p < points.rows(); ++p)
    e[p] = locator.locate(points.row(p).transpose(), &xi);
  return e;
}

}  // namespace softhd::fe
