// The global start of align() (a grid of rotations, principal axes, subsampled clouds) and
// its nearest-point finish (docs/formulation.md §8.5).

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <random>

#include "align_internal.hpp"
#include "softhd/parallel.hpp"

namespace softhd::scan::detail {

std::vector<Eigen::Matrix3d> rotation_grid(int count) {
  // Super-Fibonacci spiral on the unit quaternions: for s = i + 1/2, r = √(s/n),
  // R = √(1 − s/n), α = 2π s/φ, β = 2π s/ψ (φ = √2, ψ the root of ψ⁴ = ψ + 4),
  // q = (r sin α, r cos α, R sin β, R cos β): near-uniform and deterministic.
  const double phi = std::sqrt(2.0), psi = 1.533751168755204288118041;
  std::vector<Eigen::Matrix3d> out;
  out.reserve(static_cast<size_t>(count));
  for (int i = 0; i < count; ++i) {
    const double s = i + 0.5, r = std::sqrt(s / count), R = std::sqrt(1.0 - s / count);
    const double a = 2.0 * M_PI * s / phi, b = 2.0 * M_PI * s / psi;
    const Eigen::Quaterniond q(R * std::cos(b), r * std::sin(a), r * std::cos(a), R * std::sin(b));
    out.push_back(q.normalized().toRotationMatrix());
  }
  return out;
}

Eigen::Matrix3d principal_axes(const Eigen::MatrixXd& points) {
  const Eigen::RowVector3d mean = points.colwise().mean();
  const Eigen::MatrixXd centred = points.rowwise() - mean;
  const Eigen::Matrix3d C = centred.transpose() * centred / static_cast<double>(points.rows());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(C);
  Eigen::Matrix3d axes = eig.eigenvectors().rowwise().reverse();  // descending eigenvalues
  if (axes.determinant() < 0) axes.col(2) = -axes.col(2);
  return axes;
}

std::vector<Eigen::Index> subsample(Eigen::Index rows, Eigen::Index count, unsigned seed) {
  std::vector<Eigen::Index> index(static_cast<size_t>(rows));
  for (Eigen::Index i = 0; i < rows; ++i) index[static_cast<size_t>(i)] = i;
  if (count >= rows) return index;
  std::mt19937_64 gen(seed);  // partial Fisher–Yates: the first `count` of a shuffle
  for (Eigen::Index i = 0; i < count; ++i) {
    const auto span = static_cast<std::uint64_t>(rows - i);
    const auto j = i + static_cast<Eigen::Index>(gen() % span);
    std::swap(index[static_cast<size_t>(i)], index[static_cast<size_t>(j)]);
  }
  index.resize(static_cast<size_t>(count));
  std::sort(index.begin(), index.end());
  return index;
}

Pose fit_pose(const Eigen::MatrixXd& from, const Eigen::MatrixXd& to, bool similarity, double s_min,
              double s_max) {
  // Umeyama: with means a, b and Σ = (1/n) Σ (b_k − b)(a_k − a)ᵀ = U D Vᵀ,
  // R = U S Vᵀ (S = diag(1, 1, det U Vᵀ)), s = tr(D S) / ((1/n) Σ |a_k − a|²), t = b − s R a.
  const Eigen::RowVector3d a = from.colwise().mean(), b = to.colwise().mean();
  const Eigen::MatrixXd A = from.rowwise() - a, B = to.rowwise() - b;
  const double n = static_cast<double>(from.rows());
  const Eigen::Matrix3d S = B.transpose() * A / n;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(S, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d sign(1.0, 1.0, 1.0);
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0) sign[2] = -1.0;
  Pose p;
  p.R = svd.matrixU() * sign.asDiagonal() * svd.matrixV().transpose();
  if (similarity) {
    const double var = A.squaredNorm() / n;
    p.s = var > 0 ? std::clamp(svd.singularValues().dot(sign) / var, s_min, s_max) : 1.0;
  }
  p.t = b.transpose() - p.s * (p.R * a.transpose());
  return p;
}

Pose nearest_refinement(const NearestPoints& body, const Eigen::MatrixXd& body_points,
                        const Eigen::MatrixXd& scan, Pose P, const AlignOptions& options,
                        const FixtureConstraint* fixture, double size, int* iterations) {
  const bool similarity = options.kind == PoseKind::similarity;
  std::vector<Eigen::Index> index;
  Eigen::VectorXd dist;
  for (*iterations = 0; *iterations < options.nearest_iterations; ++*iterations) {
    body.nearest(apply_points(P, scan), &index, &dist, options.threads);
    Eigen::VectorXd sorted = dist;
    std::nth_element(sorted.data(), sorted.data() + sorted.size() / 2,
                     sorted.data() + sorted.size());
    const double keep = 3.0 * sorted[sorted.size() / 2] + 1e-15 * size;
    std::vector<Eigen::Index> pairs;
    for (Eigen::Index j = 0; j < scan.rows(); ++j)
      if (dist[j] <= keep) pairs.push_back(j);
    if (pairs.size() < 3) break;
    Eigen::MatrixXd from(static_cast<Eigen::Index>(pairs.size()), 3), to(from.rows(), 3);
    for (Eigen::Index k = 0; k < from.rows(); ++k) {
      from.row(k) = scan.row(pairs[static_cast<size_t>(k)]);
      to.row(k) = body_points.row(index[static_cast<size_t>(pairs[static_cast<size_t>(k)])]);
    }
    const Pose next = fixture != nullptr
                          ? fixture->fit(from, to)
                          : fit_pose(from, to, similarity, options.scale_min, options.scale_max);
    const double change = rotation_angle_between(next.R, P.R) * size + (next.t - P.t).norm() +
                          std::abs(next.s - P.s) * size;
    P = next;
    if (change <= options.tolerance * size) {
      ++*iterations;
      break;
    }
  }
  return P;
}

}  // namespace softhd::scan::detail
