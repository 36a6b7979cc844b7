#pragma once
/// \file align.hpp
/// Finding a scan's pose by the distance itself (docs/formulation.md §8): minimise ρ̃ (in the
/// chosen form: symmetric, scan_to_body, visible; with or without the soft cap) over a twist
/// about the moved scan's centroid, with the exact gradient from ∂ρ̃/∂y_j, after a global
/// start over a grid of rotations (and the principal-axis variants) evaluated cheaply on
/// subsampled clouds with a larger ε, its poses ranked by a coverage score that tells a
/// flipped one-sided view from the true one (CandidateScore).

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <string>

#include "softhd/hausdorff.hpp"
#include "softhd/scan/cleanup.hpp"  // Plane: the scan's table
#include "softhd/scan/fixture.hpp"
#include "softhd/scan/pose.hpp"
#include "softhd/scan/pose_map.hpp"  // PoseKind: what align() may change

namespace softhd::scan {

/// How align() compares the refined candidates of its global start (docs/formulation.md §8.5).
///   coverage: the coverage score S: the camera at the scan frame's origin, the body points
///             the pose shows it (over the scan's image) must lie on the scan and the scan
///             on the body; tells a flipped one-sided view from the true one.
///   rho:      ρ̃ on the candidate clouds (the camera unknown, e.g. a scan in another frame).
enum class CandidateScore { coverage, rho };
/// "coverage" / "rho".
std::string to_string(CandidateScore score);
/// The CandidateScore named "coverage" or "rho"; throws InvalidArgument naming `score` (for
/// the retired spelling "visible": naming "coverage").
CandidateScore candidate_score_from_string(const std::string& name);

/// Settings of align(); defaults documented per field and validated by validate().
struct AlignOptions {
  PoseKind kind = PoseKind::rigid;  ///< a rigid motion, or a similarity (with a scale s)
  double scale_min = 0.5;     ///< similarity only: bounds on s, 0 < scale_min ≤ 1 ≤ scale_max
  double scale_max = 2.0;     ///< see scale_min
  HausdorffOptions distance;  ///< the functional's parameters (ε: the finest level's) and method
  DistanceForm form;          ///< sides and cap (a visible mask is refused: align has no camera
                              ///< model of its own; use scan_to_body for partial views)
  /// A starting pose (scan → body): with global_start, one more candidate refined and compared
  /// with the global start's; without, the only start (none: the identity). Rigid for a rigid
  /// alignment (scale 1 to Pose::kScaleTolerance).
  std::optional<Pose> initial;
  bool global_start = true;  ///< search rotations first (else start at `initial`)
  int rotations = 48;        ///< global start: grid rotations tried (plus 4 principal-axis ones; 0:
                             ///< those 4 only)
  int coarse_points = 150;   ///< global start: points of each subsampled cloud
  double coarse_epsilon = 0.05;  ///< global start: ε as a fraction of the body's size L
  int keep = 4;                  ///< global start: best distinct poses refined further
  int candidate_points = 400;    ///< points of each cloud when the kept poses are refined
  CandidateScore score = CandidateScore::coverage;  ///< how the refined candidates are compared
  double score_truncation = 0.05;  ///< coverage score: nearest distances capped at this × L
  int refine_points = 1000;        ///< points of each cloud in the refinement (0: all)
  int max_iterations = 200;        ///< refinement iterations (per level)
  double tolerance = 1e-10;        ///< stop when a step moves no point more than this × L
  int nearest_iterations = 50;     ///< final nearest-point refinement iterations (0: none)
  /// The body's surface: outward triangles over the body's points (rows of `body`; e.g. a
  /// mesh's boundary triangles over its nodes, in the configuration the body is given in),
  /// closed and consistently oriented, no triangle of zero area. Empty (the default): the body
  /// is its points alone. With it, every nearest-point fit pairs a scan point with its closest
  /// point of the surface instead of the nearest body point, and the finish is the
  /// point-to-plane Gauss–Newton fit to convergence on every scan point (docs/formulation.md
  /// §8.5): a scan sampled anywhere on that surface, rigidly moved, is recovered to rounding;
  /// the residuals, overlap and rmse are distances to the surface.
  Eigen::Matrix<int, Eigen::Dynamic, 3> body_triangles;
  double inlier_distance = 0.01;  ///< the overlap's threshold as a fraction of L, in (0, 1)
  int threads = 0;                ///< as HausdorffOptions::threads
  /// The fixture (docs/formulation.md §8.12): the table in the body's frame. With it (and
  /// `table`), every pose tried keeps the table's tilt and height: the global start turns the
  /// body about the table's normal (`rotations` angles, evenly spaced) and slides it along the
  /// table, and the refinement and the nearest-point finish move only those 3 variables.
  /// Rigid alignments only. None: the pose is free.
  std::optional<Fixture> fixture;
  /// The scan's table in its own frame (find_dominant_plane of the scan before the table is
  /// removed); required with `fixture`, its normal's sign free (turned towards the scan's
  /// points).
  std::optional<Plane> table;
  /// Throws InvalidArgument naming the first invalid field.
  void validate() const;
};

/// Why align() stopped.
enum class AlignStatus { converged, iteration_limit, failed };
/// "converged", "iteration_limit" or "failed".
std::string to_string(AlignStatus status);

/// What align() found.
struct AlignSummary {
  AlignStatus status = AlignStatus::failed;  ///< why it stopped
  Pose pose;                                 ///< scan frame → body frame
  double rho = 0.0;                          ///< ρ̃ at the pose (the chosen form)
  double overlap = 0.0;          ///< fraction of scan points within `inlier_distance` of the body
  double inlier_distance = 0.0;  ///< the overlap's threshold (a length)
  double rmse = 0.0;             ///< RMS true nearest-neighbour distance of the overlapping points
  Eigen::VectorXd residuals;     ///< true nearest-neighbour distance of each moved scan point
  int iterations = 0;            ///< refinement iterations of the best candidate, over its levels
  int starts = 0;      ///< global start: starting poses tried (rotations + 4; 0 without it)
  int candidates = 0;  ///< candidates refined and compared (the kept starts, plus `initial`)
  Eigen::Index refine_body_points = 0;  ///< points of the body in the refinement
  Eigen::Index refine_scan_points = 0;  ///< points of the scan in the refinement
  double seconds = 0.0;                 ///< wall time of align()
  /// One line: status, rotation and translation of the pose, ρ̃, overlap, rmse, time.
  std::string BriefReport() const;
};

/// The size L of a body: the diagonal of its points' bounding box.
double body_size(const PointCloud& body);

/// Throws InvalidArgument starting with `what` unless the 3D cloud's points span a plane (the
/// centred points' covariance has rank ≥ 2: its second eigenvalue above 1e-12 times its
/// largest): a point, coincident or collinear points fix no pose (docs/formulation.md §8.5).
void check_fixes_pose(const PointCloud& cloud, const std::string& what);

/// ρ̃(Q(body), scan) in `form` (the body moved into the scan's frame by Q = P⁻¹, its volumes
/// unchanged) and, when `gradient` is not null, ∂ρ̃/∂δ of the twist δ = (ω, v[, σ]) about the
/// centroid c of Q(body), at δ = 0 (PoseMap::twist_gradient; 6 entries, or 7 if *gradient has
/// 7 on entry), with c in *centre: the objective of align()'s local refinement
/// (docs/formulation.md §8.5) and of the pose by variable projection (§8.11).
double pose_distance(const HausdorffTarget& scan, const PointCloud& body, const DistanceForm& form,
                     const Pose& Q, Eigen::VectorXd* gradient, Eigen::Vector3d* centre);

/// A pose objective for minimise_pose: its value at Q (body → scan frame) and, when `gradient`
/// is not null, the twist gradient about *centre (as pose_distance).
using PoseFunction =
    std::function<double(const Pose& Q, Eigen::VectorXd* gradient, Eigen::Vector3d* centre)>;

/// Settings of minimise_pose (docs/formulation.md §8.5).
struct LocalPoseSettings {
  int max_iterations = 200;       ///< BFGS iterations
  double step_tolerance = 1e-10;  ///< stop when a step moves no point more than this × size
  double size = 1.0;              ///< the body's size L (scales ω and σ into lengths)
  bool similarity = false;        ///< the twist has σ (a scale) too
  double log_scale_min = 0.0;     ///< similarity: bounds on log s of Q (the inverse pose)
  double log_scale_max = 0.0;     ///< see log_scale_min
  double first_step = 0.05;       ///< the first step moves no point more than this × size
  int max_backtracks = 40;        ///< halvings of a step before "no decrease left"
  /// If set: the nearest feasible pose to a trial pose (a projection onto a convex set of
  /// poses, e.g. a bound on the twist from a calibrated pose); every trial is replaced by it and
  /// the step taken is the twist from the current pose to it. The start must be feasible.
  std::function<Pose(const Pose&)> feasible;
  /// If not empty: an orthonormal basis (n × k, its columns) of the scaled twists
  /// u = (L ω, v[, L σ]) the steps may take (a constraint's tangent, FixtureConstraint::tangent):
  /// the gradient is projected onto its span, so every step stays in it.
  Eigen::MatrixXd subspace;
};

/// What minimise_pose found.
struct LocalPoseResult {
  Pose pose;               ///< the last accepted pose Q
  double rho = 0.0;        ///< the objective there
  int iterations = 0;      ///< accepted BFGS iterations
  int evaluations = 0;     ///< of the objective after the first (each with its gradient)
  bool converged = false;  ///< stopped by the step tolerance or no decrease left
};

/// BFGS on the twist u = (L ω, v, L σ) about the moved cloud's centroid, re-based at each
/// accepted pose, with an Armijo backtracking line search; the scale clamped to its bounds
/// (docs/formulation.md §8.5, "The minimiser").
LocalPoseResult minimise_pose(const PoseFunction& objective, const Pose& start,
                              const LocalPoseSettings& settings);

/// The pose that takes `scan` (camera frame) onto `body` (body frame). Throws InvalidArgument
/// for invalid options, non-3D clouds or a body or scan that fixes no pose (check_fixes_pose).
AlignSummary align(const PointCloud& body, const PointCloud& scan, const AlignOptions& options);

}  // namespace softhd::scan
