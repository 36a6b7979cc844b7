#pragma once
/// \file shape_objective.hpp
/// The shape-tracking objective of docs/formulation.md §4.2 and its adjoint gradient:
///
///     J(m) = ρ̃_H(Φ_m(Ω₀), Ω_d) + (M/2)∫m² + (ε_m/2)∫|∇m|²
///
/// Φ_m(Ω₀) is the deformed body as a point cloud — its nodes or its quadrature points —
/// with the reference volumes (the paper's simplification) or the deformed ones
/// V_i = ∫ N_i J dX; the gradient is exact for the choice made:
///
///     g = ∂ρ̃/∂u (through the particle positions, and volumes if they move),
///     K λ = g on the free dofs (the converged tangent's factorisation),
///     dJ/dm_k = ∂J_reg/∂m_k + ∫ M_k (F a₀)·(∇λ a₀) dX.
///
/// With a pose (ShapeObjectiveOptions::pose, docs/formulation.md §8.10) the target stays in the
/// camera's frame and the moving cloud is mapped into it, x'_i = Q_ξ(x_i), by the twist ξ about
/// a fixed centre composed with the start; evaluate(m, ξ) returns dJ/dξ beside dJ/dm.

#include <Eigen/Core>
#include <deque>
#include <memory>
#include <optional>
#include <string>

#include "softhd/fe/assembly.hpp"
#include "softhd/fe/control.hpp"
#include "softhd/fe/newton.hpp"
#include "softhd/fe/state_equation.hpp"
#include "softhd/hausdorff.hpp"
#include "softhd/point_cloud.hpp"
#include "softhd/scan/align.hpp"
#include "softhd/scan/pose.hpp"

namespace softhd {

/// Which points of the deformed body form the moving cloud.
enum class Particles {
  nodes,       ///< the mesh nodes
  quadrature,  ///< the quadrature points
  /// the boundary nodes (3D): a surface target's moving cloud, the volumes the lumped facet
  /// areas (reference, or deformed: current), docs/formulation.md §8.6
  boundary,
};
/// Volumes of the moving cloud: fixed reference volumes or the deformed ones.
enum class ParticleVolumes { reference, deformed };

/// "nodes", "quadrature" or "boundary".
std::string to_string(Particles p);
/// "reference" or "deformed".
std::string to_string(ParticleVolumes v);
Particles particles_from_string(const std::string& name);  ///< "nodes"/"quadrature"/"boundary"
ParticleVolumes particle_volumes_from_string(const std::string& name);  ///< "reference"/"deformed"

/// Settings of the objective J(m) (docs/formulation.md §4.2, §4.3); defaults per field.
struct ShapeObjectiveOptions {
  HausdorffOptions hausdorff;                            ///< α, β, γ, ε, method, threads
  Particles particles = Particles::nodes;                ///< moving cloud: nodes (paper)
  ParticleVolumes volumes = ParticleVolumes::reference;  ///< paper's simplification
  double tikhonov_mass = 0.0;                            ///< M ≥ 0 (paper: 0)
  double tikhonov_gradient = 0.0;                        ///< ε_m ≥ 0 (paper: 0)
  /// The distance's form in every evaluation (docs/formulation.md §8): symmetric (default),
  /// scan_to_body, visible, and the soft cap. For Sides::visible either a fixed mask over the
  /// moving cloud's points, or (with `camera`) none: every evaluation then marks the moving
  /// points seen from the camera (§8.7).
  DistanceForm form;
  /// Sides::visible only: the camera in the body's frame (then form.visible is empty). The moving
  /// points marked are the boundary nodes scan::visible_points finds on the deformed boundary
  /// (fe::boundary_surface) — for particles = boundary the cloud's own points, for nodes the
  /// boundary nodes among them; quadrature points are refused. Held fixed in the gradient.
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
  Eigen::VectorXd pose_gradient;  ///< dJ/dξ (with a pose, if requested and ok; else empty)
  int newton_iterations = 0;      ///< Newton iterations of the state solve
  int factorizations = 0;         ///< numeric factorisations of the state solve and the adjoint
  ///@{
  /// Wall time (seconds) of the state solve, the distance and the adjoint.
  double seconds_state = 0.0, seconds_distance = 0.0, seconds_adjoint = 0.0;
  ///@}
  std::string failure;  ///< for people: Newton's one-line report of a failed state solve
};

/// A converged state kept for warm starts, with its control (empty for the rest state).
struct WarmStart {
  Eigen::VectorXd m;  ///< the control (empty for the rest state)
  fe::State state;    ///< its converged state
};

/// J(m) and dJ/dm for one body, control space and target. Keeps the last converged
/// states for warm starts and the target's trees across evaluations. Not thread-safe.
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

  /// J(m); with `gradient`, also dJ/dm. Never throws for a failed state solve. With a pose:
  /// J at the start pose (ξ = 0), and dJ/dξ too.
  ShapeEvaluation evaluate(const Eigen::VectorXd& m, bool gradient);
  /// J(m, ξ) with the pose twist ξ (pose_variables() entries; empty means 0); with `gradient`,
  /// dJ/dm and dJ/dξ (exact, docs/formulation.md §8.10). Throws InvalidArgument for a ξ of the
  /// wrong size or not finite.
  ShapeEvaluation evaluate(const Eigen::VectorXd& m, const Eigen::VectorXd& xi, bool gradient);
  /// The number of pose variables: 0 without a pose, 6 (rigid) or 7 (similarity).
  int pose_variables() const;
  /// The pose P_ξ (scan → body) of the twist ξ (empty: the start pose; without a pose: identity).
  scan::Pose pose_at(const Eigen::VectorXd& xi) const;
  /// The twist's fixed centre c (the camera's frame; zero without a pose).
  Eigen::Vector3d pose_centre() const;
  /// The moving cloud of u in the target's frame at the twist ξ (x'_i = Q_ξ(x_i); without a
  /// pose, particles(u)).
  PointCloud target_frame_particles(const Eigen::VectorXd& u, const Eigen::VectorXd& xi) const;

  /// The moving cloud of a displacement u (num_dofs entries).
  PointCloud particles(const Eigen::VectorXd& u) const;
  /// The last converged state (the rest state before any evaluation).
  const fe::State& last_state() const;
  /// Puts a converged state for the control m first among the warm starts (e.g. the best
  /// one, so that evaluating m again starts, and stays, exactly there).
  void remember_state(const Eigen::VectorXd& m, const fe::State& state);
  /// The target with its trees.
  const HausdorffTarget& target() const;
  /// The options (with the Newton absolute tolerance filled in if it was 0).
  const ShapeObjectiveOptions& options() const;
  /// The body's assembler.
  const fe::Assembler& assembler() const;
  /// The warm-start states, most recent first (what the next evaluation starts from).
  const std::deque<WarmStart>& warm_starts() const;
  /// Replaces the warm-start states (e.g. from a checkpoint), so that the next evaluation
  /// is bitwise the one an uninterrupted run would make. Throws InvalidArgument if the
  /// list is empty, longer than warm_start_states, or a size does not fit the problem.
  void restore_warm_starts(const std::vector<WarmStart>& states);
  /// Two-level starts (docs/formulation.md §4.7): before each state solve, the coarse body
  /// `coarse` (the same body on a coarser mesh, e.g. fe::coarsened(scene)) is solved at the
  /// warm start's control and at m, and a large step starts the fine solve from the warm
  /// state plus the prolongated coarse change. `coarse` must outlive the objective.
  void use_coarse_level(const fe::Assembler& coarse);
  /// The coarse body of use_coarse_level, or null.
  const fe::Assembler* coarse_level() const;
  /// Resets the state solver (fe::StateEquation::reset), forgetting what it keeps between
  /// solves (its factorisations and path tangent): later evaluations then depend on earlier ones
  /// only through the warm starts, which a checkpoint can save. Costs a factorisation at the next
  /// solve.
  void reset_solver();
  /// Per-point fields d̃ of the last converged state (moving cloud, target cloud), with the
  /// objective's form (raw fields; ρ̃, A, B of the form).
  HausdorffResult fields(const Eigen::VectorXd& u) const;
  /// As fields(u), at the pose twist ξ (empty: 0).
  HausdorffResult fields(const Eigen::VectorXd& u, const Eigen::VectorXd& xi) const;
  /// Replaces the distance form of later evaluations (e.g. a cap set from the starting
  /// state's fields, cap_from_quantile). Throws InvalidArgument as DistanceForm::validate for
  /// the moving cloud's size.
  void set_form(DistanceForm form);
  /// The form an evaluation at displacement u uses: the options' form, with the visible mask
  /// of u's deformed boundary when a camera is set.
  DistanceForm distance_form(const Eigen::VectorXd& u) const;
  /// As distance_form(u), with the camera of the pose twist ξ (empty: 0).
  DistanceForm distance_form(const Eigen::VectorXd& u, const Eigen::VectorXd& xi) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace softhd
