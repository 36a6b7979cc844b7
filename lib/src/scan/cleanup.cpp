// Scan clean-up (docs/formulation.md §8.8): crop, statistical outliers, dominant plane.

#include "softhd/scan/cleanup.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "neighbours.hpp"
#include "softhd/error.hpp"

namespace softhd::scan {

namespace {

void check_box(const PointCloud& cloud, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
               double margin) {
  if (lower.size() != cloud.dim() || upper.size() != cloud.dim())
    throw InvalidArgument("crop_to_box: lower and upper must have the cloud's dimension " +
                          std::to_string(cloud.dim()));
  if (!lower.allFinite() || !upper.allFinite() || (lower.array() > upper.array()).any())
    throw InvalidArgument("crop_to_box: lower and upper must be finite with lower <= upper");
  if (!std::isfinite(margin) || margin < 0.0)
    throw InvalidArgument("crop_to_box: margin must be finite and >= 0, got " +
                          std::to_string(margin));
}

// The plane through d points (rows `pick` of `x`): unit normal and offset, or a zero normal
// if they are (nearly) collinear. 3D: n ∝ (b − a) × (c − a); 2D: n ∝ (−(b − a)_y, (b − a)_x).
bool plane_through(const Eigen::MatrixXd& x, const Eigen::Index* pick, Eigen::VectorXd& n,
                   double& offset) {
  const int d = static_cast<int>(x.cols());
  const Eigen::VectorXd a = x.row(pick[0]).transpose();
  const Eigen::VectorXd u = x.row(pick[1]).transpose() - a;
  n.resize(d);
  if (d == 3) {
    const Eigen::VectorXd v = x.row(pick[2]).transpose() - a;
    n << u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0];
  } else {
    n << -u[1], u[0];
  }
  const double norm = n.norm();
  if (!(norm > 0.0)) return false;
  n /= norm;
  offset = n.dot(a);
  return true;
}

// |{i : |n·x_i − offset| ≤ distance}| (runs once per RANSAC sample: no allocation).
Eigen::Index count_inliers(const Eigen::MatrixXd& x, const Eigen::VectorXd& n, double offset,
                           double distance) {
  const int d = static_cast<int>(x.cols());
  Eigen::Index count = 0;
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    double r = -offset;
    for (int k = 0; k < d; ++k) r += n[k] * x(i, k);
    count += std::abs(r) <= distance;
  }
  return count;
}

// Least-squares plane of the rows with |n·x − offset| ≤ distance: through their centroid c,
// normal the eigenvector of the smallest eigenvalue of Σ (x − c)(x − c)ᵀ.
void refit(const Eigen::MatrixXd& x, double distance, Eigen::VectorXd& n, double& offset) {
  const int d = static_cast<int>(x.cols());
  const Eigen::VectorXd r = (x * n).array() - offset;
  Eigen::VectorXd c = Eigen::VectorXd::Zero(d);
  Eigen::Index m = 0;
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    if (std::abs(r[i]) <= distance) c += x.row(i).transpose(), ++m;
  }
  if (m < d) return;
  c /= static_cast<double>(m);
  Eigen::MatrixXd s = Eigen::MatrixXd::Zero(d, d);
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    if (std::abs(r[i]) > distance) continue;
    const Eigen::VectorXd e = x.row(i).transpose() - c;
    s.noalias() += e * e.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(s);
  n = eig.eigenvectors().col(0);  // eigenvalues in increasing order
  offset = n.dot(c);
}

// The sign convention of Plane::normal: its largest-magnitude component positive.
void orient(Eigen::VectorXd& n, double& offset) {
  Eigen::Index k = 0;
  n.cwiseAbs().maxCoeff(&k);
  if (n[k] < 0.0) n = -n, offset = -offset;
}

}  // namespace

std::vector<Eigen::Index> crop_to_box(const PointCloud& cloud, const Eigen::VectorXd& lower,
                                      const Eigen::VectorXd& upper, double margin) {
  check_box(cloud, lower, upper, margin);
  const double m = margin * (upper - lower).norm();
  const Eigen::MatrixXd& x = cloud.points();
  std::vector<Eigen::Index> kept;
  for (Eigen::Index i = 0; i < cloud.size(); ++i) {
    bool inside = true;
    for (int k = 0; k < cloud.dim(); ++k)
      inside = inside && x(i, k) >= lower[k] - m && x(i, k) <= upper[k] + m;
    if (inside) kept.push_back(i);
  }
  return kept;
}

std::vector<Eigen::Index> remove_statistical_outliers(const PointCloud& cloud, int k,
                                                      double ratio) {
  if (k < 1 || k >= cloud.size())
    throw InvalidArgument("remove_statistical_outliers: k must be from 1 to N - 1 = " +
                          std::to_string(cloud.size() - 1) + ", got " + std::to_string(k));
  if (!std::isfinite(ratio))
    throw InvalidArgument("remove_statistical_outliers: ratio must be finite");
  const detail::Neighbours nb = detail::nearest_neighbours(cloud.points(), k);
  const Eigen::Index n = cloud.size();
  // m_i = (1/k) Σ_{m<k} |x_i − x_{nb(i,m)}|
  Eigen::VectorXd mean_distance(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    double sum = 0.0;
    for (int m = 0; m < k; ++m) sum += nb.distance[static_cast<size_t>(i) * k + m];
    mean_distance[i] = sum / k;
  }
  // μ = mean of m, s² = Σ (m_i − μ)² / (N − 1); kept: m_i ≤ μ + ratio · s
  const double mu = mean_distance.mean();
  const double s =
      n > 1 ? std::sqrt((mean_distance.array() - mu).square().sum() / double(n - 1)) : 0.0;
  const double limit = mu + ratio * s;
  std::vector<Eigen::Index> kept;
  for (Eigen::Index i = 0; i < n; ++i) {
    if (mean_distance[i] <= limit) kept.push_back(i);
  }
  return kept;
}

void PlaneRemoval::validate() const {
  if (!std::isfinite(distance) || !(distance > 0.0))
    throw InvalidArgument("PlaneRemoval.distance must be finite and > 0, got " +
                          std::to_string(distance));
  if (iterations < 1)
    throw InvalidArgument("PlaneRemoval.iterations must be >= 1, got " +
                          std::to_string(iterations));
  if (!(min_fraction >= 0.0 && min_fraction <= 1.0))
    throw InvalidArgument("PlaneRemoval.min_fraction must be in [0, 1], got " +
                          std::to_string(min_fraction));
}

Plane find_dominant_plane(const PointCloud& cloud, const PlaneRemoval& options) {
  options.validate();
  const Eigen::MatrixXd& x = cloud.points();
  const Eigen::Index n = cloud.size();
  const int d = cloud.dim();
  Plane best;
  best.normal = Eigen::VectorXd::Zero(d);
  if (n < d) return best;
  // The samples are drawn serially (the same for any thread count), then scored in parallel.
  std::mt19937_64 rng(options.seed);
  std::vector<Eigen::Index> picks(static_cast<size_t>(options.iterations) * d);
  for (size_t s = 0; s < picks.size(); ++s) picks[s] = static_cast<Eigen::Index>(rng() % n);
  std::vector<Eigen::Index> counts(static_cast<size_t>(options.iterations), -1);
#pragma omp parallel for schedule(dynamic, 8)
  for (int it = 0; it < options.iterations; ++it) {
    Eigen::VectorXd normal;
    double offset = 0.0;
    if (plane_through(x, &picks[static_cast<size_t>(it) * d], normal, offset))
      counts[static_cast<size_t>(it)] = count_inliers(x, normal, offset, options.distance);
  }
  const auto winner = std::max_element(counts.begin(), counts.end());  // first of the best
  if (*winner < 0) return best;                                        // all samples degenerate
  plane_through(x, &picks[static_cast<size_t>(winner - counts.begin()) * d], best.normal,
                best.offset);
  for (int round = 0; round < 2; ++round) refit(x, options.distance, best.normal, best.offset);
  orient(best.normal, best.offset);
  best.inliers = count_inliers(x, best.normal, best.offset, options.distance);
  return best;
}

std::vector<Eigen::Index> remove_dominant_plane(const PointCloud& cloud,
                                                const PlaneRemoval& options) {
  const Plane plane = find_dominant_plane(cloud, options);
  const bool remove =
      plane.inliers > 0 && double(plane.inliers) >= options.min_fraction * double(cloud.size());
  std::vector<Eigen::Index> kept;
  for (Eigen::Index i = 0; i < cloud.size(); ++i) {
    const double r = plane.normal.dot(cloud.points().row(i).transpose()) - plane.offset;
    if (!remove || std::abs(r) > options.distance) kept.push_back(i);
  }
  return kept;
}

PointCloud select(const PointCloud& cloud, const std::vector<Eigen::Index>& indices) {
  if (indices.empty()) throw InvalidArgument("select: no points left");
  Eigen::MatrixXd points(static_cast<Eigen::Index>(indices.size()), cloud.dim());
  Eigen::VectorXd volumes(points.rows());
  for (Eigen::Index r = 0; r < points.rows(); ++r) {
    const Eigen::Index i = indices[static_cast<size_t>(r)];
    if (i < 0 || i >= cloud.size())
      throw InvalidArgument("select: index " + std::to_string(i) + " out of range");
    points.row(r) = cloud.points().row(i);
    volumes[r] = cloud.volumes()[i];
  }
  return PointCloud(std::move(points), std::move(volumes));
}

void ScanCleanup::validate() const {
  if (crop && !(std::isfinite(*crop) && *crop >= 0.0))
    throw InvalidArgument("clean.crop must be a finite margin >= 0, got " + std::to_string(*crop));
  if (plane && !(std::isfinite(*plane) && *plane > 0.0))
    throw InvalidArgument("clean.plane must be a finite distance > 0, got " +
                          std::to_string(*plane));
  if (outliers && outliers->k < 1)
    throw InvalidArgument("clean.outliers.k must be >= 1, got " + std::to_string(outliers->k));
  if (outliers && !std::isfinite(outliers->ratio))
    throw InvalidArgument("clean.outliers.ratio must be finite");
}

PointCloud clean_scan(const PointCloud& scan, const Eigen::VectorXd& lower,
                      const Eigen::VectorXd& upper, const ScanCleanup& cleanup,
                      std::vector<CleanupStep>* steps) {
  cleanup.validate();
  PointCloud current = scan;
  auto apply = [&](const char* name, const std::vector<Eigen::Index>& kept) {
    const Eigen::Index removed = current.size() - static_cast<Eigen::Index>(kept.size());
    if (steps != nullptr) steps->push_back({name, removed});
    if (kept.empty())
      throw InvalidArgument(std::string("no points left after the clean-up (") + name +
                            " removed the last " + std::to_string(removed) + ")");
    if (removed > 0) current = select(current, kept);
  };
  if (cleanup.crop) apply("crop", crop_to_box(current, lower, upper, *cleanup.crop));
  if (cleanup.plane) {
    PlaneRemoval options;
    options.distance = *cleanup.plane;
    apply("plane", remove_dominant_plane(current, options));
  }
  if (cleanup.outliers) {
    const ScanCleanup::Outliers& o = *cleanup.outliers;
    if (o.k >= current.size())
      throw InvalidArgument("clean.outliers.k = " + std::to_string(o.k) +
                            " needs more points than the " + std::to_string(current.size()) +
                            " left");
    apply("outliers", remove_statistical_outliers(current, o.k, o.ratio));
  }
  return current;
}

std::string describe(const std::vector<CleanupStep>& steps, Eigen::Index points) {
  std::string out;
  for (const CleanupStep& s : steps)
    out += (out.empty() ? "" : ", ") + s.name + " removed " + std::to_string(s.removed);
  return out + " of " + std::to_string(points) + " points";
}

}  // namespace softhd::scan
