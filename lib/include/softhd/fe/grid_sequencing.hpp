#pragma once
/// \file grid_sequencing.hpp
/// Grid sequencing (docs/formulation.md §3.7): the equilibrium is first solved on coarser
/// levels, coarsest first, and each finer Newton solve starts from the coarser state
/// interpolated by the coarse shape functions. A structured box is coarsened by halving its
/// cells; a mesh from a file, which has no grid to halve, by dropping its order (p-sequencing:
/// P1/Q1 on the vertices of the same P2/Q2 cells). coarsened() is the one place that chooses;
/// the transfers between levels (prolongate, control_on_quadrature) work for both. A coarse
/// Newton iteration is cheap, and the fine solve then starts near its solution, so the
/// indefinite tangents met far from equilibrium are met on the cheap level.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "softhd/fe/control.hpp"
#include "softhd/fe/newton.hpp"
#include "softhd/fe/scene.hpp"

namespace softhd::fe {

/// How many coarser levels to solve first.
struct GridSequencingOptions {
  /// Coarser levels solved first: 0 none, −1 automatic (a box: halve while some axis has
  /// an even cell count and the coarser mesh keeps at least `min_elements` elements; a file
  /// mesh of order 2 with at least `min_elements` elements: its P1/Q1 level; else none).
  int levels = -1;
  /// The smallest coarse mesh (elements) the automatic choice accepts.
  int min_elements = 32;
  /// Throws InvalidArgument naming the field if levels < −1 or min_elements < 1.
  void validate() const;
};

/// One coarse solve of a grid sequence.
struct GridLevelReport {
  Eigen::VectorXi cells;  ///< a halved box's cells per axis (empty for a P1/Q1 level)
  NewtonSummary newton;   ///< its Newton solve
  /// What the level is, for reports: "cells 25 2 1", or "P1 on the vertices: tet4, 812
  /// nodes".
  std::string mesh;
  CellType cell = CellType::kHex8;  ///< its cell type
  Eigen::Index nodes = 0;           ///< its node count
};

/// What grid_sequenced_start did.
struct GridSequencingReport {
  std::vector<GridLevelReport> levels;  ///< coarsest first
  /// True if a coarse solve failed and the fine solve starts from rest instead.
  bool fell_back_to_rest = false;
  /// One line per level (and the fallback), for progress output.
  std::string BriefReport() const;
};

/// How a box is halved. `nested` (grid sequencing's): along its even axes only, so the coarse
/// grid's nodes are nodes of the fine one. `rounded` (multilevel optimisation's levels): as
/// `nested` where some axis is even, else every axis of at least 4 cells to (n + 1) / 2, a
/// coarser box that is not nested (25 x 5 x 1 -> 13 x 3 x 1); fields move between such levels
/// by interpolation at points (prolongate, control_at), which needs no nesting.
enum class Halving { nested, rounded };

/// The next coarser level of `scene`: a box halved as `halving` says; a file mesh of order 2
/// as P1/Q1 on its vertices (linear_mesh: the same materials per region, constraints by name
/// on the vertex nodes of their sets, fibre fields per node restricted to the vertices, the
/// linear cell's default quadrature). Throws InvalidArgument if there is none (a box with no
/// axis to halve; a file mesh of order 1).
Scene coarsened(const Scene& scene, Halving halving = Halving::nested);

/// How many times in a row coarsened(·, halving) goes on with at least `min_elements`
/// elements on the coarser level (a file mesh: 1 or 0, its P1/Q1 level).
int coarser_levels(const Scene& scene, Halving halving, int min_elements);

/// What the level `scene` is, for reports: "cells 25 2 1" (a box), or "P1 on the vertices:
/// tet4, 812 nodes" (a file mesh's P1/Q1 level), or "tet10, 4849 nodes" (any other).
std::string describe_level(const Scene& scene);

/// The number of coarser levels `options` asks for on `scene` (−1 resolved). Throws
/// InvalidArgument if an explicit count cannot be coarsened that often.
int grid_levels(const Scene& scene, const GridSequencingOptions& options);

/// Reference positions of the quadrature points of `mesh`: row e·nq + q is point q of e.
Eigen::MatrixXd quadrature_positions(const Mesh& mesh, const ReferenceGeometry& geometry);

/// The control field m of `kind` on `mesh`, acting on `regions`, at the quadrature points of
/// `assembler`'s mesh (E by nq, the layout of ControlSpace::to_quadrature): control_at those
/// points; on the same cells (same_cells, fe/interpolation.hpp: a P1/Q1 level) m is the
/// assembler's own control, taken at the same reference points.
Eigen::MatrixXd control_on_quadrature(const Assembler& assembler, const Mesh& mesh,
                                      ControlKind kind, const Eigen::VectorXd& m,
                                      const std::vector<int>& regions = {});

/// Nodal displacements on `fine` of the field u(X) = Σ_a N_a(ξ) u_a on `coarse` (the coarse
/// element containing each fine node); on the same cells (same_cells) element by element
/// through the reference coordinates (transfer_nodal), either way round. Throws
/// InvalidArgument if a node is outside.
Eigen::VectorXd prolongate(const Mesh& coarse, const Eigen::VectorXd& u_coarse, const Mesh& fine);

/// The equilibrium on `scene`'s mesh (*mesh, *state) under the control values m of `kind`
/// given on `control_mesh`, after `levels` coarser levels solved first (each level starts
/// from the one below prolongated). Appends each level's Newton summary to report->levels;
/// returns false if a solve does not converge.
bool solve_grid_level(const Scene& scene, const Mesh& control_mesh, ControlKind kind,
                      const Eigen::VectorXd& m, int levels, const NewtonOptions& newton,
                      GridSequencingReport* report, Mesh* mesh, State* state);

/// The start state for the fine solve of `scene` (its assembler `fine`) under the control
/// values m of `kind` on the fine mesh: the rest state if no level is asked for, else the
/// equilibrium of the coarser levels prolongated onto the fine nodes, with m_qp at full
/// load. A coarse solve that does not converge makes the start the rest state (reported).
State grid_sequenced_start(const Scene& scene, const Assembler& fine, const Eigen::VectorXd& m,
                           const NewtonOptions& newton, const GridSequencingOptions& options,
                           GridSequencingReport* report = nullptr);

}  // namespace softhd::fe
