// The global start of align() (a grid of rotations, principal axes, subsampled clouds) and
// its nearest-point finish (docs/formulation.md §8.5).

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <string>

#include "align_internal.hpp"
#include "softhd/error.hpp"
#include "softhd/parallel.hpp"

namespace softhd::scan::detail {

using softhd::detail::SignedDistance;

std::unique_ptr<BodySurface> make_body_surface(const PointCloud& body,
                                               const AlignOptions& options) {
  const auto& T = options.body_triangles;
  if (T.rows() == 0) return nullptr;
  if (T.minCoeff() < 0 || T.maxCoeff() >= body.size())
    throw InvalidArgument("align: body_triangles must name the body's points (0 to " +
                          std::to_string(body.size() - 1) + "), got " +
                          std::to_string(T.minCoeff()) + " to " + std::to_string(T.maxCoeff()));
  try {
    return std::make_unique<BodySurface>(TriangleSurface{body.points(), T});
  } catch (const InvalidArgument& e) {
    throw InvalidArgument(std::string("align: body_triangles: ") + e.what());
  }
}

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

namespace {

/// The pairs' trimming distance: 3× the median of `dist`, plus 1e-15 × size (so an exact fit,
/// all distances at rounding, keeps its pairs).
double trimming_distance(const Eigen::VectorXd& dist, double size) {
  Eigen::VectorXd sorted = dist;
  std::nth_element(sorted.data(), sorted.data() + sorted.size() / 2, sorted.data() + sorted.size());
  return 3.0 * sorted[sorted.size() / 2] + 1e-15 * size;
}

/// The closest points of the surface to the rows of x (serial within, OpenMP over rows).
std::vector<SignedDistance> closest_of(const BodySurface& surface, const Eigen::MatrixXd& x,
                                       int threads) {
  return surface.at_rows(x, resolve_threads(threads));
}

/// Σ_j min(sd_j², keep²): the point-to-surface fit's trimmed objective.
double trimmed_squares(const std::vector<SignedDistance>& q, double keep) {
  double sum = 0.0;
  for (const SignedDistance& d : q) sum += std::min(d.sd * d.sd, keep * keep);
  return sum;
}

/// The Gauss–Newton step of Σ_j sd_j² over the pairs within `keep`, in the scaled twist
/// u = (L ω, v, L σ) about their centroid *c: sd_j(δ) ≈ sd_j + n̂_j·(ω × (x_j − c) + v +
/// σ (x_j − c)), so J_j = (((x_j − c) × n̂_j)/L, n̂_j, n̂_j·(x_j − c)/L) and u = −J⁺ sd (the
/// least-squares solution of least norm: a surface that does not fix a motion leaves it be).
Eigen::VectorXd gauss_newton_step(const Eigen::MatrixXd& x, const std::vector<SignedDistance>& q,
                                  double keep, double L, bool similarity,
                                  const Eigen::MatrixXd& subspace, Eigen::Vector3d* c) {
  const int n = similarity ? 7 : 6;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Index count = 0;
  for (Eigen::Index j = 0; j < x.rows(); ++j)
    if (std::abs(q[static_cast<size_t>(j)].sd) <= keep) sum += x.row(j).transpose(), ++count;
  *c = sum / static_cast<double>(std::max<Eigen::Index>(count, 1));
  Eigen::MatrixXd J(count, n);
  Eigen::VectorXd r(count);
  for (Eigen::Index j = 0, k = 0; j < x.rows(); ++j) {
    const SignedDistance& d = q[static_cast<size_t>(j)];
    if (!(std::abs(d.sd) <= keep)) continue;
    const Eigen::Vector3d a = x.row(j).transpose() - *c, g = d.gradient;
    J.block<1, 3>(k, 0) = a.cross(g).transpose() / L;
    J.block<1, 3>(k, 3) = g.transpose();
    if (similarity) J(k, 6) = g.dot(a) / L;
    r[k++] = d.sd;
  }
  if (subspace.size() == 0) return -J.completeOrthogonalDecomposition().solve(r);
  // u = B z in the span of B's columns (the fixture's tangent): min |J B z + sd|².
  return -subspace * Eigen::MatrixXd(J * subspace).completeOrthogonalDecomposition().solve(r);
}

}  // namespace

double mean_surface_distance(const BodySurface& surface, const Eigen::MatrixXd& scan, const Pose& P,
                             double cap, int threads) {
  const std::vector<SignedDistance> q = closest_of(surface, apply_points(P, scan), threads);
  double sum = 0.0;
  for (const SignedDistance& d : q) sum += std::min(std::abs(d.sd), cap);
  return sum / static_cast<double>(std::max<size_t>(q.size(), 1));
}

Pose surface_refinement(const BodySurface& surface, const Eigen::MatrixXd& scan, Pose P,
                        const AlignOptions& options, const FixtureConstraint* fixture, double size,
                        int* iterations) {
  const bool similarity = options.kind == PoseKind::similarity;
  // With a fixture, twists of P (on the left, body frame) that keep every height along n_b.
  const Eigen::MatrixXd subspace =
      fixture != nullptr ? table_tangent(fixture->body_normal()) : Eigen::MatrixXd();
  std::vector<SignedDistance> q = closest_of(surface, apply_points(P, scan), options.threads);
  for (*iterations = 0; *iterations < options.nearest_iterations; ++*iterations) {
    Eigen::VectorXd dist(static_cast<Eigen::Index>(q.size()));
    for (size_t j = 0; j < q.size(); ++j) dist[static_cast<Eigen::Index>(j)] = std::abs(q[j].sd);
    const double keep = trimming_distance(dist, size), merit = trimmed_squares(q, keep);
    Eigen::Vector3d c;
    const Eigen::VectorXd u =
        gauss_newton_step(apply_points(P, scan), q, keep, size, similarity, subspace, &c);
    // Halve the step until the trimmed sum does not increase (at most 30 times).
    bool accepted = false;
    double alpha = 1.0;
    Pose trial;
    std::vector<SignedDistance> q_trial;
    for (int k = 0; k < 30 && !accepted; ++k, alpha *= 0.5) {
      Eigen::VectorXd delta = alpha * u;
      delta.head<3>() /= size;
      if (similarity) delta[6] /= size;
      trial = twist_step(P, delta, c);
      if (similarity) trial.s = std::clamp(trial.s, options.scale_min, options.scale_max);
      q_trial = closest_of(surface, apply_points(trial, scan), options.threads);
      accepted = trimmed_squares(q_trial, keep) <= merit;
      if (accepted) break;
    }
    if (!accepted) break;  // no decrease left at double precision
    const double change = rotation_angle_between(trial.R, P.R) * size + (trial.t - P.t).norm() +
                          std::abs(trial.s - P.s) * size;
    P = trial;
    q = std::move(q_trial);
    if (change <= options.tolerance * size) {
      ++*iterations;
      break;
    }
  }
  return P;
}

Pose nearest_refinement(const NearestPoints& body, const Eigen::MatrixXd& body_points,
                        const BodySurface* surface, const Eigen::MatrixXd& scan, Pose P,
                        const AlignOptions& options, const FixtureConstraint* fixture, double size,
                        int* iterations) {
  if (surface != nullptr)
    return surface_refinement(*surface, scan, P, options, fixture, size, iterations);
  const bool similarity = options.kind == PoseKind::similarity;
  std::vector<Eigen::Index> index;
  Eigen::VectorXd dist;
  for (*iterations = 0; *iterations < options.nearest_iterations; ++*iterations) {
    body.nearest(apply_points(P, scan), &index, &dist, options.threads);
    const double keep = trimming_distance(dist, size);
    std::vector<Eigen::Index> pairs;
    for (Eigen::Index j = 0; j < scan.rows(); ++j)
      if (dist[j] <= keep) pairs.push_back(j);
    if (pairs.size() < 3) break;
    Eigen::MatrixXd from(static_cast<Eigen::Index>(pairs.size()), 3), to(from.rows(), 3);
    for (Eigen::Index k = 0; k < from.rows(); ++k) {
      const auto j = static_cast<size_t>(pairs[static_cast<size_t>(k)]);
      from.row(k) = scan.row(static_cast<Eigen::Index>(j));
      to.row(k) = body_points.row(index[j]);
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
