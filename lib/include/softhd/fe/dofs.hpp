#pragma once
/// \file dofs.hpp
/// Degrees of freedom: dim displacement components per node (dof = node dim + component),
/// some fixed to zero by Dirichlet constraints on named faces.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "softhd/fe/mesh.hpp"

namespace softhd::fe {

/// u_c = 0 on a named face for the listed components (all of them by default: a clamp).
struct DirichletConstraint {
  std::string face;             ///< "x0", "x1", "y0", "y1", "z0" or "z1"
  std::vector<int> components;  ///< subset of 0..dim-1; empty means all
};

/// Numbering of the free dofs.
struct DofMap {
  int dim = 3;                ///< components per node
  Eigen::Index num_dofs = 0;  ///< num_nodes · dim
  Eigen::Index num_free = 0;  ///< dofs not fixed by a constraint
  /// Free index of each dof, or -1 if it is fixed.
  Eigen::VectorXi free_index;
  /// Dof of each free index.
  Eigen::VectorXi free_dofs;

  /// Full vector (fixed entries zero) from free values.
  Eigen::VectorXd expand(const Eigen::VectorXd& free_values) const;
  /// The free entries of a full vector.
  Eigen::VectorXd restrict(const Eigen::VectorXd& full_values) const;
};

/// Throws InvalidArgument naming an unknown face or an out-of-range component.
DofMap make_dof_map(const Mesh& mesh, const std::vector<DirichletConstraint>& constraints);

/// Checks that the constraints hold the body (docs/formulation.md §7): for every connected
/// part of the mesh (elements joined by shared nodes) the fixed dofs must fix its rigid
/// motions — the 6 (3D) or 3 (2D) translations and rotations restricted to the fixed dofs have
/// full rank. Throws InvalidArgument with one line naming the part (its regions) and the
/// groups that hold it, or a constraint group that has no node of the body; also what
/// make_dof_map throws.
void check_rigid_motions(const Mesh& mesh, const std::vector<DirichletConstraint>& constraints);

}  // namespace softhd::fe
