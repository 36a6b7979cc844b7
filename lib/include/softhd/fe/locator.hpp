#pragma once
/// \file locator.hpp
/// Point location in any Mesh (docs/formulation.md §7): the element containing a reference
/// point X and its reference coordinates ξ with X = Σ_a X_a N_a(ξ). Structured boxes by
/// arithmetic (fe::locate); otherwise a k-d tree over the centres of the element bounding
/// boxes (padded by a quarter of their size for curved quadratic elements; candidates within
/// the largest half-diagonal, lowest element id first) and Newton inversion of the
/// isoparametric map in each candidate element (lib/src/fe/locator.cpp).

#include <Eigen/Core>
#include <memory>

#include "softhd/fe/mesh.hpp"

namespace softhd::fe {

/// Locates points in one mesh; built once, then const and thread-safe.
class PointLocator {
 public:
  /// Keeps a reference to `mesh`, which must outlive the locator.
  explicit PointLocator(const Mesh& mesh);
  ~PointLocator();
  /// Movable (the tree moves with it), not copyable.
  PointLocator(PointLocator&&) noexcept;
  /// Movable, not copyable.
  PointLocator& operator=(PointLocator&&) noexcept;

  /// The element containing X (dim entries) and ξ in it, or -1 if X is outside the mesh
  /// (tolerance 1e-10 relative to the mesh's size, in reference coordinates for ξ).
  int locate(const Eigen::VectorXd& X, Eigen::VectorXd* xi) const;

 private:
  struct Tree;
  const Mesh* mesh_;
  std::unique_ptr<Tree> tree_;  ///< null for structured meshes
};

}  // namespace softhd::fe
