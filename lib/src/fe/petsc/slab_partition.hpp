#pragma once
// The partition of a structured box mesh into slabs of cells along its axis with the most
// cells, one slab per rank, and the global numbering of the free dofs that gives every rank
// a contiguous range (internal to the PETSc state backend; no PETSc or MPI types here, so it
// is testable on one process).
//
// Ownership: rank r owns the elements of its slab and the node planes from the slab's first
// plane up to, but excluding, its last one (the last rank owns its last plane too). The
// global free numbering orders node planes along the slab axis, then the nodes within a
// plane (the other axes, lower axis fastest), then the components: each rank's owned rows
// are one contiguous range, and a node's components are consecutive (block size dim when
// every node is free or wholly fixed).

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "softhd/fe/dofs.hpp"
#include "softhd/fe/mesh.hpp"
#include "softhd/fe/scene.hpp"

namespace softhd::fe::petsc_detail {

/// One rank's slab.
struct SlabPartition {
  int rank = 0, size = 1;
  int axis = 0;        ///< slab axis: the one with the most cells (the lowest on ties)
  int c0 = 0, c1 = 0;  ///< this rank's cells [c0, c1) along the axis
  Mesh mesh;           ///< the slab's mesh, with the global mesh's node coordinates
  std::vector<DirichletConstraint> constraints;  ///< the scene's, restricted to the slab
  std::vector<int> global_node;                  ///< global node id of each slab node
  std::vector<int> global_element;               ///< global element id of each slab element
  std::vector<int> global_vertex;                ///< global vertex id of each slab vertex
  Eigen::Index num_global_nodes = 0, num_global_elements = 0, num_global_vertices = 0;
};

/// The slab of `rank` among `size`: cells split as evenly as possible. Throws
/// InvalidArgument if the axis has fewer cells than there are ranks.
SlabPartition make_slab_partition(const Scene& scene, int rank, int size);

/// The global free-dof numbering as seen by one rank.
struct FreeNumbering {
  std::int64_t num_global = 0;                  ///< free dofs of the whole mesh
  std::int64_t owned_begin = 0, owned_end = 0;  ///< this rank's rows [begin, end)
  std::vector<std::int64_t> local_to_global;    ///< per slab free index: global row
  std::vector<int> owned_local;                 ///< slab free index of each owned row, in order
  std::vector<std::int64_t> owned_global_dof;   ///< global dof (node dim + c) of each owned row
  bool whole_nodes = true;  ///< every node has all or none of its components free
};

/// Numbers the free dofs; `slab_dofs` is the DofMap of the slab's assembler (its fixed dofs
/// must be those the scene's constraints fix on the global mesh; checked, Error
/// otherwise).
FreeNumbering number_free_dofs(const Scene& scene, const SlabPartition& slab,
                               const DofMap& slab_dofs);

}  // namespace softhd::fe::petsc_detail
