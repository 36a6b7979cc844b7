#pragma once
/// \file geometry.hpp
/// Reference-configuration data at the quadrature points of a mesh, computed once:
/// shape values, gradients dN/dX and weights w_q det(dX/dxi). Also the lumped nodal
/// volumes V_i = ∫ N_i dX (docs/formulation.md §1.2).

#include <Eigen/Core>

#include "softhd/fe/mesh.hpp"

namespace softhd::fe {

/// Full Gauss quadrature ((p+1)^dim points per element) on the reference body.
class ReferenceGeometry {
 public:
  /// Throws InvalidArgument if an element is inverted (det(dX/dxi) <= 0).
  explicit ReferenceGeometry(const Mesh& mesh);

  /// The dimension d (2 or 3).
  int dim() const { return dim_; }
  /// Nodes per element, (p+1)^d.
  int nodes_per_element() const { return nen_; }
  /// Quadrature points per element, (p+1)^d.
  int points_per_element() const { return nq_; }
  /// The number of elements E.
  Eigen::Index num_elements() const { return weights_.rows(); }
  /// Shape values: nq by nen (the same on every element).
  const Eigen::MatrixXd& shape_values() const { return N_; }
  /// Reference coordinates of the quadrature points: nq by dim.
  const Eigen::MatrixXd& reference_points() const { return xi_; }
  /// dN_a/dX at point q of element e: column (e nq + q) nen + a of a dim-row matrix.
  Eigen::Ref<const Eigen::MatrixXd> gradients(Eigen::Index e, int q) const {
    return dNdX_.middleCols((e * nq_ + q) * nen_, nen_);
  }
  /// w_q det J0 at point q of element e (E by nq).
  const Eigen::MatrixXd& weights() const { return weights_; }

 private:
  int dim_ = 3, nen_ = 0, nq_ = 0;
  Eigen::MatrixXd N_, xi_, dNdX_, weights_;
};

/// Lumped nodal volumes V_i = ∫ N_i dX (areas in 2D); they sum to |Ω₀| and are positive
/// for tensor-product Q1 and Q2 elements (1-D weights 1/3, 4/3, 1/3 per unit cell for Q2).
Eigen::VectorXd lumped_volumes(const Mesh& mesh, const ReferenceGeometry& geometry);

/// Reference positions of all quadrature points, (E nq) by dim, element-major.
Eigen::MatrixXd quadrature_points(const Mesh& mesh, const ReferenceGeometry& geometry);

}  // namespace softhd::fe
