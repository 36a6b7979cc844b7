#pragma once
// The partition of a body's mesh (a box or a file's; any cell type) among the ranks of the
// PETSc state backend, and the global numbering of the free dofs that gives every rank one
// contiguous range of rows (internal; no PETSc or MPI types here, so it is testable on one
// process).
//
// Elements: recursive coordinate bisection of the element centroids. A part of the body
// shared by k ranks is cut across the axis it has the most elements across (its extent
// over the mean element width along that axis; the lowest axis on ties), at position
// ⌊n ⌊k/2⌋ / k⌋ of its n elements sorted along that axis (ties by element id); the lower
// side goes to its first ⌊k/2⌋ ranks. The cut moves down to the start of the run of equal
// centroid coordinates it falls in (else up to its end) unless a side would then have
// fewer elements than ranks: on a box the cuts fall between cell planes, and on 2 ranks a
// box of nc cells along its longest axis is cut into slabs of ⌊nc/2⌋ and ⌈nc/2⌉ cells.
//
// Nodes: a node shared by several ranks is owned by the lowest rank whose elements touch
// it. Rows: rank by rank, each rank's owned nodes in the lexicographic order of their
// coordinates (X_a, X_c, X_b), a the first cut's axis and b < c the others (on a box: node
// plane by node plane along a), the free components of a node consecutive (block size dim
// when every node is free or wholly fixed).
//
// Every rank builds the whole mesh once to cut it and to count the nonzeros of its owned
// rows (nodes, connectivity, element bounds and a node-to-element incidence; freed when the
// partition is made) and keeps only its elements.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "softhd/fe/assembly.hpp"
#include "softhd/fe/body.hpp"
#include "softhd/fe/dofs.hpp"
#include "softhd/fe/mesh.hpp"

namespace softhd::fe::petsc_detail {

/// The global free-dof numbering as seen by one rank.
struct FreeNumbering {
  std::int64_t num_global = 0;                  ///< free dofs of the whole mesh
  std::int64_t owned_begin = 0, owned_end = 0;  ///< this rank's rows [begin, end)
  std::vector<std::int64_t> local_to_global;    ///< per local free index: global row
  std::vector<int> owned_local;                 ///< local free index of each owned row, in order
  std::vector<std::int64_t> owned_global_dof;   ///< global dof (node dim + c) of each owned row
  bool whole_nodes = true;  ///< every local node has all or none of its components free
  ///@{
  /// Nonzeros of each owned row of the tangent (free dofs, both triangles) in the columns
  /// this rank owns and in the others: the free dofs of the nodes that share an element of
  /// the whole mesh with the row's node (exact preallocation, whatever rank assembles them).
  std::vector<int> diagonal_nonzeros, off_diagonal_nonzeros;
  ///@}
};

/// One rank's part of the body.
struct Partition {
  int rank = 0, size = 1;
  int axis = 0;  ///< the first cut's axis
  /// The rank's elements (in global element order) and their nodes and vertices (in global
  /// order), with the global mesh's coordinates, regions and region names; each named
  /// boundary set restricted to these nodes (possibly empty). Not structured().
  Mesh mesh;
  FiberField fibers;                ///< the body's fibre field on `mesh`
  std::vector<int> global_node;     ///< global node id of each local node
  std::vector<int> global_element;  ///< global element id of each local element
  std::vector<int> global_vertex;   ///< global vertex id of each local vertex
  Eigen::Index num_global_nodes = 0, num_global_elements = 0, num_global_vertices = 0;
  /// The rows, for the DofMap of `mesh` under the body's constraints (make_dof_map).
  FreeNumbering numbering;
};

/// The element owner (0..size-1) of every element of `mesh` by the recursive bisection
/// above; *first_axis gets the first cut's axis (0 for one rank). Throws InvalidArgument if
/// the mesh has fewer elements than ranks.
std::vector<int> bisect_elements(const Mesh& mesh, int size, int* first_axis);

/// The part of `rank` among `size` of `body`. Throws InvalidArgument if the mesh
/// has fewer elements than ranks or a node in no element.
Partition make_partition(const Body& body, int rank, int size);

}  // namespace softhd::fe::petsc_detail
