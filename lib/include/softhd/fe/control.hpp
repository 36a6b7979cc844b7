#pragma once
/// \file control.hpp
/// Discretisations of the active tension m(X) (docs/formulation.md §4.1): nodal values on the mesh
/// vertices interpolated with Q1 (bi/trilinear) shape functions on every element (also on
/// Q2 meshes), so bounds hold pointwise, or one value per element. A control may act on some
/// regions of the mesh only (scene key control.region): m = 0 in the other elements, and the
/// controls that touch none of its elements are held at 0.

#include <Eigen/Core>
#include <string>
#include <vector>

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

/// True if element e of `mesh` lies in one of `regions` (ids into mesh.region_names); an empty
/// list is the whole body.
bool in_regions(const Mesh& mesh, const std::vector<int>& regions, Eigen::Index e);

/// Per control of `kind` on `mesh`: 1 if it acts on an element of `regions` (a vertex of one,
/// or one; all with no regions), else 0.
std::vector<char> acting_controls(const Mesh& mesh, ControlKind kind,
                                  const std::vector<int>& regions);

/// The control vector equal to `value` where a control acts (acting_controls) and 0
/// elsewhere: the bounds and the start of a run.
Eigen::VectorXd constant_control(const Mesh& mesh, ControlKind kind,
                                 const std::vector<int>& regions, double value);

/// The linear map m ↦ m(X_q) at the quadrature points, m(X_q) = Σ_k M_k(X_q) m_k in the
/// elements of the control's regions, 0 in the others.
class ControlSpace {
 public:
  /// The control space of `kind` on `mesh`, with `geometry` its quadrature data, acting on the
  /// elements of `regions` (ids into mesh.region_names; empty: the whole body).
  ControlSpace(const Mesh& mesh, const ReferenceGeometry& geometry, ControlKind kind,
               std::vector<int> regions = {});

  /// Vertex or element controls.
  ControlKind kind() const { return kind_; }
  /// The regions the control acts on (empty: the whole body).
  const std::vector<int>& regions() const { return regions_; }
  /// constant_control(value) of this space: `value` where a control acts, 0 elsewhere.
  Eigen::VectorXd constant(double value) const;
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
  std::vector<int> regions_;
  std::vector<char> acts_in_;  ///< per element: 1 in the control's regions
  std::vector<char> active_;   ///< per control: 1 if it touches an element of the regions
  Eigen::Index size_ = 0;
  Connectivity support_;             ///< E by (2^dim or 1): control ids per element
  Eigen::MatrixXd M_;                ///< nq by (2^dim or 1): shape values at the quadrature points
  std::vector<Eigen::MatrixXd> dM_;  ///< per element q-major: dim by (nq · ncols) gradients
  Eigen::MatrixXd weights_;          ///< E by nq
};

/// The control at every node of `mesh` (e.g. for VTU point data): vertex controls interpolated
/// with their Q1 shape functions (Q2 mid-nodes included), 0 at nodes of no element of the
/// control's regions; zeros for element controls, which are cell data.
Eigen::VectorXd control_at_nodes(const Mesh& mesh, const ControlSpace& space,
                                 const Eigen::VectorXd& m);

/// Values at the reference points X (rows) of the control field m of `kind` on `mesh`:
/// Q1 interpolation of the vertex values, or the value of the containing element; 0 in the
/// elements outside `regions` (empty: the whole body). Throws InvalidArgument naming the
/// first point outside the body.
Eigen::VectorXd control_at(const Mesh& mesh, ControlKind kind, const Eigen::VectorXd& m,
                           const Eigen::MatrixXd& X, const std::vector<int>& regions = {});

}  // namespace softhd::fe
