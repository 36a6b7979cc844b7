#pragma once
/// \file geometry.hpp
/// Reference-configuration data at the quadrature points of a mesh, computed once:
/// shape values, gradients dN/dX and weights w_q det(dX/dxi). Also the lumped nodal
/// volumes V_i = ∫ N_i dX (docs/formulation.md §1.2).

#include <Eigen/Core>
#include <vector>

#include "softhd/fe/mesh.hpp"

namespace softhd::fe {

/// Whether ReferenceGeometry keeps dN/dX at every quadrature point.
enum class GradientStorage {
  kStored,    ///< computed once, dim·nen·nq doubles per element (17.5 KB for a Q2 hexahedron)
  kOnDemand,  ///< not kept: point_gradients() recomputes them from the element's nodes
};

/// Quadrature on the reference body, by the reference-element table (fe/reference_element.hpp):
/// by default reference_element(cell).default_quadrature_degree, for quadrilaterals and
/// hexahedra the full Gauss rule with (p+1)^d points.
class ReferenceGeometry {
 public:
  /// The most nodes per element point_gradients() handles (a Q2 hexahedron; a P2
  /// tetrahedron has 10).
  static constexpr int kMaxNodes = 27;

  /// `quadrature_degree` 0 takes the cell type's default. Throws InvalidArgument if an
  /// element is inverted (det(dX/dxi) <= 0 at a quadrature point), if the degree is out of
  /// the table's range, or with kOnDemand if an element has more than kMaxNodes nodes.
  explicit ReferenceGeometry(const Mesh& mesh, GradientStorage storage = GradientStorage::kStored,
                             int quadrature_degree = 0);

  /// The dimension d (2 or 3).
  int dim() const { return dim_; }
  /// Nodes per element.
  int nodes_per_element() const { return nen_; }
  /// Quadrature points per element ((p+1)^d for the default rule on quadrilaterals and
  /// hexahedra).
  int points_per_element() const { return nq_; }
  /// The number of elements E.
  Eigen::Index num_elements() const { return weights_.rows(); }
  /// Shape values: nq by nen (the same on every element).
  const Eigen::MatrixXd& shape_values() const { return N_; }
  /// Reference coordinates of the quadrature points: nq by dim.
  const Eigen::MatrixXd& reference_points() const { return xi_; }
  /// True if gradients() may be called (GradientStorage::kStored).
  bool stores_gradients() const { return stored_; }
  /// dN_a/dX at point q of element e: column (e nq + q) nen + a of a dim-row matrix.
  /// Only when stores_gradients().
  Eigen::Ref<const Eigen::MatrixXd> gradients(Eigen::Index e, int q) const {
    return dNdX_.middleCols((e * nq_ + q) * nen_, nen_);
  }
  /// dN_a/dX at point q of element e of `mesh` (the mesh this was built from), computed
  /// from its nodes into G (dim by nen, column-major: G[a dim + J] = dN_a/dX_J). Equal to
  /// gradients(e, q) up to rounding (3 by 3 inverse by cofactors); no allocation.
  void point_gradients(const Mesh& mesh, Eigen::Index e, int q, double* G) const;
  /// w_q det J0 at point q of element e (E by nq).
  const Eigen::MatrixXd& weights() const { return weights_; }

 private:
  int dim_ = 3, nen_ = 0, nq_ = 0;
  bool stored_ = true;
  Eigen::MatrixXd N_, xi_, dNdX_, weights_;
  std::vector<Eigen::MatrixXd> dN_ref_;  ///< per point: nen by dim, dN_a/dξ
};

/// How element volumes are lumped onto nodes (docs/formulation.md §7). The row sum
/// w_a = ∫ N_a dX is positive on every Q1, Q2 (tensor-product) and P1 element, but on P2
/// simplices it is −V/20 (tetrahedra) or 0 (triangles) at the vertices; those take HRZ
/// lumping w_a = V_e M_aa / Σ_b M_bb (M_ab = ∫ N_a N_b dX), which is positive and sums to
/// V_e (affine P2 tetrahedron: V/36 at vertices, 4V/27 at edges; triangle: A/19, 16A/57).
enum class Lumping { kRowSum, kHRZ };

/// The lumping of a cell type: HRZ for P2 simplices, the row sum otherwise.
Lumping lumping(CellType type);

/// The lumped weights w (nen) of element e whose volume is Σ_q c_q, c_q = w_q det J0 J_q
/// (J = null: J_q = 1, the reference volumes), and if dw_dJ is not null their derivatives
/// dw_dJ[a + nen q] = ∂w_a/∂J_q:
///   row sum: w_a = Σ_q N_a(ξ_q) c_q,
///   HRZ:     w_a = V m_a / S, m_a = Σ_q N_a(ξ_q)² c_q, V = Σ_q c_q, S = Σ_a m_a.
/// No allocation.
void lumped_element_weights(const ReferenceGeometry& geometry, Lumping lumping, Eigen::Index e,
                            const double* J, double* w, double* dw_dJ);

/// Lumped nodal volumes V_i = Σ_e w_a(e) (areas in 2D) by lumping(mesh.cell): positive,
/// summing to |Ω₀|; the row sum ∫ N_i dX where it is positive (1-D weights 1/3, 4/3, 1/3
/// per unit cell for Q2).
Eigen::VectorXd lumped_volumes(const Mesh& mesh, const ReferenceGeometry& geometry);

/// Reference positions of all quadrature points, (E nq) by dim, element-major.
Eigen::MatrixXd quadrature_points(const Mesh& mesh, const ReferenceGeometry& geometry);

}  // namespace softhd::fe
