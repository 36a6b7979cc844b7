#include "neighbours.hpp"

#include <cmath>

#include "../common/matrix_rows.hpp"

namespace softhd::scan::detail {

namespace {
using softhd::detail::MatrixRows;
using FlannTree = softhd::detail::MatrixRowsTree<>;
}  // namespace

Neighbours nearest_neighbours(const Eigen::MatrixXd& points, int k) {
  const Eigen::Index n = points.rows();
  const int d = static_cast<int>(points.cols());
  Neighbours out;
  out.k = k;
  out.index.resize(static_cast<size_t>(n) * k);
  out.distance.resize(static_cast<size_t>(n) * k);
  const MatrixRows rows{&points};
  FlannTree tree(d, rows, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  const size_t want = static_cast<size_t>(k) + 1;  // the point itself is among them
#pragma omp parallel
  {
    std::vector<size_t> found(want);
    std::vector<double> dist2(want);
#pragma omp for schedule(static)
    for (Eigen::Index i = 0; i < n; ++i) {
      double q[3] = {0.0, 0.0, 0.0};
      for (int c = 0; c < d; ++c) q[c] = points(i, c);
      const size_t got = tree.knnSearch(q, want, found.data(), dist2.data());
      // Drop the point itself; if duplicates hid it, drop the farthest instead.
      size_t skip = got - 1;
      for (size_t m = 0; m < got; ++m) {
        if (static_cast<Eigen::Index>(found[m]) == i) skip = m;
      }
      size_t slot = static_cast<size_t>(i) * k;
      for (size_t m = 0; m < got && slot < static_cast<size_t>(i + 1) * k; ++m) {
        if (m == skip) continue;
        out.index[slot] = static_cast<Eigen::Index>(found[m]);
        out.distance[slot] = std::sqrt(dist2[m]);
        ++slot;
      }
    }
  }
  return out;
}

}  // namespace softhd::scan::detail
