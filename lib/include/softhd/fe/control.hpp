#pragma once
/// \file control.hpp
/// Discretisations of the active tension m(X) (docs/formulation.md §4.1): nodal values on the mesh
/// vertices interpolated with Q1 (bi/trilinear) shape functions on every element (also on
/// Q2 meshes), so bounds hold pointwise, or one value per element.

#include <Eigen/Core>
#include <string>

#include "softhd/fe/geometry.hpp"
#include "softhd/fe/mesh.hpp"

namespace softhd::fe {

/// Where the control values live: mesh vertices (Q1 interpolation) or elements (constant).
enum class ControlKind { kVertex, kElement };

/// Parses "vertex" / "element"; throws InvalidArgument otherwise.
ControlKind parse_control_kind(const std::string& name);

/// Reference positions of the controls of `kind` on `mesh` (its vertices, or its element
/// centres as the mean of all element nodes): controls by dim. Needs no quadrature data.
Eigen::MatrixXd control_positions(const Mesh& mesh, ControlKind kind);

/// The linear map m ↦ m(X_q) at the quadrature points, m(X_q) = Σ_k M_k(X_q) m_k.
class ControlSpace {
 public:
  /// The control space of `kind` on `mesh`, with `geometry` its quadrature data.
  ControlSpace(const Mesh& mesh, const ReferenceGeometry& geometry, ControlKind kind);

  /// Vertex or element controls.
  ControlKind kind() const { return kind_; }
  /// Number of control values: vertices or elements.
  Eigen::Index size() const { return size_; }
  /// Control values at the quadrature points, E by nq.
  Eigen::MatrixXd to_quadrature(const Eigen::VectorXd& m) const;
  /// The transpose map: g_k = Σ_e Σ_q M_k(X_q) v(e, q) (v is E by nq).
  Eigen::VectorXd from_quadrature(const Eigen::MatrixXd& v) const;
  /// Reference positions of the controls (vertices, or element centres): size by dim.
  Eigen::MatrixXd positions(const Mesh& mesh) const { return control_positions(mesh, kind_); }
  /// (M/2) ∫ m² + (ε/2) ∫ |∇m|² and its gradient w.r.t. m (docs/formulation.md §4.2); `gradient`
  /// may be null.
  double regularisation(const Eigen::VectorXd& m, double M, double eps,
                        Eigen::VectorXd* gradient) const;

 private:
  ControlKind kind_;
  Eigen::Index size_ = 0;
  Connectivity support_;             ///< E by (2^dim or 1): control ids per element
  Eigen::MatrixXd M_;                ///< nq by (2^dim or 1): shape values at the quadrature points
  std::vector<Eigen::MatrixXd> dM_;  ///< per element q-major: dim by (nq · ncols) gradients
  Eigen::MatrixXd weights_;          ///< E by nq
};

/// The control at every node of `mesh` (e.g. for VTU point data): vertex controls interpolated
/// with their Q1 shape functions (Q2 mid-nodes included); zeros for element controls, which
/// are cell data.
Eigen::VectorXd control_at_nodes(const Mesh& mesh, const ControlSpace& space,
                                 const Eigen::VectorXd& m);

}  // namespace softhd::fe
