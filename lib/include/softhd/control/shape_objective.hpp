#pragma once
/// \file shape_objective.hpp
/// The shape-tracking objective of docs/formulation.md §4.2 and its adjoint gradient:
///
///     J(m) = ρ̃_H(Φ_m(Ω₀), Ω_d) + (M/2)∫m² + (ε_m/2)∫|∇m|²
///
/// Φ_m(Ω₀) is the deformed body as a point cloud — its nodes, its quadrature points or its
/// boundary nodes — with the reference volumes (the paper's simplification) or the deformed ones
/// V_i = ∫ N_i J dX; the gradient is exact for the choice made:
///
///     g = ∂ρ̃/∂u (through the particle positions, and volumes if they move),
///     K λ = g on the free dofs (the converged tangent's factorisation),
///     dJ/dm_k = ∂J_reg/∂m_k + ∫ M_k (F a₀)·(∇λ a₀) dX.
///
/// With a pose (ShapeObjectiveOptions::pose, docs/formulation.md §8.10) the target stays in the
/// camera's frame and the moving cloud is mapped into it, x'_i = Q_ξ(x_i), by the twist ξ about
/// a fixed centre composed with the start; evaluate(m, gradient, ξ) returns dJ/dξ beside dJ/dm.

#include <Eigen/Core>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "softhd/control/moving_cloud.hpp"
#include "softhd/control/state_path.hpp"
#include "softhd/fe/assembly.hpp"
#include "softhd/fe/control.hpp"
#include "softhd/fe/newton.hpp"
#include "softhd/fe/state_equation.hpp"
#include "softhd/hausdorff.hpp"
#include "softhd/point_cloud.hpp"
#include "softhd/scan/pose.hpp"
#include "softhd/scan/pose_map.hpp"

namespace softhd {

/// How the pose of a target in the camera's frame is found (docs/formulation.md §8.10, §8.11).
enum class PoseMethod {
  /// The twist ξ joins the optimiser's variables: J(m, ξ), evaluate(m, gradient, ξ) returns
  /// dJ/dξ beside dJ/dm.
  joint,
  /// Variable projection: J(m) = min over ξ of ρ̃(Q_ξ(X(u(m))), Y) + J_reg(m); each evaluation
  /// minimises over ξ on its state (warm-started from the last evaluation's ξ), and dJ/dm is
  /// the adjoint at the optimal ξ (the envelope theorem).
  projection,
};
/// "joint" or "projection".
std::string to_string(PoseMethod method);
/// The PoseMethod named "joint" or "projection"; throws InvalidArgument naming `pose.method`.
PoseMethod pose_method_from_string(const std::string& name);

/// A bound on the projection's twist ξ = (ω, v) from the start pose (docs/formulation.md
/// §8.11): |ω| ≤ rotation (radians), |v| ≤ translation (a length: the displacement of the body's
/// centre in the scan's frame) — a calibrated camera's uncertainty.
struct PoseBound {
  double rotation = 0.0;     ///< radians, > 0
  double translation = 0.0;  ///< a length, > 0
};

/// Settings of the objective J(m) (docs/formulation.md §4.2, §4.3); defaults per field.
struct ShapeObjectiveOptions {
  /// α, β, γ, ε, method, threads, and the quadrature: collocation (default; the moving cloud
  /// against the target's points) or cells (docs/formulation.md §2.8: ρ̃ of the body's cells,
  /// deformed by u, against target_cells; particles and volumes then play no part, and the
  /// target's points only serve fields()). Cells need a 3D body and, for the symmetric form,
  /// target_cells; with form.sides scan_to_body and no target_cells the scan is a surface: the
  /// body's continuum J at its points, averaged with their volumes as surface weights
  /// (docs/formulation.md §2.8, "A scan's surface against the body's cells"). They do not yet
  /// support α, β, γ other than 4, 4, 2, the visible form, a cap, a camera, a pose, or
  /// second_order (InvalidArgument naming the field).
  HausdorffOptions hausdorff;
  Particles particles = Particles::nodes;                ///< moving cloud: nodes (paper)
  ParticleVolumes volumes = ParticleVolumes::reference;  ///< paper's simplification
  double tikhonov_mass = 0.0;                            ///< M ≥ 0 (paper: 0)
  double tikhonov_gradient = 0.0;                        ///< ε_m ≥ 0 (paper: 0)
  /// The distance's form in every evaluation (docs/formulation.md §8): symmetric (default),
  /// scan_to_body, visible, and the soft cap. For Sides::visible either a fixed mask over the
  /// moving cloud's points, or (with `camera`) none: every evaluation then marks the moving
  /// points seen from the camera (§8.7).
  DistanceForm form;
  /// Sides::visible only: the camera in the body's frame (then form.camera_mask is empty). The
  /// moving points marked are the boundary nodes scan::visible_points finds on the deformed
  /// boundary (fe::boundary_surface) — for particles = boundary the cloud's own points, for nodes
  /// the boundary nodes among them; quadrature points are refused. Held fixed in the gradient.
  std::optional<Eigen::Vector3d> camera;
  fe::NewtonOptions newton;   ///< state solver settings
  int warm_start_states = 8;  ///< converged states kept for warm starts (≥ 1)
  /// With a coarse level (ShapeObjective::use_coarse_level): the coarse-corrected start is
  /// used when the coarse solve to the new control needs at least this many Newton
  /// iterations (a large step); smaller steps keep the warm start and its path predictor,
  /// which is better for them (bending: 3 fine iterations instead of 5).
  int coarse_correction_iterations = 6;
  /// The target's frame (docs/formulation.md §8.10). Empty (default): the target is in the
  /// body's frame. Set: the target is in the camera's frame and this is the start P₀ (scan →
  /// body) of the joint pose; an evaluation at the twist ξ maps the moving cloud into the
  /// camera's frame by Q_ξ = T_ξ ∘ P₀⁻¹, T_ξ(z) = c + e^σ exp([ω]×)(z − c) + v, c = P₀⁻¹ of the
  /// rest cloud's centroid. Sides::visible then takes its camera from the pose (P_ξ's
  /// camera_position(); `camera` must be empty). 3D only.
  std::optional<scan::Pose> pose;
  /// With a pose: rigid (ξ = (ω, v), 6 variables) or similarity (ξ = (ω, v, σ), 7, σ = log of
  /// the scale change). Default rigid.
  scan::PoseKind pose_kind = scan::PoseKind::rigid;
  /// With a pose: joint (default) or projection (docs/formulation.md §8.11).
  PoseMethod pose_method = PoseMethod::joint;
  /// projection: the inner minimisation over ξ (scan::minimise_pose) stops when a step moves no
  /// point more than this × L (L the rest moving cloud's bounding-box diagonal; 1e-10), or when
  /// no step decreases ρ̃ at double precision, ...
  double pose_tolerance = 1e-10;
  /// ... or after this many BFGS iterations (100).
  int pose_iterations = 100;
  /// projection: the inner minimisation keeps ξ within this bound (none: unbounded).
  std::optional<PoseBound> pose_bound;
  /// projection: the fixture's table normal n_b in the body's frame (docs/formulation.md §8.12;
  /// not necessarily a unit vector). The inner minimisation then turns the body only about the
  /// table's normal and shifts it only along the table, keeping the start pose's tilt and
  /// height (ω along n_s = R₀ n_b, v ⊥ n_s, R₀ the start's rotation body → scan frame:
  /// scan::table_tangent). None (default): all 6 twist variables.
  std::optional<Eigen::Vector3d> pose_table_normal;
  /// Keep what ShapeObjective::hessian_product needs at each evaluation with the gradient (the
  /// distance's second-order quantities, HausdorffRequest::hessian_points). False (default):
  /// evaluations pay nothing for it. Needs reference volumes and no pose.
  bool second_order = false;
  /// hausdorff.quadrature cells only: the target as a body with cells, a 3D mesh (any cell
  /// type) with its nodes where the target is (SceneTarget::cells). Its hexahedra, boundary and
  /// kernel integrals are built once, when the objective is made.
  std::shared_ptr<const fe::Mesh> target_cells;

  /// Throws InvalidArgument naming the first invalid field (the distance's parameters and
  /// form, and the Newton options included). The visible mask's size is checked against the
  /// moving cloud at each evaluation.
  void validate() const;
};

/// How an evaluation of J(m) ended.
enum class EvaluationStatus {
  ok,            ///< J (and the gradient, if asked for) computed
  state_failed,  ///< the state solve did not converge: no J (ShapeEvaluation::failure says why)
};
/// "ok" or "state_failed".
std::string to_string(EvaluationStatus status);

/// One evaluation of J(m).
struct ShapeEvaluation {
  EvaluationStatus status = EvaluationStatus::state_failed;  ///< set to ok once J is computed
  double J = 0.0;                                            ///< ρ̃ + regularisation
  ///@{
  /// ρ̃, A and B of the deformed body against the target (docs/formulation.md §2.1).
  double rho = 0.0, A = 0.0, B = 0.0;
  ///@}
  double regularisation = 0.0;    ///< the Tikhonov terms of J
  Eigen::VectorXd gradient;       ///< dJ/dm (if requested and ok)
  Eigen::VectorXd pose_gradient;  ///< dJ/dξ (joint pose, if requested and ok; else empty)
  /// With a pose (if ok): the twist ξ the evaluation was made at — the given one (joint), or
  /// the inner minimisation's (projection); else empty.
  Eigen::VectorXd pose_twist;
  int pose_iterations = 0;    ///< projection: the inner minimisation's BFGS iterations
  int newton_iterations = 0;  ///< Newton iterations of the state solve
  int factorizations = 0;     ///< numeric factorisations of the state solve and the adjoint
  ///@{
  /// Wall time (seconds) of the state solve, the distance and the adjoint.
  double seconds_state = 0.0, seconds_distance = 0.0, seconds_adjoint = 0.0;
  ///@}
  std::string failure;  ///< for people: Newton's one-line report of a failed state solve
};

/// What one ShapeObjective::hessian_product cost.
struct HessianProductStats {
  /// The point's state, distance and adjoint were made again first (evaluations moved the
  /// state since, or m was not kept); the two below are that evaluation's.
  bool reestablished = false;
  int newton_iterations = 0;  ///< of the re-establishing solve (0 normally)
  int factorizations = 0;     ///< of the re-establishing solve and adjoint
  double seconds = 0.0;       ///< wall time of the product (re-establishing included)
};

/// J(m) and dJ/dm for one body, control space and target, as a composition: the state path
/// m ↦ u(m) (StatePath), the moving cloud u ↦ X(u) (MovingCloud), optionally the pose map
/// X ↦ Q_ξ(X) (scan::PoseMap), the distance form against the target (its trees built once),
/// plus the Tikhonov terms of the control space. Not thread-safe.
class ShapeObjective {
 public:
  /// The assembler and control space must outlive the objective; the state equation is
  /// solved by the serial Newton (fe::StateSolver) on them. Throws InvalidArgument for
  /// dimensions that differ or invalid options.
  ShapeObjective(const fe::Assembler& assembler, const fe::ControlSpace& control,
                 HausdorffTarget target, ShapeObjectiveOptions options = {});
  /// As above, with the state solver `make_solver` makes from the Newton options (once,
  /// with the absolute tolerance filled in; e.g. fe::state_solver_factory for a backend).
  /// The solver must solve the body of `assembler` with the controls of `control`; the
  /// objective uses it only through fe::StateEquation. With a PETSc solver every member
  /// of the objective is collective over the ranks.
  ShapeObjective(const fe::Assembler& assembler, const fe::ControlSpace& control,
                 HausdorffTarget target, ShapeObjectiveOptions options,
                 const fe::StateSolverFactory& make_solver);
  ~ShapeObjective();

  /// J(m) and, with `gradient`, dJ/dm; with a joint pose, at the twist ξ (pose()->variables()
  /// entries; empty: 0), and dJ/dξ too (exact, docs/formulation.md §8.10); with the projection,
  /// at the ξ that minimises ρ̃ on m's state from pose_warm_start() (ξ must be empty; §8.11). Never
  /// throws for a failed state solve (the evaluation's status says so). Throws InvalidArgument for
  /// an m or ξ of the wrong size or not finite.
  ShapeEvaluation evaluate(const Eigen::VectorXd& m, bool gradient,
                           const Eigen::VectorXd& xi = Eigen::VectorXd());

  /// H v, the reduced Hessian of J(m) (docs/formulation.md §4.4.1) at the control m applied to
  /// v (one value per control each):
  ///   w = (du/dm) v, V = (∂X/∂u) w, q = (∂X/∂u)ᵀ ∇²ρ̃ V (the distance's product of `part`),
  ///   s = the state's side for (v, w, q, part), H v = ∇²J_reg v + s.
  /// m is normally the control of the last evaluate(m, gradient = true) or of the last product
  /// (both are kept): if evaluations moved the state since (a rejected trial), m's state,
  /// distance and adjoint are re-established first from its kept converged state (0 Newton
  /// iterations); another m is evaluated first (from the nearest warm start). Needs
  /// options().second_order; throws InvalidArgument without it or for an m or v of the wrong
  /// size or not finite, and StateSolveError if the state solve at m fails.
  Eigen::VectorXd hessian_product(const Eigen::VectorXd& m, const Eigen::VectorXd& v,
                                  HessianPart part = HessianPart::full,
                                  HessianProductStats* stats = nullptr);

  /// Projection (options().pose_method): the twist every inner minimisation starts from, 0 (the
  /// start pose) until set; empty otherwise. evaluate() does not change it: track_shape sets it
  /// to the pose of the start, then of each accepted iterate (replayed ones too), so the
  /// evaluations of one optimiser round share their start (docs/formulation.md §8.11).
  const Eigen::VectorXd& pose_warm_start() const;
  /// Sets pose_warm_start(). Throws InvalidArgument without the projection or for a ξ of the
  /// wrong size or not finite.
  void set_pose_warm_start(const Eigen::VectorXd& xi);

  /// The states solved so far: warm starts, two-level starts, solver resets.
  StatePath& state_path();
  /// As state_path(), read-only.
  const StatePath& state_path() const;
  /// The first map of the chain: the moving cloud X(u) in the body's frame.
  const MovingCloud& moving_cloud() const;
  /// The second map: the pose map Q_ξ into the target's (camera) frame, or null when the target
  /// is in the body's frame (ShapeObjectiveOptions::pose). pose()->at(ξ).inverse() is the pose
  /// P_ξ (scan → body).
  const scan::PoseMap* pose() const;

  /// Per-point fields d̃ of the moving cloud of u (at the twist ξ) against the target, with the
  /// objective's form (raw fields; ρ̃, A, B of the form).
  HausdorffResult fields(const Eigen::VectorXd& u,
                         const Eigen::VectorXd& xi = Eigen::VectorXd()) const;
  /// The form an evaluation at displacement u (and twist ξ) uses: the options' form, with the
  /// visible mask of u's deformed boundary when a camera is set (the pose's camera with a pose).
  DistanceForm distance_form(const Eigen::VectorXd& u,
                             const Eigen::VectorXd& xi = Eigen::VectorXd()) const;
  /// Replaces the distance form of later evaluations (e.g. a cap set from the starting
  /// state's fields, cap_from_quantile). Throws InvalidArgument as DistanceForm::validate for
  /// the moving cloud's size.
  void set_form(DistanceForm form);

  /// Quadrature cells only (else InvalidArgument): ρ̃ by the cell form of the body at the
  /// displacement *u against the target's cells (the matched floor, u the known map; with a pose
  /// the body at the start pose, as target_frame_cloud's), or, with u null, of the target's
  /// cells against themselves (the self floor).
  double cell_rho(const Eigen::VectorXd* u) const;
  /// Quadrature cells: the hexahedra of the body and of the target ({0, 0} with collocation;
  /// the target's 0 against a scan's surface, whose cell_rho(nullptr) is refused).
  std::pair<long, long> cell_counts() const;

  /// The target with its trees.
  const HausdorffTarget& target() const;
  /// The options (with the Newton absolute tolerance filled in if it was 0).
  const ShapeObjectiveOptions& options() const;
  /// The body's assembler.
  const fe::Assembler& assembler() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The number of pose variables the optimiser carries: pose()->variables() (6 or 7) for a joint
/// pose, 0 without a pose or with the projection (which finds ξ inside each evaluation).
inline int pose_variables(const ShapeObjective& objective) {
  return objective.pose() && objective.options().pose_method == PoseMethod::joint
             ? objective.pose()->variables()
             : 0;
}
/// The pose P_ξ (scan → body) at the twist ξ (empty: 0): pose()->at(ξ).inverse(), the identity
/// without a pose.
scan::Pose pose_at(const ShapeObjective& objective, const Eigen::VectorXd& xi);
/// The moving cloud of u in the target's frame at the twist ξ: Q_ξ(X(u)), or X(u) without a pose.
PointCloud target_frame_cloud(const ShapeObjective& objective, const Eigen::VectorXd& u,
                              const Eigen::VectorXd& xi = Eigen::VectorXd());

}  // namespace softhd
