#include "kd_tree.hpp"

#include <algorithm>
#include <cassert>
#include <numeric>

namespace softhd::detail {

KdTree::KdTree(const Eigen::MatrixXd& points, int leaf_size) {
  assert(leaf_size >= 1);
  const Eigen::Index n = points.rows();
  order_.resize(static_cast<size_t>(n));
  std::iota(order_.begin(), order_.end(), Eigen::Index{0});
  nodes_.reserve(static_cast<size_t>(4 * (n / leaf_size + 1)));
  build(0, n, 1, leaf_size, points);
  points_.resize(n, points.cols());
  for (Eigen::Index k = 0; k < n; ++k) points_.row(k) = points.row(order_[static_cast<size_t>(k)]);
}

int KdTree::build(Eigen::Index begin, Eigen::Index end, int level, int leaf_size,
                  const Eigen::MatrixXd& input) {
  depth_ = std::max(depth_, level);
  const int d = static_cast<int>(input.cols());
  const int id = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  KdNode node;
  node.begin = begin;
  node.end = end;
  for (int k = 0; k < d; ++k) {
    node.lo[k] = INFINITY;
    node.hi[k] = -INFINITY;
  }
  for (Eigen::Index q = begin; q < end; ++q)
    for (int k = 0; k < d; ++k) {
      const double x = input(order_[static_cast<size_t>(q)], k);
      node.lo[k] = std::min(node.lo[k], x);
      node.hi[k] = std::max(node.hi[k], x);
    }
  int axis = 0;
  for (int k = 1; k < d; ++k)
    if (node.hi[k] - node.lo[k] > node.hi[axis] - node.lo[axis]) axis = k;
  // A leaf when small enough, or when all points coincide (nothing left to split).
  if (end - begin > leaf_size && node.hi[axis] > node.lo[axis]) {
    const Eigen::Index mid = begin + (end - begin) / 2;
    auto first = order_.begin() + begin, nth = order_.begin() + mid, last = order_.begin() + end;
    std::nth_element(first, nth, last, [&](Eigen::Index a, Eigen::Index b) {
      return input(a, axis) < input(b, axis);
    });
    build(begin, mid, level + 1, leaf_size, input);
    node.right = build(mid, end, level + 1, leaf_size, input);
  }
  nodes_[static_cast<size_t>(id)] = node;
  return id;
}

Eigen::VectorXd KdTree::permute(const Eigen::VectorXd& v) const {
  Eigen::VectorXd out(v.size());
  for (Eigen::Index k = 0; k < v.size(); ++k) out[k] = v[order_[static_cast<size_t>(k)]];
  return out;
}

std::vector<NodeMoments> node_moments(const KdTree& tree, const double* a, const double* c,
                                      const KernelPower& power) {
  const int d = tree.dim();
  const Eigen::MatrixXd& P = tree.points();
  const std::vector<KdNode>& nodes = tree.nodes();
  std::vector<NodeMoments> m(nodes.size());
  // Children follow their parents: a reverse sweep sees both children first.
  for (size_t id = nodes.size(); id-- > 0;) {
    const KdNode& node = nodes[id];
    NodeMoments& s = m[id];
    if (node.right < 0) {
      if (c != nullptr) s.scale = *std::max_element(c + node.begin, c + node.end);
      double sum[3] = {0.0, 0.0, 0.0};
      for (Eigen::Index q = node.begin; q < node.end; ++q) {
        const double wq = c != nullptr ? a[q] * power.scalar(c[q] / s.scale) : a[q];
        s.mass += a[q];
        s.weight += wq;
        for (int k = 0; k < d; ++k) sum[k] += wq * P(q, k);
      }
      for (int k = 0; k < d; ++k)
        s.centroid[k] = s.weight > 0.0 ? sum[k] / s.weight : 0.5 * (node.lo[k] + node.hi[k]);
      for (Eigen::Index q = node.begin; q < node.end; ++q) {
        const double wq = c != nullptr ? a[q] * power.scalar(c[q] / s.scale) : a[q];
        double r2 = 0.0;
        for (int k = 0; k < d; ++k) r2 += (P(q, k) - s.centroid[k]) * (P(q, k) - s.centroid[k]);
        s.spread += wq * r2;
      }
      continue;
    }
    const NodeMoments& l = m[id + 1];
    const NodeMoments& r = m[static_cast<size_t>(node.right)];
    s.scale = std::max(l.scale, r.scale);
    // Effective weights of a child rescaled to the parent's scale: factor (C_child/C)^α.
    const double fl = c != nullptr ? power.scalar(l.scale / s.scale) : 1.0;
    const double fr = c != nullptr ? power.scalar(r.scale / s.scale) : 1.0;
    s.mass = l.mass + r.mass;
    s.weight = fl * l.weight + fr * r.weight;
    for (int k = 0; k < d; ++k)
      s.centroid[k] =
          s.weight > 0.0
              ? (fl * l.weight * l.centroid[k] + fr * r.weight * r.centroid[k]) / s.weight
              : 0.5 * (node.lo[k] + node.hi[k]);
    double dl = 0.0, dr = 0.0;
    for (int k = 0; k < d; ++k) {
      dl += (l.centroid[k] - s.centroid[k]) * (l.centroid[k] - s.centroid[k]);
      dr += (r.centroid[k] - s.centroid[k]) * (r.centroid[k] - s.centroid[k]);
    }
    s.spread = fl * (l.spread + l.weight * dl) + fr * (r.spread + r.weight * dr);
  }
  return m;
}

}  // namespace softhd::detail
