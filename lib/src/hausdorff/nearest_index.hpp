#pragma once
// Nearest neighbours with nanoflann (internal): the one nearest-point wrapper of the library.

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "softhd/work_share.hpp"

namespace softhd::detail {

/// A k-d tree over the rows of an N by d matrix, built once. The matrix must outlive
/// the index (the tree points at it; it does not copy it).
class NearestIndex {
 public:
  explicit NearestIndex(const Eigen::MatrixXd& points);
  ~NearestIndex();
  NearestIndex(NearestIndex&&) noexcept;
  NearestIndex& operator=(NearestIndex&&) noexcept;

  /// For each row q of `queries` (K by d): min_i |q − x_i| (Euclidean).
  /// OpenMP over the queries; `threads` = 0 uses OpenMP's default. With a share, each
  /// process answers its run of the queries and the distances are summed over the group
  /// (collective; exact, the other processes contribute zeros).
  Eigen::VectorXd distances(const Eigen::MatrixXd& queries, int threads,
                            const WorkShare* share = nullptr) const;
  /// For each row q of `queries`: the index of its nearest row (ties: nanoflann's choice) and
  /// the distance. OpenMP over the queries above 512 of them.
  void nearest(const Eigen::MatrixXd& queries, std::vector<Eigen::Index>* index,
               Eigen::VectorXd* distance, int threads) const;

 private:
  struct Tree;
  std::unique_ptr<Tree> tree_;
};

class KdTree;

/// For every point q of `queries` (a k-d tree over them): min_x |q − x| over the points x of
/// `sources` (Euclidean), in the caller's order of the queries. One query leaf at a time:
/// its first point's nearest source bounds every point of the leaf (plus the leaf's
/// diagonal), the source leaves within that bound of the leaf's box are the candidates,
/// and each query point scans them nearest box first, skipping boxes beyond its best.
/// Where a kd search from the root cannot prune (sources nearly equidistant from a query,
/// a curved body seen from its centre of curvature) this visits them once per query leaf.
/// OpenMP over the query leaves; with a share, as NearestIndex::distances.
Eigen::VectorXd nearest_distances(const KdTree& sources, const KdTree& queries, int threads,
                                  const WorkShare* share = nullptr);

}  // namespace softhd::detail
