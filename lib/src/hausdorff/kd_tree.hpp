#pragma once
// A k-d tree with per-node moments for method tree's far-field approximations
// (internal). nanoflann answers the nearest-neighbour queries; this tree only groups
// the source points of a pair pass into boxes and carries what the error bounds need.

#include <Eigen/Core>
#include <algorithm>
#include <vector>

#include "pair_kernel.hpp"

namespace softhd::detail {

/// One box of the tree. Nodes are stored in preorder: the left child of node n is
/// n + 1, the right child is `right` (−1 for a leaf), so every child follows its parent.
struct KdNode {
  double lo[3] = {0.0, 0.0, 0.0};  ///< bounding box of the node's points
  double hi[3] = {0.0, 0.0, 0.0};
  Eigen::Index begin = 0;  ///< the node's points are tree positions [begin, end)
  Eigen::Index end = 0;
  int right = -1;
};

/// Squared distance from the point q to the box of n (0 inside).
inline double box_gap2(const KdNode& n, const double* q, int d) {
  double g2 = 0.0;
  for (int k = 0; k < d; ++k) {
    const double gap = std::max({n.lo[k] - q[k], q[k] - n.hi[k], 0.0});
    g2 += gap * gap;
  }
  return g2;
}

/// Squared distance between the boxes of a and b (0 where they overlap).
inline double box_gap2(const KdNode& a, const KdNode& b, int d) {
  double g2 = 0.0;
  for (int k = 0; k < d; ++k) {
    const double gap = std::max({a.lo[k] - b.hi[k], b.lo[k] - a.hi[k], 0.0});
    g2 += gap * gap;
  }
  return g2;
}

/// Median splits along the widest side of the bounding box until a node has at most
/// `leaf_size` points. Stores the points in tree order (N by d, one contiguous array
/// per coordinate), so a node's points are one slice of each coordinate array.
class KdTree {
 public:
  KdTree(const Eigen::MatrixXd& points, int leaf_size);

  int dim() const { return static_cast<int>(points_.cols()); }
  Eigen::Index size() const { return points_.rows(); }
  const std::vector<KdNode>& nodes() const { return nodes_; }
  /// order()[k] = index in the caller's cloud of tree position k.
  const std::vector<Eigen::Index>& order() const { return order_; }
  /// N by d, tree order.
  const Eigen::MatrixXd& points() const { return points_; }
  /// Number of levels (a traversal stack of 2·depth() entries always suffices).
  int depth() const { return depth_; }
  /// v (caller's order) in tree order.
  Eigen::VectorXd permute(const Eigen::VectorXd& v) const;

 private:
  int build(Eigen::Index begin, Eigen::Index end, int level, int leaf_size,
            const Eigen::MatrixXd& input);
  std::vector<KdNode> nodes_;
  std::vector<Eigen::Index> order_;
  Eigen::MatrixXd points_;
  int depth_ = 0;
};

/// Moments of one node for source weights a_n ≥ 0 and, optionally, per-point scales
/// c_n > 0. With scales, the node's scale is C = max c_n and its effective weights are
/// ã_n = a_n (c_n/C)^α (so that a_n (c_n t)^α = ã_n (C t)^α); without, C = 1, ã_n = a_n.
struct NodeMoments {
  double mass = 0.0;                     ///< Σ a_n (shares of the error budget)
  double weight = 0.0;                   ///< Σ ã_n
  double centroid[3] = {0.0, 0.0, 0.0};  ///< Σ ã_n x_n / Σ ã_n (box centre if 0)
  double spread = 0.0;                   ///< Σ ã_n |x_n − centroid|²
  double scale = 1.0;                    ///< C
};

/// NodeMoments of every node of `tree`, for weights `a` and scales `c` (nullptr: none),
/// both in tree order. Leaves directly, inner nodes from their children (parallel-axis
/// rule, rescaling a child by (C_child/C)^α): O(N + nodes).
std::vector<NodeMoments> node_moments(const KdTree& tree, const double* a, const double* c,
                                      const KernelPower& power);

}  // namespace softhd::detail
