#include "nearest_index.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "kd_tree.hpp"
#include "softhd/parallel.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

#include "../common/matrix_rows.hpp"

namespace softhd::detail {

namespace {
using FlannTree = MatrixRowsTree<>;
}  // namespace

// The adaptor must live at a fixed address as long as the tree (nanoflann keeps a
// reference to it), hence both in one heap object.
struct NearestIndex::Tree {
  explicit Tree(const Eigen::MatrixXd& p)
      : rows{&p},
        index(static_cast<int>(p.cols()), rows, nanoflann::KDTreeSingleIndexAdaptorParams(16)) {}
  MatrixRows rows;
  FlannTree index;
};

NearestIndex::NearestIndex(const Eigen::MatrixXd& points) : tree_(std::make_unique<Tree>(points)) {}
NearestIndex::~NearestIndex() = default;
NearestIndex::NearestIndex(NearestIndex&&) noexcept = default;
NearestIndex& NearestIndex::operator=(NearestIndex&&) noexcept = default;

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

void NearestIndex::nearest(const Eigen::MatrixXd& queries, std::vector<Eigen::Index>* index,
                           Eigen::VectorXd* distance, int threads) const {
  const Eigen::Index n = queries.rows();
  const int d = static_cast<int>(queries.cols());
  index->assign(static_cast<size_t>(n), 0);
  distance->resize(n);
#pragma omp parallel for schedule(static) num_threads(resolve_threads(threads)) if (n > 512)
  for (Eigen::Index q = 0; q < n; ++q) {
    double point[3];
    for (int k = 0; k < d; ++k) point[k] = queries(q, k);
    size_t i = 0;
    double d2 = 0.0;
    tree_->index.knnSearch(point, 1, &i, &d2);
    (*index)[static_cast<size_t>(q)] = static_cast<Eigen::Index>(i);
    (*distance)[q] = std::sqrt(d2);
  }
}

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

/// min over the source points [begin, end) (tree order) of |q − x|², below `best`: one
/// vectorised loop per dimension count (a loop over the coordinates inside did not vectorise).
template <int D>
double scan2_d(const double* const* x, Eigen::Index begin, Eigen::Index end, const double* q,
               double best) {
  const double* x0 = x[0];
  const double* x1 = x[1];
  const double* x2 = x[D - 1];
  const double q0 = q[0], q1 = q[1], q2 = q[D - 1];
#pragma omp simd reduction(min : best)
  for (Eigen::Index i = begin; i < end; ++i) {
    const double a = q0 - x0[i], b = q1 - x1[i];
    const double c = D == 3 ? q2 - x2[i] : 0.0;
    best = std::min(best, a * a + b * b + c * c);
  }
  return best;
}

double scan2(const double* const* x, Eigen::Index begin, Eigen::Index end, const double* q, int d,
             double best) {
  return d == 3 ? scan2_d<3>(x, begin, end, q, best) : scan2_d<2>(x, begin, end, q, best);
}

/// The leaf holding q's nearest source: branch and bound from the root, nearer child first.
int nearest_leaf(const KdTree& src, const double* const* x, const double* q,
                 std::vector<int>& stack) {
  const std::vector<KdNode>& nodes = src.nodes();
  const int d = src.dim();
  double best = kInfinity;
  int leaf = 0;
  stack.assign(1, 0);
  while (!stack.empty()) {
    const KdNode& n = nodes[static_cast<size_t>(stack.back())];
    const int id = stack.back();
    stack.pop_back();
    if (box_gap2(n, q, d) >= best) continue;
    if (n.right < 0) {
      const double b = scan2(x, n.begin, n.end, q, d, best);
      if (b < best) best = b, leaf = id;
      continue;
    }
    const int l = id + 1, r = n.right;
    const bool left_first = box_gap2(nodes[static_cast<size_t>(l)], q, d) <=
                            box_gap2(nodes[static_cast<size_t>(r)], q, d);
    stack.push_back(left_first ? r : l);  // popped last
    stack.push_back(left_first ? l : r);
  }
  return leaf;
}

/// Per thread: the traversal stack and the candidate source leaves of one query leaf.
struct LeafScratch {
  std::vector<int> stack;
  std::vector<std::pair<double, int>> candidates;  // (squared box distance, leaf id)
};

/// The nearest-source distances of the points of query leaf T (tree positions), into out.
void leaf_nearest(const KdTree& src, const double* const* x, const KdTree& qt, const KdNode& T,
                  LeafScratch& s, double* out) {
  const int d = src.dim();
  const Eigen::MatrixXd& Q = qt.points();
  double q[3] = {0.0, 0.0, 0.0}, diag2 = 0.0;
  for (int k = 0; k < d; ++k) {
    q[k] = Q(T.begin, k);
    diag2 += (T.hi[k] - T.lo[k]) * (T.hi[k] - T.lo[k]);
  }
  // Every o in T: |o − y| ≤ |o − q₀| + |q₀ − y| ≤ diag T + d₀ for y the nearest source of
  // q₀ (in leaf L₀), so o's nearest source lies in a leaf whose box is within that of T's
  // box (a margin for rounding). L₀'s points also give every o its first bound.
  const int first = nearest_leaf(src, x, q, s.stack);
  const KdNode& L0 = src.nodes()[static_cast<size_t>(first)];
  const double d0 = std::sqrt(scan2(x, L0.begin, L0.end, q, d, kInfinity));
  const double bound = (d0 + std::sqrt(diag2)) * (1.0 + 1e-9);
  const std::vector<KdNode>& nodes = src.nodes();
  s.candidates.clear();
  s.stack.assign(1, 0);
  while (!s.stack.empty()) {
    const int id = s.stack.back();
    s.stack.pop_back();
    const KdNode& n = nodes[static_cast<size_t>(id)];
    const double g2 = box_gap2(n, T, d);
    if (g2 > bound * bound) continue;
    if (n.right < 0) {
      s.candidates.emplace_back(g2, id);
    } else {
      s.stack.push_back(n.right);
      s.stack.push_back(id + 1);
    }
  }
  std::sort(s.candidates.begin(), s.candidates.end());
  for (Eigen::Index i = T.begin; i < T.end; ++i) {
    for (int k = 0; k < d; ++k) q[k] = Q(i, k);
    double best = scan2(x, L0.begin, L0.end, q, d, kInfinity);
    for (const auto& c : s.candidates) {
      // The candidates come by their gap to T's box, a lower bound of their gap to q.
      if (c.first >= best) break;
      if (c.second == first) continue;  // scanned above
      const KdNode& n = nodes[static_cast<size_t>(c.second)];
      if (box_gap2(n, q, d) >= best) continue;
      best = scan2(x, n.begin, n.end, q, d, best);
    }
    out[i] = std::sqrt(best);
  }
}

}  // namespace

Eigen::VectorXd nearest_distances(const KdTree& sources, const KdTree& queries, int threads,
                                  const WorkShare* share) {
  const std::vector<KdNode>& qnodes = queries.nodes();
  std::vector<int> leaves;
  std::vector<double> cost;
  for (size_t id = 0; id < qnodes.size(); ++id)
    if (qnodes[id].right < 0) {
      leaves.push_back(static_cast<int>(id));
      cost.push_back(static_cast<double>(qnodes[id].end - qnodes[id].begin));
    }
  UnitRange mine{0, leaves.size()};
  if (share != nullptr) mine = split_by_cost(cost, share->size(), share->rank());
  const double* x[3] = {nullptr, nullptr, nullptr};
  for (int k = 0; k < sources.dim(); ++k) x[k] = sources.points().col(k).data();
  Eigen::VectorXd in_tree_order = Eigen::VectorXd::Zero(queries.size());
  // Small query sets in one thread, as in NearestIndex::distances: waking a team costs more.
  const bool parallel = queries.size() > 256;
#pragma omp parallel num_threads(resolve_threads(threads)) if (parallel)
  {
    LeafScratch scratch;
#pragma omp for schedule(dynamic, 16)
    for (size_t l = mine.first; l < mine.last; ++l)
      leaf_nearest(sources, x, queries, qnodes[static_cast<size_t>(leaves[l])], scratch,
                   in_tree_order.data());
  }
  if (share != nullptr) share->sum(in_tree_order.data(), static_cast<size_t>(queries.size()));
  Eigen::VectorXd out(queries.size());
  const std::vector<Eigen::Index>& order = queries.order();
  for (size_t q = 0; q < order.size(); ++q)
    out[order[q]] = in_tree_order[static_cast<Eigen::Index>(q)];
  return out;
}

}  // namespace softhd::detail
