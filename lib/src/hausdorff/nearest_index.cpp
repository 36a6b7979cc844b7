#include "nearest_index.hpp"

#include <cmath>
#include <nanoflann.hpp>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace softhd::detail {

namespace {
// nanoflann's dataset adaptor: reads the caller's N by d matrix in place.
struct MatrixRows {
  const Eigen::MatrixXd* points;
  size_t kdtree_get_point_count() const { return static_cast<size_t>(points->rows()); }
  double kdtree_get_pt(size_t i, size_t d) const {
    return (*points)(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(d));
  }
  template <class BBox>
  bool kdtree_get_bbox(BBox&) const {
    return false;
  }
};
using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, MatrixRows>,
                                                   MatrixRows, -1, size_t>;
}  // namespace

// The adaptor must live at a fixed address as long as the tree (nanoflann keeps a
// reference to it), hence both in one heap object.
struct NearestIndex::Tree {
  explicit Tree(const Eigen::MatrixXd& p)
      : rows{&p},
        index(static_cast<int>(p.cols()), rows, nanoflann::KDTreeSingleIndexAdaptorParams(16)) {}
  MatrixRows rows;
  KdTree index;
};

NearestIndex::NearestIndex(const Eigen::MatrixXd& points) : tree_(std::make_unique<Tree>(points)) {}
NearestIndex::~NearestIndex() = default;
NearestIndex::NearestIndex(NearestIndex&&) noexcept = default;
NearestIndex& NearestIndex::operator=(NearestIndex&&) noexcept = default;

int resolve_threads(int threads) {
#ifdef _OPENMP
  return threads > 0 ? threads : omp_get_max_threads();
#else
  (void)threads;
  return 1;
#endif
}

Eigen::VectorXd NearestIndex::distances(const Eigen::MatrixXd& queries, int threads,
                                        const WorkShare* share) const {
  const Eigen::Index n = queries.rows();
  const int d = static_cast<int>(queries.cols());
  Eigen::VectorXd out = Eigen::VectorXd::Zero(n);
  const int nthreads = resolve_threads(threads);
  // One query costs about the same as any other: the share splits them by count.
  UnitRange mine{0, static_cast<size_t>(n)};
  if (share != nullptr)
    mine = split_by_cost(std::vector<double>(static_cast<size_t>(n), 1.0), share->size(),
                         share->rank());
  const Eigen::Index first = static_cast<Eigen::Index>(mine.first);
  const Eigen::Index last = static_cast<Eigen::Index>(mine.last);
#pragma omp parallel for schedule(static) num_threads(nthreads) if (last - first > 256)
  for (Eigen::Index q = first; q < last; ++q) {
    double point[3];
    for (int k = 0; k < d; ++k) point[k] = queries(q, k);
    size_t index = 0;
    double dist2 = 0.0;
    tree_->index.knnSearch(point, 1, &index, &dist2);
    out[q] = std::sqrt(dist2);
  }
  if (share != nullptr) share->sum(out.data(), static_cast<size_t>(n));
  return out;
}

}  // namespace softhd::detail
