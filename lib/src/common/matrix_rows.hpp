#pragma once
// nanoflann's dataset adaptor over the rows of an N by d matrix, read in place (internal):
// the one adaptor of the k-d trees in hausdorff/nearest_index.cpp, scan/neighbours.cpp and
// fe/locator.cpp. A tree keeps a reference to its adaptor: both must stay at one
// address while the tree lives.

#include <Eigen/Core>
#include <cstddef>
#include <nanoflann.hpp>
#include <vector>

namespace softhd::detail {

struct MatrixRows {
  const Eigen::MatrixXd* points;
  size_t kdtree_get_point_count() const { return static_cast<size_t>(points->rows()); }
  double kdtree_get_pt(size_t i, size_t d) const {
    return (*points)(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(d));
  }
  template <class BBox>
  bool kdtree_get_bbox(BBox&) const {
    return false;  // nanoflann computes the bounding box
  }
};

/// A k-d tree over MatrixRows, Euclidean (squared distances), of dimension Dim (−1: the
/// matrix's column count, given at run time).
template <int Dim = -1>
using MatrixRowsTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, MatrixRows>,
                                        MatrixRows, Dim, size_t>;

/// Collects every point within squared distance r2 into *found, as `Index` (the result-set
/// interface nanoflann's radiusSearchCustomCallback takes, the same in its 1.4 and 1.5 releases).
template <class Index>
struct WithinRadius {
  double r2;
  std::vector<Index>* found;
  void init() {}
  void clear() { found->clear(); }
  size_t size() const { return found->size(); }
  bool full() const { return true; }
  bool addPoint(double d2, size_t i) {
    if (d2 <= r2) found->push_back(static_cast<Index>(i));
    return true;
  }
  double worstDist() const { return r2; }
};

}  // namespace softhd::detail
