#pragma once
// Pieces of align() (internal): the objective on one level of detail, its local minimiser
// over a twist, the rotation grid of the global start, and the nearest-point refinement
// (docs/formulation.md §8.5).

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "../common/surface_bvh.hpp"
#include "../hausdorff/nearest_index.hpp"
#include "softhd/hausdorff.hpp"
#include "softhd/scan/align.hpp"
#include "softhd/scan/pose.hpp"

namespace softhd::scan::detail {

/// ρ̃ between the body moved into the scan's frame (moving cloud X = Q(body), Q = P⁻¹) and the
/// scan (target Y, fixed in its own frame: its trees are built once, in the constructor).
/// Volumes are the body's own (ρ̃ uses V_i/|X|, which a scale leaves unchanged).
class PoseObjective {
 public:
  PoseObjective(const Eigen::MatrixXd& body, const Eigen::VectorXd& body_volumes,
                const PointCloud& scan, const HausdorffOptions& distance, DistanceForm form);
  /// ρ̃ at Q and its twist gradient (scan::pose_distance).
  double value(const Pose& Q, Eigen::VectorXd* gradient, Eigen::Vector3d* centre) const;
  const HausdorffTarget& target() const { return target_; }

 private:
  PointCloud body_;
  HausdorffTarget target_;
  DistanceForm form_;
};

/// The pose after a twist δ = (ω, v, σ) about the centre c: z ↦ c + e^σ exp([ω]×)(z − c) + v
/// applied after Q.
Pose twist_step(const Pose& Q, const Eigen::VectorXd& delta, const Eigen::Vector3d& centre);

using LocalSettings = LocalPoseSettings;
using LocalResult = LocalPoseResult;

/// scan::minimise_pose on a PoseObjective.
LocalResult minimise_pose(const PoseObjective& objective, const Pose& start,
                          const LocalSettings& settings);

/// `count` rotations spread over SO(3) (a super-Fibonacci spiral of unit quaternions).
std::vector<Eigen::Matrix3d> rotation_grid(int count);

/// The principal axes (columns, eigenvalues descending, det +1) of the rows of `points`.
Eigen::Matrix3d principal_axes(const Eigen::MatrixXd& points);

/// `count` rows of `points` (all if fewer), chosen by a seeded shuffle: deterministic.
std::vector<Eigen::Index> subsample(Eigen::Index rows, Eigen::Index count, unsigned seed);

/// Nearest neighbours among the rows of a fixed N by 3 matrix (a k-d tree built once; the
/// matrix must outlive it).
using NearestPoints = softhd::detail::NearestIndex;

/// The body's surface (AlignOptions::body_triangles over the body's points): closest points,
/// their distances and the surface's normals there (its hierarchy built once).
using BodySurface = softhd::detail::SurfaceDistance;

/// The body's surface of `options` (null if it has no triangles); InvalidArgument naming
/// body_triangles for triangles that do not name the body's points or do not close a surface.
std::unique_ptr<BodySurface> make_body_surface(const PointCloud& body, const AlignOptions& options);

/// The score align() chooses its candidate by (docs/formulation.md §8.5): with the camera at
/// the scan frame's origin, the body points a pose Q puts nearest the camera in their pixel
/// (over the pixels that hold scan points) should lie on the scan, and every scan point on
/// the body. S(Q) = ½ [mean_j min(d(y_j, Q(B)), c) + mean_{x∈V} min(d(x, Y), c)] / (s_Q L),
/// c = truncation · s_Q L: dimensionless, 0 for a perfect fit. Exact nearest distances (k-d
/// trees built once); no gradient (it only ranks local minima).
class CoverageScore {
 public:
  /// With a surface (not null; it must outlive the score), d(y_j, Q(B)) is the distance to it.
  CoverageScore(const Eigen::MatrixXd& body, const Eigen::MatrixXd& scan, double size,
                double truncation, int threads, const BodySurface* surface = nullptr);
  double value(const Pose& Q) const;

 private:
  Eigen::Index pixel_of(const Eigen::Vector3d& p) const;  ///< −1 outside the image
  Eigen::MatrixXd body_, scan_;
  double size_, truncation_;
  int threads_;
  NearestPoints body_tree_, scan_tree_;
  const BodySurface* surface_ = nullptr;
  Eigen::Vector3d e1_, e2_, e3_;
  double pixel_ = 1.0, depth_tolerance_ = 0.0, lo_u_ = 0.0, lo_v_ = 0.0;
  Eigen::Index nu_ = 0, nv_ = 0;
  std::vector<char> footprint_;  ///< nu × nv: 1 where a scan point falls
};

/// The refined candidate (Q: body → scan frame) align() continues from: the lowest ρ̃ (score
/// rho), or (score coverage) the lowest CoverageScore after each candidate is taken by
/// nearest_refinement (its pose replaced by the fitted one); ties: the first.
/// With a fixture (not null), the nearest-point fits keep its constraint. With the body's
/// surface (not null), every candidate is fitted (to the surface), and score rho compares the
/// scan's mean distance to the surface, each capped at score_truncation × L, instead of ρ̃.
size_t choose_candidate(const PointCloud& body, const PointCloud& scan, double size,
                        const AlignOptions& options, const FixtureConstraint* fixture,
                        const BodySurface* surface, std::vector<LocalResult>* refined);

/// The least-squares pose (rigid, or a similarity with s clamped to [s_min, s_max]) taking
/// the rows `from` onto the rows `to` (Kabsch/Umeyama via the SVD of the cross-covariance).
Pose fit_pose(const Eigen::MatrixXd& from, const Eigen::MatrixXd& to, bool similarity, double s_min,
              double s_max);

/// Iterated nearest-point fit of the scan onto the body (P the scan's pose): pairs each moved
/// scan point with its nearest body point, keeps the pairs within 3× the median distance and
/// fits the pose to them (fit_pose; with a fixture, not null, FixtureConstraint::fit), until the
/// pose stops changing. With the body's surface (not null): surface_refinement.
Pose nearest_refinement(const NearestPoints& body, const Eigen::MatrixXd& body_points,
                        const BodySurface* surface, const Eigen::MatrixXd& scan, Pose P,
                        const AlignOptions& options, const FixtureConstraint* fixture, double size,
                        int* iterations);

/// The point-to-plane fit of the scan onto the body's surface (P the scan's pose), Gauss–Newton
/// on Σ_j sd(P y_j)² over the pairs within 3× the median distance (sd the signed distance to
/// the surface, its gradient n̂_j the face normal at the closest point), a twist about the
/// pairs' centroid per step, halved until the trimmed sum decreases, until a step moves no
/// point more than tolerance × size (at most nearest_iterations steps). With a fixture (not
/// null) the twist is kept in table_tangent(n_b): a turn about the table's normal and a shift
/// along it, so every pose keeps the constraint.
Pose surface_refinement(const BodySurface& surface, const Eigen::MatrixXd& scan, Pose P,
                        const AlignOptions& options, const FixtureConstraint* fixture, double size,
                        int* iterations);

/// The mean over the scan's points of min(d(P y_j, surface), cap) (the true distance).
double mean_surface_distance(const BodySurface& surface, const Eigen::MatrixXd& scan, const Pose& P,
                             double cap, int threads);

}  // namespace softhd::scan::detail
