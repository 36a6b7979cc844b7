#pragma once
// A 3D mesh's cells split into trilinear hexahedra (internal), the cell form of a body that the
// cell-integrated distance integrates over (docs/formulation.md §2.8):
//
//   hex8   the cell itself;
//   hex27  its 8 octants, whose corners are its 27 nodes;
//   tet4, tet10  4 hexahedra, one per vertex v: v, the midpoints of v's three edges, the
//          centroids of v's three faces and the cell's centroid.
//
// Every corner of a sub-hexahedron is a point of its element's map, x(ξ) = Σ_a N_a(ξ) x_a, so
// the corners are linear in the mesh's nodes: points = map · nodes, and a gradient with respect
// to the points pulls back to the nodes by mapᵀ. A corner on a vertex, edge, face or in the cell
// is shared by every element on that entity (keyed by its vertices), so the hexahedra are
// conforming: their faces on one element only are the body's boundary. On affine cells (hex8
// parallelepipeds, tet4, tet10 with straight edges) the hexahedra fill the cell exactly; on
// curved cells (hex27, tet10) they interpolate it at their corners (second order in h).

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "softhd/fe/mesh.hpp"

namespace softhd::fe {

/// Sub-hexahedra of a mesh's cells over points linear in the mesh's nodes.
struct HexDecomposition {
  /// S by 8 point ids per sub-hexahedron, corners in Gmsh's order (reference coordinates 0
  /// (−,−,−), 1 (+,−,−), 2 (+,+,−), 3 (−,+,−), then the same at +), positively oriented
  /// wherever the element's map is.
  Eigen::Matrix<int, Eigen::Dynamic, 8> cells;
  Eigen::VectorXi parent;  ///< the mesh element of each sub-hexahedron (S)
  /// P by mesh.num_nodes(): the points are map · (N by 3 node positions), any configuration.
  Eigen::SparseMatrix<double, Eigen::RowMajor> map;
};

/// The sub-hexahedra of every cell of a 3D mesh. Throws InvalidArgument for a 2D mesh (the cell
/// form is 3D only).
HexDecomposition hex_decomposition(const Mesh& mesh);

}  // namespace softhd::fe
