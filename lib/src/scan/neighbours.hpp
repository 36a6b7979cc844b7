#pragma once
// The k nearest neighbours of every point of a cloud, with nanoflann (internal to scan/).

#include <Eigen/Core>
#include <vector>

namespace softhd::scan::detail {

/// For each of the N rows of `points` (N by d), its k nearest other rows, nearest first:
/// `index[i * k + m]` and `distance[i * k + m]` (Euclidean) for m = 0..k−1. The point itself
/// is left out (a duplicate of it is a neighbour at distance 0). Requires 1 ≤ k < N.
/// OpenMP over the points; deterministic (each point's search is independent).
struct Neighbours {
  int k = 0;
  std::vector<Eigen::Index> index;
  std::vector<double> distance;
};
Neighbours nearest_neighbours(const Eigen::MatrixXd& points, int k);

}  // namespace softhd::scan::detail
