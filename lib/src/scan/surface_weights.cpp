// Surface weights of a scan (docs/formulation.md §8.9): k-nearest-neighbour areas and
// tangent-plane Voronoi cells.

#include "softhd/scan/surface_weights.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "neighbours.hpp"
#include "softhd/enum_names.hpp"
#include "softhd/error.hpp"

namespace softhd::scan {

namespace {

constexpr auto kAreaEstimateNames = enum_sequence<AreaEstimate::delaunay>({"knn", "delaunay"});

// knn: a surface A = π r_k² / k, a curve L = 2 r_k / k (for a Poisson sample of density ρ,
// π r_k² ρ is Gamma(k, 1)-distributed, so its mean is k/ρ: the estimate of 1/ρ is unbiased).
double knn_area(double r_k, int k, int dim) {
  return dim == 3 ? M_PI * r_k * r_k / k : 2.0 * r_k / k;
}

// The unit vectors of the neighbourhood's principal axes (columns), largest variance first:
// the last column is the normal (3D) or the curve's normal (2D). Fixed-size: no allocation.
template <int D>
Eigen::Matrix<double, D, D> principal_axes(const Eigen::MatrixXd& x, Eigen::Index i,
                                           const Eigen::Index* nb, int k) {
  using Vec = Eigen::Matrix<double, D, 1>;
  const Vec xi = x.row(i).transpose();
  Vec c = xi;
  for (int m = 0; m < k; ++m) c += x.row(nb[m]).transpose();
  c /= double(k + 1);
  Eigen::Matrix<double, D, D> s = (xi - c) * (xi - c).transpose();
  for (int m = 0; m < k; ++m) {
    const Vec e = x.row(nb[m]).transpose() - c;
    s.noalias() += e * e.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, D, D>> eig(s);
  return eig.eigenvectors().rowwise().reverse();  // eigenvalues were in increasing order
}

// Clips the convex polygon `poly` to the half-plane a·q ≤ b (Sutherland–Hodgman), into `out`.
void clip(const std::vector<Eigen::Vector2d>& poly, const Eigen::Vector2d& a, double b,
          std::vector<Eigen::Vector2d>& out) {
  out.clear();
  const size_t n = poly.size();
  for (size_t v = 0; v < n; ++v) {
    const Eigen::Vector2d& p = poly[v];
    const Eigen::Vector2d& q = poly[(v + 1) % n];
    const double fp = a.dot(p) - b, fq = a.dot(q) - b;
    if (fp <= 0.0) out.push_back(p);
    if ((fp < 0.0 && fq > 0.0) || (fp > 0.0 && fq < 0.0))
      out.push_back(p + (fp / (fp - fq)) * (q - p));
  }
}

// Shoelace: area = ½ |Σ p_v × p_{v+1}|.
double polygon_area(const std::vector<Eigen::Vector2d>& poly) {
  double twice = 0.0;
  for (size_t v = 0; v < poly.size(); ++v) {
    const Eigen::Vector2d& p = poly[v];
    const Eigen::Vector2d& q = poly[(v + 1) % poly.size()];
    twice += p.x() * q.y() - p.y() * q.x();
  }
  return 0.5 * std::abs(twice);
}

// Surface: the tangent plane from the k nearest neighbours; with p_j the `candidates` nearest
// projected on it (the point at 0), the Voronoi cell {q : q·p_j ≤ |p_j|²/2 ∀j} inside the
// square |q|_∞ ≤ r_k; its area (a border point's: see below). A candidate with |p_j|/2 beyond the
// cell's farthest vertex cannot cut it. `poly` and `next` are the caller's scratch.
double voronoi_area(const Eigen::MatrixXd& x, Eigen::Index i, const Eigen::Index* nb,
                    const double* dist, int k, int candidates, std::vector<Eigen::Vector2d>& poly,
                    std::vector<Eigen::Vector2d>& next) {
  const Eigen::Matrix3d axes = principal_axes<3>(x, i, nb, k);
  const double r = dist[k - 1];
  poly = {{-r, -r}, {r, -r}, {r, r}, {-r, r}};
  double reach2 = 2.0 * r * r;  // the farthest vertex's |q|², an upper bound
  for (int m = 0; m < candidates && !poly.empty(); ++m) {
    const Eigen::Vector3d e = (x.row(nb[m]) - x.row(i)).transpose();
    const Eigen::Vector2d p(e.dot(axes.col(0)), e.dot(axes.col(1)));
    const double p2 = p.squaredNorm();
    if (!(p2 > 0.0) || 0.25 * p2 >= reach2) continue;  // a duplicate or too far to cut
    clip(poly, p, 0.5 * p2, next);
    poly.swap(next);
    reach2 = 0.0;
    for (const Eigen::Vector2d& v : poly) reach2 = std::max(reach2, v.squaredNorm());
  }
  // A point on the border of an open scan: its cell reaches the square (no neighbour bounds
  // it outwards). Its area is twice its cell's inward half, the half on the side of its k
  // nearest neighbours' centroid g: {q in the cell : g·q ≥ 0}.
  bool border = false;
  for (const Eigen::Vector2d& v : poly)
    border = border || v.cwiseAbs().maxCoeff() >= r * (1 - 1e-9);
  if (!border) return polygon_area(poly);
  Eigen::Vector2d g = Eigen::Vector2d::Zero();
  for (int m = 0; m < k; ++m) {
    const Eigen::Vector3d e = (x.row(nb[m]) - x.row(i)).transpose();
    g += Eigen::Vector2d(e.dot(axes.col(0)), e.dot(axes.col(1)));
  }
  clip(poly, -g, 0.0, next);
  return 2.0 * polygon_area(next);
}

// Curve: the tangent from the k nearest neighbours, s_j the candidates' coordinates along it; the
// cell [max_{s<0} s/2, min_{s>0} s/2], an end point's missing side mirrored from the other.
double voronoi_length(const Eigen::MatrixXd& x, Eigen::Index i, const Eigen::Index* nb, int k,
                      int candidates) {
  const Eigen::Matrix2d axes = principal_axes<2>(x, i, nb, k);
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double left = kInf, right = kInf;  // half-gaps to the nearest neighbour on each side
  for (int m = 0; m < candidates; ++m) {
    const Eigen::Vector2d e = (x.row(nb[m]) - x.row(i)).transpose();
    const double s = e.dot(axes.col(0));
    if (s > 0.0) right = std::min(right, 0.5 * s);
    if (s < 0.0) left = std::min(left, -0.5 * s);
  }
  if (left == kInf) left = right;
  if (right == kInf) right = left;
  return left == kInf ? 0.0 : left + right;
}

}  // namespace

std::string to_string(AreaEstimate estimate) { return enum_name(kAreaEstimateNames, estimate); }

AreaEstimate area_estimate_from_string(const std::string& name) {
  return enum_from_name(kAreaEstimateNames, name, "area estimate");
}

Eigen::VectorXd area_weights(const PointCloud& cloud, AreaEstimate estimate, int neighbours) {
  const int d = cloud.dim();
  const int least = estimate == AreaEstimate::delaunay ? d : 1;
  if (neighbours < least || neighbours >= cloud.size())
    throw InvalidArgument("area_weights: neighbours must be from " + std::to_string(least) +
                          " to N - 1 = " + std::to_string(cloud.size() - 1) + ", got " +
                          std::to_string(neighbours));
  // The Voronoi cell's bounding neighbours are not always among the k nearest (in a density
  // gradient, the sparse side's are farther): it clips with 3k candidates.
  const Eigen::Index n = cloud.size();
  const int k = neighbours;
  const int candidates =
      estimate == AreaEstimate::knn ? k : static_cast<int>(std::min<Eigen::Index>(3 * k, n - 1));
  const detail::Neighbours nb = detail::nearest_neighbours(cloud.points(), candidates);
  Eigen::VectorXd area(n);
#pragma omp parallel
  {
    std::vector<Eigen::Vector2d> poly, next;
    poly.reserve(static_cast<size_t>(candidates) + 4);
    next.reserve(static_cast<size_t>(candidates) + 4);
#pragma omp for schedule(static)
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::Index* idx = &nb.index[static_cast<size_t>(i) * candidates];
      const double* dist = &nb.distance[static_cast<size_t>(i) * candidates];
      if (estimate == AreaEstimate::knn)
        area[i] = knn_area(dist[k - 1], k, d);
      else
        area[i] = d == 3 ? voronoi_area(cloud.points(), i, idx, dist, k, candidates, poly, next)
                         : voronoi_length(cloud.points(), i, idx, k, candidates);
    }
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    if (!(area[i] > 0.0) || !std::isfinite(area[i]))
      throw InvalidArgument("area_weights: point " + std::to_string(i) +
                            " has no area (its neighbours coincide with it); raise neighbours");
  }
  return area;
}

PointCloud with_area_weights(const PointCloud& cloud, AreaEstimate estimate, int neighbours) {
  return PointCloud(cloud.points(), area_weights(cloud, estimate, neighbours));
}

}  // namespace softhd::scan
