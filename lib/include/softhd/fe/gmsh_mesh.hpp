#pragma once
/// \file gmsh_mesh.hpp
/// A Mesh from a Gmsh file's data (io/msh.hpp; docs/formulation.md §7): the elements of the
/// file's top dimension (tetrahedra or hexahedra in 3D, triangles or quadrilaterals in 2D,
/// one cell type per mesh) with Gmsh's local node order mapped to the internal one, the
/// physical groups of the top dimension as regions and those of lower dimensions as named
/// boundary node sets (a physical surface "base" becomes mesh.face("base")).

#include <string>

#include "softhd/fe/assembly.hpp"
#include "softhd/fe/mesh.hpp"
#include "softhd/io/msh.hpp"

namespace softhd::fe {

/// How the file's elements become the mesh.
struct GmshMeshOptions {
  /// 0: the file's order; 1: the elements' vertices only (P1/Q1 on a second-order file);
  /// 2: second order, straight-sided midside nodes added to a first-order file (a
  /// second-order file is kept isoparametric).
  int order = 0;
  /// Coordinates are multiplied by this (e.g. 1e-3 for a file in mm and a scene in m), in
  /// [kMinScale, kMaxScale].
  double scale = 1.0;

  ///@{
  /// The range of `scale`: a file's lengths in any unit from nanometres to kilometres made
  /// metres or millimetres, with the scaled lengths and volumes far from overflow and
  /// underflow.
  static constexpr double kMinScale = 1e-12;
  static constexpr double kMaxScale = 1e12;
  ///@}

  /// Throws InvalidArgument naming the field.
  void validate() const;
};

/// The counts and memory estimate (check_mesh_size) of mesh_from_gmsh(file, options) from
/// the file's counts (io::scan_msh_counts), before the file is parsed. Vertices V and
/// elements E give, by Euler's formula without its boundary terms, the nodes of a
/// second-order mesh (2V + kE: k = 1 for simplices, 2 quadrilaterals, 6 hexahedra) and the
/// node pairs sharing a cell (docs/formulation.md §7). Zero counts if the file has no
/// element type softhd solves on (mesh_from_gmsh then says so).
MeshSize gmsh_mesh_size(const io::MshCounts& counts, const GmshMeshOptions& options = {});

/// The mesh of `file`. Throws InvalidArgument with one line naming what is wrong (no
/// elements of the body's dimension — Gmsh writes none for a geometry with physical
/// surfaces but no physical volume —, mixed cell types or orders, an element type softhd
/// does not solve on, an entity in two physical volumes); callers prefix the file name.
/// Unused nodes (e.g. geometry points) are dropped; nodes are numbered in file order.
Mesh mesh_from_gmsh(const io::MshFile& file, const GmshMeshOptions& options = {});

/// The mesh of the Gmsh file at `path` (io::read_msh, then mesh_from_gmsh), with
/// det(dX/dξ) > 0 checked at the cell type's default quadrature points; `volume`, if not
/// null, gets |Ω₀| = Σ w_q det J0 there. Throws InvalidArgument for invalid options,
/// ResourceError (check_mesh_size, naming the file) if gmsh_mesh_size's estimate exceeds
/// `memory_limit` bytes, before the file is parsed, and FileError with one line naming the
/// file (and line or block) for anything wrong with it.
Mesh read_gmsh_mesh(const std::string& path, const GmshMeshOptions& options = {},
                    double* volume = nullptr, double memory_limit = kDefaultMemoryLimit);

/// The fibre field of the file's $ElementData or $NodeData block `name` (3 components) on
/// mesh_from_gmsh(file, options): per element, or per node (a new midside node gets the mean
/// of its support's). Throws InvalidArgument naming the block and what is wrong (missing,
/// not 3 components, an element or node without a value).
FiberField gmsh_fiber_field(const io::MshFile& file, const std::string& name,
                            const GmshMeshOptions& options = {});

}  // namespace softhd::fe
