#pragma once
/// \file mesh_hierarchy.hpp
/// A body and its coarser levels, with the transfers of fields between them
/// (docs/formulation.md §3.7 and §4.8). One hierarchy serves the three users of coarse
/// levels: grid sequencing of one state solve (fe/grid_sequencing.hpp), the two-level starts
/// of an optimisation's state solves, and multilevel optimisation (a coarse problem per level).
///
/// A level is made from the one above it by coarsened(): a structured box halves its cells
/// (Halving says how), a mesh from a file drops its order (P1/Q1 on the vertices of the same
/// P2/Q2 cells: p-sequencing). The transfers (prolongate, control_on_quadrature,
/// prolongate_control) work between any two levels, nested or not.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "softhd/fe/body.hpp"
#include "softhd/fe/control.hpp"

namespace softhd::fe {

/// How a box is halved. `nested` (grid sequencing and two-level starts): along its even axes
/// only, so the coarse grid's nodes are nodes of the fine one. `rounded` (multilevel
/// optimisation): as `nested` where some axis is even, else every axis of at least 4 cells to
/// (n + 1) / 2, a coarser box that is not nested (25 x 5 x 1 -> 13 x 3 x 1); fields move
/// between such levels by interpolation at points, which needs no nesting.
enum class Halving { nested, rounded };

/// The next coarser level of `body`: a box halved as `halving` says; a file mesh of order 2
/// as P1/Q1 on its vertices (linear_mesh: the same materials per region, constraints by name
/// on the vertex nodes of their sets, fibre fields per node restricted to the vertices, the
/// linear cell's default quadrature). Throws InvalidArgument if there is none (a box with no
/// axis to halve; a file mesh of order 1).
Body coarsened(const Body& body, Halving halving = Halving::nested);

/// How many times in a row coarsened(·, halving) goes on with at least `min_elements`
/// elements on the coarser level (a file mesh: 1 or 0, its P1/Q1 level). Builds no level of a
/// file mesh.
int coarser_levels(const Body& body, Halving halving, int min_elements);

/// What the level `body` is, for reports: "cells 25 2 1" (a box), or "P1 on the vertices:
/// tet4, 812 nodes" (a file mesh's P1/Q1 level), or "tet10, 4849 nodes" (any other).
std::string describe_level(const Body& body);

/// A body (level 0) and `coarser` levels below it, each coarsened() from the one above.
class MeshHierarchy {
 public:
  /// Throws InvalidArgument "N coarser levels asked for, but the body has K (why)" if
  /// coarsened() stops before `coarser` levels, or if coarser < 0.
  MeshHierarchy(const Body& body, Halving halving, int coarser);
  /// The levels, the body's included: 1 + coarser.
  int size() const { return static_cast<int>(levels_.size()); }
  /// Level k: 0 the body, size() − 1 the coarsest.
  const Body& level(int k) const { return levels_.at(static_cast<size_t>(k)); }
  /// How each level was made from the one above.
  Halving halving() const { return halving_; }

 private:
  std::vector<Body> levels_;
  Halving halving_;
};

/// Reference positions of the quadrature points of `mesh`: row e·nq + q is point q of e.
Eigen::MatrixXd quadrature_positions(const Mesh& mesh, const ReferenceGeometry& geometry);

/// The control field m of `kind` on `mesh`, acting on `regions`, at the quadrature points of
/// `assembler`'s mesh (E by nq, the layout of ControlSpace::to_quadrature): control_at those
/// points; on the same cells (same_cells, fe/interpolation.hpp: a P1/Q1 level) m is the
/// assembler's own control, taken at the same reference points.
Eigen::MatrixXd control_on_quadrature(const Assembler& assembler, const Mesh& mesh,
                                      ControlKind kind, const Eigen::VectorXd& m,
                                      const std::vector<int>& regions = {});

/// Nodal displacements on `to` of the field u(X) = Σ_a N_a(ξ) u_a on `from` (the element of
/// `from` containing each node of `to`): from a coarser level to a finer one, or back; on the
/// same cells (same_cells) element by element through the reference coordinates
/// (transfer_nodal). Throws InvalidArgument if a node is outside.
Eigen::VectorXd prolongate(const Mesh& from, const Eigen::VectorXd& u_from, const Mesh& to);

/// The control m of `coarse_control` on `coarse` at the controls of `fine_control` on `fine`
/// (another level of the same body): vertex controls interpolated at the fine vertices,
/// element controls the containing coarse element's value at each fine element's centre
/// (control_at); 0 outside `regions`. On the same cells (a P1/Q1 level and its P2/Q2 mesh) m
/// itself.
Eigen::VectorXd prolongate_control(const Mesh& coarse, const ControlSpace& coarse_control,
                                   const Eigen::VectorXd& m, const Mesh& fine,
                                   const ControlSpace& fine_control,
                                   const std::vector<int>& regions);

}  // namespace softhd::fe
