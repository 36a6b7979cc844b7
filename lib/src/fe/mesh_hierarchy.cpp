#include "softhd/fe/mesh_hierarchy.hpp"

#include <memory>
#include <sstream>
#include <string>

#include "softhd/error.hpp"
#include "softhd/fe/interpolation.hpp"

namespace softhd::fe {

namespace {

// The box with half the cells along every even axis; with Halving::rounded, a box with no
// even axis has every axis of at least 4 cells halved rounding up, n -> (n + 1) / 2 (a coarser
// box whose grid is not nested in the finer one: the levels exchange fields by interpolation
// at points, prolongate and control_at, which need no nesting).
Body halved(const Body& body, Halving halving) {
  Body coarse = body;
  bool halved = false;
  for (Eigen::Index k = 0; k < coarse.cells.size(); ++k) {
    if (coarse.cells[k] % 2 == 0) {
      coarse.cells[k] /= 2;
      halved = true;
    }
  }
  if (!halved && halving == Halving::rounded) {
    for (Eigen::Index k = 0; k < coarse.cells.size(); ++k) {
      if (coarse.cells[k] >= 4) {
        coarse.cells[k] = (coarse.cells[k] + 1) / 2;
        halved = true;
      }
    }
  }
  if (!halved) {
    std::ostringstream os;
    os << "no cell count of (" << body.cells.transpose() << ") can be halved";
    if (halving == Halving::rounded) os << " (none is even or at least 4)";
    throw InvalidArgument(os.str());
  }
  return coarse;
}

// A file mesh of order 2 as P1/Q1 on its vertices: the mesh's vertex nodes, fibres per node
// restricted to them (per element and uniform ones as they are), the linear cell's default
// quadrature; materials by region and constraints by name carry over.
Body order_dropped(const Body& body) {
  if (body.order != 2)
    throw InvalidArgument("the mesh from " + body.mesh_file +
                          " is of order 1 at this level (a first-order file, or an order-2 "
                          "file's vertices): a file mesh has no grid to halve, so its one "
                          "coarser level is an order-2 mesh's vertices (P1/Q1 on its cells)");
  const Mesh& fine = *body.file_mesh;
  Body coarse = body;
  coarse.file_mesh = std::make_shared<const Mesh>(linear_mesh(fine));
  coarse.order = 1;
  coarse.gmsh_options.order = 1;
  coarse.quadrature_degree = 0;
  if (body.fiber_field.kind == FiberField::Kind::kNode) {
    Eigen::Matrix3Xd a(3, fine.num_vertices());
    for (Eigen::Index k = 0; k < a.cols(); ++k)
      a.col(k) = body.fiber_field.values.col(fine.vertex_nodes[k]);
    coarse.fiber_field.values = a;
  }
  return coarse;
}

}  // namespace

std::string describe_level(const Body& body) {
  std::ostringstream os;
  if (body.is_box()) {
    os << "cells " << body.cells.transpose();
    return os.str();
  }
  const Mesh& mesh = *body.file_mesh;
  const ReferenceElement& ref = reference_element(mesh.cell);
  if (body.gmsh_options.order == 1)  // the vertices only (order_dropped, or "order": 1)
    os << (ref.simplex ? "P1" : "Q1") << " on the vertices: ";
  os << to_string(mesh.cell) << ", " << mesh.num_nodes() << " nodes";
  return os.str();
}

Body coarsened(const Body& body, Halving halving) {
  // The one choice of the coarse level: halving needs a structured grid, which only a box
  // has; a file mesh drops its order on the same cells instead.
  return body.is_box() ? halved(body, halving) : order_dropped(body);
}

int coarser_levels(const Body& body, Halving halving, int min_elements) {
  // A file mesh: its P1/Q1 level (order_dropped: as many elements), which has no coarser one;
  // answered without building it.
  if (!body.is_box())
    return body.order == 2 && body.file_mesh->num_elements() >= min_elements ? 1 : 0;
  int levels = 0;
  Body s = body;
  while (true) {
    Body c;
    try {
      c = halved(s, halving);  // a box's cells only: throws where no axis can be halved
    } catch (const InvalidArgument&) {
      return levels;
    }
    if (c.cells.prod() < min_elements) return levels;
    ++levels;
    s = std::move(c);
  }
}

MeshHierarchy::MeshHierarchy(const Body& body, Halving halving, int coarser) : halving_(halving) {
  if (coarser < 0) throw InvalidArgument("mesh hierarchy: coarser levels must be >= 0");
  levels_.reserve(static_cast<size_t>(coarser) + 1);
  levels_.push_back(body);
  for (int l = 0; l < coarser; ++l) {
    try {
      levels_.push_back(coarsened(levels_.back(), halving));
    } catch (const InvalidArgument& e) {  // say how many levels there are, and why
      throw InvalidArgument(std::to_string(coarser) +
                            " coarser levels asked for, but the body has " + std::to_string(l) +
                            " (" + e.what() + ")");
    }
  }
}

Eigen::MatrixXd quadrature_positions(const Mesh& mesh, const ReferenceGeometry& geometry) {
  const int nq = geometry.points_per_element(), nen = geometry.nodes_per_element();
  const Eigen::MatrixXd& N = geometry.shape_values();  // nq by nen
  Eigen::MatrixXd X(mesh.num_elements() * nq, mesh.dim), Xe(nen, mesh.dim);
  for (Eigen::Index e = 0; e < mesh.num_elements(); ++e) {
    for (int a = 0; a < nen; ++a) Xe.row(a) = mesh.nodes.row(mesh.elements(e, a));
    X.middleRows(e * nq, nq) = N * Xe;  // X_q = Σ_a N_a(ξ_q) X_a
  }
  return X;
}

Eigen::MatrixXd control_on_quadrature(const Assembler& assembler, const Mesh& mesh,
                                      ControlKind kind, const Eigen::VectorXd& m,
                                      const std::vector<int>& regions) {
  // The same cells and vertices (and regions): m(ξ_q) = Σ_k M_k(ξ_q) m_k in each element of
  // the control's regions, no point search.
  if (same_cells(assembler.mesh(), mesh))
    return ControlSpace(assembler.mesh(), assembler.geometry(), kind, regions).to_quadrature(m);
  const Eigen::VectorXd v = control_at(
      mesh, kind, m, quadrature_positions(assembler.mesh(), assembler.geometry()), regions);
  const int nq = assembler.geometry().points_per_element();
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      v.data(), assembler.mesh().num_elements(), nq);
}

Eigen::VectorXd prolongate(const Mesh& coarse, const Eigen::VectorXd& u_coarse, const Mesh& fine) {
  if (coarse.dim != fine.dim || u_coarse.size() != coarse.num_nodes() * coarse.dim)
    throw InvalidArgument("prolongate: the coarse field does not match its mesh");
  const int d = fine.dim;
  const Eigen::MatrixXd U = u_coarse.reshaped(d, coarse.num_nodes()).transpose();
  // The same cells: u(ξ_a) = Σ_b N_b(ξ_a) u_b element by element (p-sequencing).
  if (same_cells(coarse, fine)) return transfer_nodal(coarse, U, fine).transpose().reshaped();
  // u(X_n) = Σ_a N_a(ξ) u_a in the coarse element containing the fine node X_n
  std::vector<int> outside;
  const Eigen::MatrixXd u =
      interpolate_nodal(coarse, PointLocator(coarse), U, fine.nodes, &outside);
  if (!outside.empty())
    throw InvalidArgument("prolongate: fine node " + std::to_string(outside[0]) + " is outside");
  return u.transpose().reshaped();
}

Eigen::VectorXd prolongate_control(const Mesh& coarse, const ControlSpace& coarse_control,
                                   const Eigen::VectorXd& m, const Mesh& fine,
                                   const ControlSpace& fine_control,
                                   const std::vector<int>& regions) {
  // The same cells (a P1/Q1 level): the same vertices and elements carry the same controls.
  if (same_cells(coarse, fine) && coarse_control.kind() == fine_control.kind()) return m;
  return control_at(coarse, coarse_control.kind(), m, fine_control.positions(fine), regions);
}

}  // namespace softhd::fe
