#pragma once
/// \file targets.hpp
/// Targets with a known map T (docs/formulation.md §5.2): the bending scene's circular arc,
/// analytic at any resolution, and a manufactured state (the torsion target: the deformed nodes of
/// a state solved on a finer mesh, interpolated by that mesh's shape functions). A known map gives
/// the matched floor ρ̃(T(Ω₀), Ω_d) and the true shape error |x_i − T(X_i)|.

#include <Eigen/Core>

#include "softhd/fe/locator.hpp"
#include "softhd/fe/mesh.hpp"
#include "softhd/point_cloud.hpp"

namespace softhd {

/// The plate origin + [0, length] × [0, width] × [0, thickness], clamped at its face
/// X1 = origin1, bent about the X2 axis through the total angle θ, curling towards +X3
/// (docs/formulation.md §5.2). With P = X − origin, R = length/θ and z = P3 − thickness/2:
///
///     T(X) = origin + ((R − z) sin(P1/R), P2, thickness/2 + R − (R − z) cos(P1/R)),
///     det ∇T = 1 − z/R.
///
/// T is the identity on the clamped face and preserves the mid-surface's length.
struct ArcMap {
  double length = 10.0;              ///< L, along X1 (the clamp is at X1 = 0)
  double thickness = 0.1;            ///< t, along X3
  double angle = 3.141592653589793;  ///< θ in (0, 2π]
  /// The plate's lower corner (a scene's mesh.lower): T commutes with translations.
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();

  /// Throws InvalidArgument for a non-positive length or thickness, θ outside
  /// (0, 2π], or R ≤ thickness/2 (the inner surface would fold).
  void validate() const;
  /// T(X).
  Eigen::Vector3d operator()(const Eigen::Vector3d& X) const;
  /// det ∇T(X) = 1 − z/R.
  double jacobian(const Eigen::Vector3d& X) const;
  /// The cloud mapped by T, volumes multiplied by det ∇T (exact for a cell-centred
  /// cloud to second order in the cell size; the mapped volumes sum to ∫ det ∇T).
  PointCloud apply(const PointCloud& reference) const;
  /// Nodal displacements u = T(X) − X of a 3D mesh (num_nodes · 3, node-major).
  Eigen::VectorXd displacement(const fe::Mesh& mesh) const;
};

/// The map of a manufactured target: `deformed` holds the deformed nodes of a state solved
/// on `source`, in `source`'s node order. Between nodes T is the FE interpolant,
///
///     T(X) = X + Σ_a N_a(ξ) (y_a − X_a)   in the source element containing X,
///
/// exact at every source node (so at every node of a mesh the source refines).
class NodalMap {
 public:
  /// Throws InvalidArgument if the counts or dimensions of `source` and `deformed` differ.
  NodalMap(fe::Mesh source, const PointCloud& deformed);
  /// The mesh the state was solved on.
  const fe::Mesh& source() const { return source_; }
  /// u_T(X) = T(X) − X at one reference point. Throws InvalidArgument outside the source body.
  Eigen::VectorXd displacement_at(const Eigen::VectorXd& X) const;
  /// Nodal displacements u = T(X) − X of a mesh (num_nodes · dim, node-major). Throws
  /// InvalidArgument naming the first node outside the source body.
  Eigen::VectorXd displacement(const fe::Mesh& mesh) const;

 private:
  /// u_T at the rows of X (P by dim), located by `locator` (of source_).
  Eigen::MatrixXd displacements_at(const fe::PointLocator& locator, const Eigen::MatrixXd& X) const;

  fe::Mesh source_;
  Eigen::MatrixXd u_;  // source nodes by dim: y_a − X_a
};

}  // namespace softhd
