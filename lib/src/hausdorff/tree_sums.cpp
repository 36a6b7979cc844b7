#include "tree_sums.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace softhd::detail {

namespace {

constexpr int kMaxStack = 256;  // > depth + 1 for any tree of up to 2^200 points

/// Error budget of one sum (see the header).
struct Budget {
  double low = 0.0;    // lower bound of the exact sum, from what has been summed so far
  double spent = 0.0;  // sum of the error bounds of the approximations made
  double done = 0.0;   // mass of the nodes already summed or approximated
  double total = 0.0;  // mass of the whole tree

  bool admits(double err, double low_node, double mass, double tau) const {
    const double share = total > 0.0 ? std::min(1.0, (done + mass) / total) : 1.0;
    return spent + err <= tau * (low + low_node) * share;  // false for NaN bounds
  }
  void approximate(double err, double low_node, double mass) {
    spent += err;
    low += low_node;
    done += mass;
  }
  void exact(double sum, double mass) {
    low += sum;
    done += mass;
  }
};

/// Error bounds and lower bounds of one node's one-term approximation.
struct FarBounds {
  double err_sum, err_grad;  // bounds of |ΔS| and ‖ΔG‖
  double low_sum, low_grad;  // W k(R_max), W k(R_max) t(R_max)
};

FarBounds far_bounds(double c, const NodeMoments& m, double r_min, double r_max, double alpha,
                     double eps, const KernelPower& power) {
  const double t_min = 1.0 / (r_min + eps), t_max = 1.0 / (r_max + eps);
  const double k_min = power.scalar(c * t_min), k_max = power.scalar(c * t_max);
  const double W = m.weight;
  const double hessian = alpha * k_min * t_min * std::max((alpha + 1.0) * t_min, 1.0 / r_min);
  const double third =
      k_min *
      ((alpha + 1.0) * (alpha + 2.0) * t_min * t_min * t_min +
       1.1547005383792517 * ((alpha + 1.0) * t_min * t_min + t_min / r_min) / r_min);  // 2/√3
  FarBounds b;
  b.err_sum = std::min(0.5 * m.spread * hessian, W * (k_min - k_max));
  b.err_grad = std::min(0.5 * m.spread * third, 2.0 * W * k_min * t_min);
  b.low_sum = W * k_max;
  b.low_grad = W * k_max * t_max;
  return b;
}

/// Distances from o to the nearest point and to the farthest corner of a node's box.
void box_distances(const double* o, const KdNode& n, int d, double& r_min, double& r_max) {
  double near2 = 0.0, far2 = 0.0;
  for (int k = 0; k < d; ++k) {
    const double below = n.lo[k] - o[k], above = o[k] - n.hi[k];
    const double gap = std::max({below, above, 0.0});
    const double span = std::max(std::fabs(o[k] - n.lo[k]), std::fabs(o[k] - n.hi[k]));
    near2 += gap * gap;
    far2 += span * span;
  }
  r_min = std::sqrt(near2);
  r_max = std::sqrt(far2);
}

double box_distance(const double* o, const KdNode& n, int d) {
  double near2 = 0.0;
  for (int k = 0; k < d; ++k) {
    const double gap = std::max({n.lo[k] - o[k], o[k] - n.hi[k], 0.0});
    near2 += gap * gap;
  }
  return near2;
}

/// Adds the one-term approximation W k t-terms at centroid x_c to (sum, grad).
void add_monopole(const double* o, int d, double c, const NodeMoments& m, double eps,
                  const KernelPower& power, bool want_grad, double& sum, double* grad) {
  double diff[3] = {0.0, 0.0, 0.0}, r2 = 0.0;
  for (int k = 0; k < d; ++k) {
    diff[k] = o[k] - m.centroid[k];
    r2 += diff[k] * diff[k];
  }
  const double r = std::sqrt(r2), t = 1.0 / (r + eps);
  const double wp = m.weight * power.scalar(c * t);
  sum += wp;
  if (want_grad && r > 0.0) {
    const double g = wp * t / r;
    for (int k = 0; k < d; ++k) grad[k] += g * diff[k];
  }
}

}  // namespace

PairSums tree_sums(const double* o, double c_o, const TreePass& pass, const KernelPower& power,
                   double eps, double tau, unsigned flags, std::int64_t& evaluations) {
  const KdTree& tree = *pass.tree;
  const std::vector<KdNode>& nodes = tree.nodes();
  const int d = tree.dim();
  const double alpha = power.alpha();
  const bool want_sum = (flags & kOuterSum) != 0, want_grad = (flags & kOuterGrad) != 0;
  const bool want_outer = want_sum || want_grad, want_inner = (flags & kInner) != 0;
  assert(!want_outer || pass.outer != nullptr);
  assert(!want_inner || pass.inner != nullptr);
  assert(tree.depth() + 1 < kMaxStack);

  Budget b_sum, b_grad, b_h, b_g2;
  if (want_outer) b_sum.total = b_grad.total = pass.outer[0].mass;
  if (want_inner) b_h.total = b_g2.total = pass.inner[0].mass;
  PairSums out;
  int stack[kMaxStack];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const int id = stack[--top];
    const KdNode& node = nodes[static_cast<size_t>(id)];
    const NodeMoments* mo = want_outer ? &pass.outer[id] : nullptr;
    const NodeMoments* mi = want_inner ? &pass.inner[id] : nullptr;
    if ((mo == nullptr || mo->mass == 0.0) && (mi == nullptr || mi->mass == 0.0)) continue;

    double r_min = 0.0, r_max = 0.0;
    box_distances(o, node, d, r_min, r_max);
    if (r_min > 0.0) {
      FarBounds fo{}, fi{};
      bool ok = true;
      if (want_outer) {
        fo = far_bounds(c_o, *mo, r_min, r_max, alpha, eps, power);
        ok = (!want_sum || b_sum.admits(fo.err_sum, fo.low_sum, mo->mass, tau)) &&
             (!want_grad || b_grad.admits(fo.err_grad, fo.low_grad, mo->mass, tau));
      }
      if (ok && want_inner) {
        fi = far_bounds(mi->scale, *mi, r_min, r_max, alpha, eps, power);
        ok = b_h.admits(fi.err_sum, fi.low_sum, mi->mass, tau) &&
             b_g2.admits(fi.err_grad, fi.low_grad, mi->mass, tau);
      }
      if (ok) {
        if (want_outer) {
          double s = 0.0;
          add_monopole(o, d, c_o, *mo, eps, power, want_grad, s, out.G);
          if (want_sum) out.S += s;
          b_sum.approximate(fo.err_sum, fo.low_sum, mo->mass);
          b_grad.approximate(fo.err_grad, fo.low_grad, mo->mass);
        }
        if (want_inner) {
          add_monopole(o, d, mi->scale, *mi, eps, power, true, out.H, out.G2);
          b_h.approximate(fi.err_sum, fi.low_sum, mi->mass);
          b_g2.approximate(fi.err_grad, fi.low_grad, mi->mass);
        }
        ++evaluations;
        continue;
      }
    }
    if (node.right < 0) {  // a leaf: exact
      PairSources sub = pass.src;
      sub.size = node.end - node.begin;
      for (int k = 0; k < d; ++k) sub.coord[k] += node.begin;
      if (sub.weight != nullptr) sub.weight += node.begin;
      if (sub.coef != nullptr) sub.coef += node.begin;
      if (sub.scale != nullptr) sub.scale += node.begin;
      const PairSums s = pair_sums(o, c_o, sub, power, eps, flags | kMagnitude);
      out.S += s.S;
      out.H += s.H;
      for (int k = 0; k < 3; ++k) {
        out.G[k] += s.G[k];
        out.G2[k] += s.G2[k];
      }
      if (want_outer) {
        b_sum.exact(s.S, mo->mass);
        b_grad.exact(s.Gm, mo->mass);
      }
      if (want_inner) {
        b_h.exact(s.H, mi->mass);
        b_g2.exact(s.G2m, mi->mass);
      }
      evaluations += sub.size;
      continue;
    }
    // Children: the nearer one on top of the stack, so it is summed first.
    const int left = id + 1, right = node.right;
    if (box_distance(o, nodes[static_cast<size_t>(left)], d) <=
        box_distance(o, nodes[static_cast<size_t>(right)], d)) {
      stack[top++] = right;
      stack[top++] = left;
    } else {
      stack[top++] = left;
      stack[top++] = right;
    }
  }
  out.Gm = b_grad.low;
  out.G2m = b_g2.low;
  return out;
}

}  // namespace softhd::detail
