#pragma once
/// \file grid_sequencing.hpp
/// Grid sequencing (docs/formulation.md §3.7): the equilibrium is first solved on coarser
/// levels, coarsest first, and each finer Newton solve starts from the coarser state
/// interpolated by the coarse shape functions. A structured box is coarsened by halving its
/// cells; a mesh from a file, which has no grid to halve, by dropping its order (p-sequencing:
/// P1/Q1 on the vertices of the same P2/Q2 cells): the levels of a MeshHierarchy
/// (fe/mesh_hierarchy.hpp), which also holds the transfers between them. A coarse
/// Newton iteration is cheap, and the fine solve then starts near its solution, so the
/// indefinite tangents met far from equilibrium are met on the cheap level.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "softhd/fe/body.hpp"
#include "softhd/fe/control.hpp"
#include "softhd/fe/mesh_hierarchy.hpp"
#include "softhd/fe/newton.hpp"

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

/// The number of coarser levels `options` asks for on `body` (−1 resolved). Throws
/// InvalidArgument if an explicit count cannot be coarsened that often.
int grid_levels(const Body& body, const GridSequencingOptions& options);

/// The hierarchy of grid sequencing on `body`: options.levels coarser levels of
/// Halving::nested (−1 resolved). Throws InvalidArgument if an explicit count cannot be
/// coarsened that often, saying how many levels the body has.
MeshHierarchy grid_hierarchy(const Body& body, const GridSequencingOptions& options);

/// Solves the equilibrium on levels size() − 1, …, 1 of `levels` (coarsest first, each from
/// the one below prolongated) under the control values m of `kind` given on `control_mesh`;
/// *mesh and *state are level 1's. Appends each level's Newton summary to report->levels;
/// returns false, after the report of the failed level, if a solve does not converge.
bool solve_coarse_levels(const MeshHierarchy& levels, const Mesh& control_mesh, ControlKind kind,
                         const Eigen::VectorXd& m, const NewtonOptions& newton,
                         GridSequencingReport* report, Mesh* mesh, State* state);

/// The start state for the fine solve of `body` (its assembler `fine`) under the control
/// values m of `kind` on the fine mesh: the rest state if no level is asked for, else the
/// equilibrium of the coarser levels prolongated onto the fine nodes, with m_qp at full
/// load. A coarse solve that does not converge makes the start the rest state (reported).
State grid_sequenced_start(const Body& body, const Assembler& fine, const Eigen::VectorXd& m,
                           const NewtonOptions& newton, const GridSequencingOptions& options,
                           GridSequencingReport* report = nullptr);

}  // namespace softhd::fe
