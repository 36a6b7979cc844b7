#include "softhd/control/shape_objective.hpp"

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <optional>

#include "cell_form.hpp"
#include "softhd/enum_names.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/geometry.hpp"
#include "softhd/fe/state_solver.hpp"
#include "softhd/scan/align.hpp"
#include "softhd/scan/fixture.hpp"

namespace softhd {

namespace {
constexpr EnumNames<EvaluationStatus, 2> kEvaluationStatus{
    {{EvaluationStatus::ok, "ok"}, {EvaluationStatus::state_failed, "state_failed"}}};
constexpr auto kPoseMethods = enum_sequence<PoseMethod::projection>({"joint", "projection"});

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// The moving cloud's map, after checking the dimension the options need (3D for boundary
/// particles, a camera or a pose). With a pose the boundary is kept too: set_form may choose
/// the visible distance later.
MovingCloud make_moving_cloud(const fe::Assembler& a, const ShapeObjectiveOptions& o) {
  if (o.pose && a.mesh().dim != 3)
    throw InvalidArgument("pose: a pose (target in the camera's frame) needs a 3D body");
  const bool boundary = o.particles == Particles::boundary || o.camera || o.pose;
  if (boundary && a.mesh().dim != 3)
    throw InvalidArgument(o.particles == Particles::boundary
                              ? "particles boundary needs a 3D body"
                              : "a camera (distance visible) needs a 3D body");
  return MovingCloud(a, o.particles, o.volumes, boundary);
}

/// The target's options decide the distance: options.hausdorff must say the same (else setting
/// α, β, γ, ε or the method on the objective alone would silently do nothing).
void check_same_distance(const HausdorffOptions& mine, const HausdorffOptions& target) {
  const HausdorffParams &a = mine.params, &b = target.params;
  const char* field = a.alpha != b.alpha                           ? "params.alpha"
                      : a.beta != b.beta                           ? "params.beta"
                      : a.gamma != b.gamma                         ? "params.gamma"
                      : a.epsilon != b.epsilon                     ? "params.epsilon"
                      : mine.method != target.method               ? "method"
                      : mine.tolerance != target.tolerance         ? "tolerance"
                      : mine.tree_fallback != target.tree_fallback ? "tree_fallback"
                                                                   : nullptr;
  if (field)
    throw InvalidArgument(std::string("ShapeObjectiveOptions::hausdorff.") + field +
                          " differs from the target's (build the HausdorffTarget with the "
                          "objective's options)");
}

/// quadrature cells: what the cell form cannot do yet, refused naming the field.
void check_cells_quadrature(const ShapeObjectiveOptions& o) {
  if (o.hausdorff.quadrature != Quadrature::cells) {
    if (o.target_cells)
      throw InvalidArgument(
          "target_cells: given, but hausdorff.quadrature is collocation (cells uses them)");
    return;
  }
  const HausdorffParams& p = o.hausdorff.params;
  const char* field = p.alpha != 4.0   ? "hausdorff.params.alpha (4)"
                      : p.beta != 4.0  ? "hausdorff.params.beta (4)"
                      : p.gamma != 2.0 ? "hausdorff.params.gamma (2)"
                                       : nullptr;
  if (field)
    throw InvalidArgument(std::string("quadrature cells: only the paper's exponents, not yet "
                                      "other values of ") +
                          field);
  // symmetric: the target's cells; scan_to_body: the scan's surface (its points and weights).
  if (o.form.sides == Sides::visible)
    throw InvalidArgument(
        "form.sides: quadrature cells supports the symmetric and scan_to_body distances "
        "(not yet visible)");
  if (o.form.sides == Sides::scan_to_body && o.target_cells)
    throw InvalidArgument(
        "target_cells: quadrature cells with scan_to_body integrates over the scan's surface "
        "(its points and surface weights), not over target cells");
  if (o.form.cap.c != 0.0) throw InvalidArgument("form.cap: quadrature cells has no cap (not yet)");
  if (o.camera) throw InvalidArgument("camera: quadrature cells has no camera (not yet)");
  if (o.pose && (o.form.sides != Sides::scan_to_body || o.target_cells))
    throw InvalidArgument(
        "pose: quadrature cells takes a pose against a scan's surface only (form.sides "
        "scan_to_body, no target_cells)");
  if (o.pose && o.pose_method != PoseMethod::projection)
    throw InvalidArgument(
        "pose.method: quadrature cells finds the pose by projection only (not joint)");
  if (o.second_order)
    throw InvalidArgument(
        "second_order: quadrature cells has no Hessian-vector product (optimiser.algorithm "
        "newton) yet");
  if (!o.target_cells && o.form.sides == Sides::symmetric)
    throw InvalidArgument(
        "target_cells: quadrature cells needs the target's cells (a target with a mesh), or "
        "the scan_to_body distance against a scan's surface");
}

/// The cell rule's options from the distance's: ε, threads, and with method tree J's tree
/// tolerance τ and the cheapest of J's rules whose own measured error (docs/formulation.md §2.8:
/// near_ratio 2, 8 angle points: 3.7e-6 of J) stays below τ/10; method exact: all pairs at the
/// default rules (≤ ~1e-9).
detail::CellDistanceOptions cell_options(const HausdorffOptions& h) {
  detail::CellDistanceOptions c;
  c.epsilon = h.params.epsilon;
  c.threads = h.threads;
  c.tolerance = h.method == Method::tree ? h.tolerance : 0.0;
  if (c.tolerance >= 3.7e-5) c.j_near_ratio = 2.0, c.j_angle_points = 8;
  return c;
}

}  // namespace

std::string to_string(EvaluationStatus s) { return enum_name(kEvaluationStatus, s); }
std::string to_string(PoseMethod method) { return enum_name(kPoseMethods, method); }
PoseMethod pose_method_from_string(const std::string& name) {
  return enum_from_name(kPoseMethods, name, "pose.method");
}

struct ShapeObjective::Impl {
  Impl(const fe::Assembler& a, const fe::ControlSpace& c, HausdorffTarget t,
       ShapeObjectiveOptions o, const fe::StateSolverFactory& make_solver)
      : assembler(a),
        control(c),
        target(std::move(t)),
        options(std::move(o)),
        cloud(make_moving_cloud(a, options)),
        path(a, c, make_solver(options.newton), options.newton, options.warm_start_states,
             options.coarse_correction_iterations) {
    if (options.hausdorff.quadrature == Quadrature::cells)
      cells = options.target_cells
                  ? std::make_unique<detail::CellForm>(a.mesh(), *options.target_cells,
                                                       cell_options(options.hausdorff))
                  : std::make_unique<detail::CellForm>(a.mesh(), target.cloud().points(),
                                                       target.cloud().volumes(),
                                                       cell_options(options.hausdorff));
    if (options.pose) {
      // Q₀ = P₀⁻¹ (body → camera) and the twist's centre c = Q₀(centroid of the rest cloud).
      const scan::Pose start_inverse = options.pose->inverse();
      const Eigen::Vector3d mean = cloud.at(path.last_state().u).points().colwise().mean();
      const Eigen::Vector3d centre =
          scan::apply_points(start_inverse, mean.transpose()).row(0).transpose();
      pose.emplace(start_inverse, centre, options.pose_kind);
      if (options.pose_method == PoseMethod::projection) {
        const PointCloud rest = cloud.at(path.last_state().u);
        pose_size =
            (rest.points().colwise().maxCoeff() - rest.points().colwise().minCoeff()).norm();
        warm_twist = Eigen::VectorXd::Zero(pose->variables());
      }
    }
  }

  const fe::Assembler& assembler;
  const fe::ControlSpace& control;
  HausdorffTarget target;
  ShapeObjectiveOptions options;
  MovingCloud cloud;
  StatePath path;
  std::optional<scan::PoseMap> pose;  // with a pose (docs/formulation.md §8.10)
  Eigen::VectorXd warm_twist;         // projection: the next inner minimisation's start (§8.11)
  double pose_size = 0.0;             // projection: L of the rest moving cloud
  std::unique_ptr<detail::CellForm> cells;  // quadrature cells (docs/formulation.md §2.8)

  bool projecting() const { return pose && options.pose_method == PoseMethod::projection; }
  /// The projection's inner minimisation (docs/formulation.md §8.11): the twist
  ///   ξ* = argmin_ξ ρ̃(Q_ξ(X(u)), Y)   (the form f, its visible set held fixed)
  /// by scan::minimise_pose on the pose Q = Q_ξ, from Q_{warm_twist}; *iterations its BFGS's.
  Eigen::VectorXd project(const Eigen::VectorXd& u, const DistanceForm& f, int* iterations) const {
    const PointCloud X = cloud.at(u);
    const scan::PoseFunction rho = [&](const scan::Pose& Q, Eigen::VectorXd* g,
                                       Eigen::Vector3d* c) {
      return scan::pose_distance(target, X, f, Q, g, c);
    };
    return minimise(rho, iterations);
  }
  /// The same with quadrature cells: ρ̃ = A of the scan's points pulled into the body's frame
  /// by Q⁻¹ against the body's J at u (built once), the twist about the centroid of Q(X(u)).
  Eigen::VectorXd project_cells(const Eigen::VectorXd& u, int* iterations) const {
    const std::shared_ptr<const detail::CellForm::Deformed> body = cells->deform(u);
    const Eigen::RowVector3d mean = cloud.at(u).points().colwise().mean();
    const scan::PoseFunction rho = [&](const scan::Pose& Q, Eigen::VectorXd* g,
                                       Eigen::Vector3d* c) {
      const Eigen::Vector3d centre = scan::apply_points(Q, mean).row(0).transpose();
      if (g) *c = centre;
      return cells->posed_rho(*body, Q, centre, g);
    };
    return minimise(rho, iterations);
  }
  /// scan::minimise_pose of `rho` from Q_{warm_twist} with the projection's settings; ξ* of the
  /// pose found, *iterations its BFGS's.
  Eigen::VectorXd minimise(const scan::PoseFunction& rho, int* iterations) const {
    scan::LocalPoseSettings st;
    st.max_iterations = options.pose_iterations;
    st.step_tolerance = options.pose_tolerance;
    st.size = pose_size;
    st.first_step = 1e-3;    // from the last evaluation's optimum: a small first step
    st.max_backtracks = 20;  // a step 2^-20 of BFGS's that does not decrease ρ̃: at its minimum
    if (options.pose_bound) st.feasible = [this](const scan::Pose& Q) { return bounded(Q); };
    if (options.pose_table_normal)  // the start's tilt and height kept (§8.12)
      st.subspace = scan::table_tangent(pose->start().R * options.pose_table_normal->normalized());
    const scan::LocalPoseResult r = scan::minimise_pose(rho, pose->at(warm_twist), st);
    *iterations = r.iterations;
    return pose->twist_of(r.pose);
  }

  /// The pose of Q's twist ξ = twist_of(Q) with |ω| and |v| cut to options.pose_bound (each
  /// ball's nearest point: ω ← ω min(1, a/|ω|), v ← v min(1, b/|v|)).
  scan::Pose bounded(const scan::Pose& Q) const {
    Eigen::VectorXd xi = pose->twist_of(Q);
    const double w = xi.head<3>().norm(), v = xi.segment<3>(3).norm();
    const PoseBound& b = *options.pose_bound;
    if (w <= b.rotation && v <= b.translation) return Q;
    if (w > b.rotation) xi.head<3>() *= b.rotation / w;
    if (v > b.translation) xi.segment<3>(3) *= b.translation / v;
    return pose->at(xi);
  }
  /// ξ checked (size, finite); empty means 0 (and stays empty without a pose).
  Eigen::VectorXd checked_twist(const Eigen::VectorXd& xi) const {
    if (pose) return pose->checked(xi);
    if (xi.size() != 0)
      throw InvalidArgument("pose twist has " + std::to_string(xi.size()) + " values, expected 0");
    return xi;
  }
  /// The camera in the body's frame at ξ: the options' camera, or P_ξ's with a pose.
  std::optional<Eigen::Vector3d> camera_at(const Eigen::VectorXd& xi) const {
    if (!pose) return options.camera;
    return pose->at(xi).inverse().camera_position();
  }
  /// The moving cloud of u in the target's frame at ξ.
  PointCloud moved(const Eigen::VectorXd& u, const Eigen::VectorXd& xi) const {
    PointCloud X = cloud.at(u);
    return pose ? pose->apply(X, xi) : X;
  }
  /// The distance's form at u: for Sides::visible the moving points seen from the camera.
  DistanceForm form(const Eigen::VectorXd& u, const std::optional<Eigen::Vector3d>& camera) const {
    DistanceForm f = options.form;
    if (f.sides != Sides::visible || !camera) return f;  // no mask to make
    f.camera_mask = cloud.visible_from(u, *camera);
    return f;
  }
  /// The evaluation at m; with `converged` (a state converged for m) the solve starts there.
  /// `remember`: the converged state joins the warm starts (not when re-establishing a point).
  ShapeEvaluation evaluate(const Eigen::VectorXd& m, bool gradient, const Eigen::VectorXd& xi,
                           const fe::State* converged = nullptr, bool remember = true);

  /// The rest of an evaluation with quadrature cells, from the converged state: ρ̃ by the cell
  /// form, dρ̃/du = mapᵀ ∂ρ̃/∂points into the adjoint.
  // J = ρ̃ + the Tikhonov terms of m (their gradient into reg_gradient if non-null).
  void add_regularisation(const Eigen::VectorXd& m, Eigen::VectorXd* reg_gradient,
                          ShapeEvaluation* ev) const {
    ev->regularisation =
        control.regularisation(m, options.tikhonov_mass, options.tikhonov_gradient, reg_gradient);
    ev->J = ev->rho + ev->regularisation;
  }
  ShapeEvaluation finish_cells(const Eigen::VectorXd& m, bool gradient, const fe::State& state,
                               std::chrono::steady_clock::time_point t0, ShapeEvaluation ev);

  /// A point of hessian_product (options.second_order): a control evaluated with the gradient,
  /// its converged state and its distance result (with the second-order quantities).
  struct HessianPoint {
    Eigen::VectorXd m;
    fe::State state;
    HausdorffResult distance;
    std::uint64_t generation = 0;  // path.generation() right after its adjoint
    bool valid = false;
  };
  HessianPoint last_gradient;  // the last evaluation with the gradient
  HessianPoint last_product;   // the point of the last product
  /// The point m with its state and adjoint current in the solver (re-established if needed).
  const HessianPoint& hessian_point(const Eigen::VectorXd& m, HessianProductStats* stats);
  Eigen::VectorXd hessian_product(const Eigen::VectorXd& m, const Eigen::VectorXd& v,
                                  HessianPart part, HessianProductStats* stats);
};

void ShapeObjectiveOptions::validate() const {
  hausdorff.validate();
  if (!(tikhonov_mass >= 0.0))
    throw InvalidArgument("tikhonov_mass (Tikhonov weight M) must be >= 0");
  if (!(tikhonov_gradient >= 0.0))
    throw InvalidArgument("tikhonov_gradient (Tikhonov weight eps_m) must be >= 0");
  if (warm_start_states < 1) throw InvalidArgument("warm_start_states must be >= 1");
  if (coarse_correction_iterations < 0)
    throw InvalidArgument("coarse_correction_iterations must be >= 0");
  if (!(pose_tolerance > 0.0 && pose_tolerance < 1.0))
    throw InvalidArgument("pose_tolerance must be in (0, 1) (a fraction of L)");
  if (pose_iterations < 1) throw InvalidArgument("pose_iterations must be >= 1");
  if (pose_table_normal) {
    if (!pose || pose_method != PoseMethod::projection)
      throw InvalidArgument(
          "pose_table_normal constrains the pose found by projection (pose.method projection)");
    if (!pose_table_normal->allFinite() || !(pose_table_normal->norm() > 0.0))
      throw InvalidArgument("pose_table_normal must be finite and of nonzero length");
  }
  if (pose_bound) {
    if (pose_method != PoseMethod::projection)
      throw InvalidArgument(
          "pose_bound bounds the pose found by projection (pose.method projection)");
    if (!(pose_bound->rotation > 0.0 && std::isfinite(pose_bound->rotation)))
      throw InvalidArgument("pose_bound.rotation must be finite and > 0 (radians)");
    if (!(pose_bound->translation > 0.0 && std::isfinite(pose_bound->translation)))
      throw InvalidArgument("pose_bound.translation must be finite and > 0 (a length)");
  }
  if (pose && pose_method == PoseMethod::projection && pose_kind != scan::PoseKind::rigid)
    throw InvalidArgument(
        "pose.method projection finds a rigid pose; the target's \"align\" is similarity (use "
        "pose.method joint)");
  if (pose) {
    if (camera)
      throw InvalidArgument("camera: with a pose the camera is the pose's (leave camera empty)");
    const scan::Pose& p = *pose;
    if (!p.R.allFinite() || !p.t.allFinite() || !std::isfinite(p.s) || !(p.s > 0.0))
      throw InvalidArgument("pose: not finite, or its scale is not positive");
    if ((p.R.transpose() * p.R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-9 ||
        p.R.determinant() < 0.0)
      throw InvalidArgument("pose: R is not a rotation (to 1e-9)");
    if (pose_kind == scan::PoseKind::rigid && !p.rigid()) {
      char text[160];
      std::snprintf(text, sizeof text,
                    "pose: a rigid pose has scale 1 (to %g), got scale %.10g (pose_kind rigid; "
                    "use similarity for a scaled pose)",
                    scan::Pose::kScaleTolerance, p.s);
      throw InvalidArgument(text);
    }
  }
  const bool has_camera = camera || pose;  // a pose gives the camera (Sides::visible)
  if (has_camera && (camera || form.sides == Sides::visible)) {
    // the mask is made per evaluation: only the cap to check here
    if (form.camera_mask.size() != 0)
      throw InvalidArgument(
          "form.camera_mask: with a camera the objective marks the visible points (leave it "
          "empty)");
    DistanceForm cap_only = form;
    cap_only.sides = Sides::symmetric;
    cap_only.validate(0);
  } else {  // a given mask, checked against the moving cloud's size by the objective
    if (form.sides == Sides::visible && form.camera_mask.size() == 0)
      throw InvalidArgument(
          "camera: distance visible needs the camera position (or a mask in form.camera_mask)");
    form.validate(form.sides == Sides::visible ? form.camera_mask.size() : 0);
  }
  if (form.sides == Sides::visible && has_camera) {
    if (camera && !camera->allFinite()) throw InvalidArgument("camera must be finite");
    if (particles == Particles::quadrature)
      throw InvalidArgument("distance visible marks nodes: particles must be nodes or boundary");
  } else if (camera) {
    throw InvalidArgument("camera is given but the distance is " + to_string(form.sides) +
                          " (a camera selects the visible distance)");
  }
  newton.validate();
  check_cells_quadrature(*this);
  if (second_order && volumes != ParticleVolumes::reference)
    throw InvalidArgument(
        "volumes: the Hessian-vector product (second_order, for optimiser.algorithm newton) "
        "supports "
        "reference volumes only, got " +
        to_string(volumes));
  if (second_order && pose)
    throw InvalidArgument(
        "pose: the Hessian-vector product (second_order, for optimiser.algorithm newton) does not "
        "support a target in the camera's frame (a pose, joint or by projection)");
}

ShapeObjective::ShapeObjective(const fe::Assembler& assembler, const fe::ControlSpace& control,
                               HausdorffTarget target, ShapeObjectiveOptions options)
    : ShapeObjective(assembler, control, std::move(target), std::move(options),
                     [&assembler, &control](const fe::NewtonOptions& newton) {
                       return std::make_unique<fe::StateSolver>(assembler, control, newton);
                     }) {}

ShapeObjective::ShapeObjective(const fe::Assembler& assembler, const fe::ControlSpace& control,
                               HausdorffTarget target, ShapeObjectiveOptions options,
                               const fe::StateSolverFactory& make_solver) {
  if (target.cloud().dim() != assembler.mesh().dim) {
    throw InvalidArgument("the target cloud is " + std::to_string(target.cloud().dim()) +
                          "D but the body is " + std::to_string(assembler.mesh().dim) + "D");
  }
  options.validate();
  check_same_distance(options.hausdorff, target.options());
  if (options.newton.absolute_tolerance == 0.0) {
    // A floor under the relative residual test: the optimiser's small control changes
    // make |R(0; m)| tiny, and 1e-9 of a tiny reference lies below the residual's round-off.
    const double volume = fe::lumped_volumes(assembler.mesh(), assembler.geometry()).sum();
    options.newton.absolute_tolerance =
        fe::residual_floor(assembler.stiffness_scale(), volume, assembler.mesh().dim);
  }
  impl_ = std::make_unique<Impl>(assembler, control, std::move(target), std::move(options),
                                 make_solver);
}
ShapeObjective::~ShapeObjective() = default;

StatePath& ShapeObjective::state_path() { return impl_->path; }
const StatePath& ShapeObjective::state_path() const { return impl_->path; }
const MovingCloud& ShapeObjective::moving_cloud() const { return impl_->cloud; }
const scan::PoseMap* ShapeObjective::pose() const { return impl_->pose ? &*impl_->pose : nullptr; }
const Eigen::VectorXd& ShapeObjective::pose_warm_start() const { return impl_->warm_twist; }
void ShapeObjective::set_pose_warm_start(const Eigen::VectorXd& xi) {
  if (!impl_->projecting())
    throw InvalidArgument("set_pose_warm_start: the objective has no pose by projection");
  if (xi.size() == 0) throw InvalidArgument("set_pose_warm_start: an empty twist");
  impl_->warm_twist = impl_->pose->checked(xi);
}
double ShapeObjective::cell_rho(const Eigen::VectorXd* u) const {
  if (!impl_->cells) throw InvalidArgument("cell_rho: the objective's quadrature is collocation");
  if (u && impl_->pose) return impl_->cells->evaluate(*u, impl_->pose->start()).rho;  // at Q₀
  return u ? impl_->cells->evaluate(*u).rho : impl_->cells->self_rho();
}
std::pair<long, long> ShapeObjective::cell_counts() const {
  if (!impl_->cells) return {0, 0};
  if (impl_->cells->surface()) return {impl_->cells->body_hexahedra(), 0};
  return {impl_->cells->body_hexahedra(), static_cast<long>(impl_->cells->target().cells.rows())};
}
const HausdorffTarget& ShapeObjective::target() const { return impl_->target; }
const ShapeObjectiveOptions& ShapeObjective::options() const { return impl_->options; }
const fe::Assembler& ShapeObjective::assembler() const { return impl_->assembler; }

void ShapeObjective::set_form(DistanceForm form) {
  ShapeObjectiveOptions o = impl_->options;
  o.form = std::move(form);
  o.validate();  // the camera's rules
  if (!o.camera && !o.pose)
    o.form.validate(impl_->cloud.at(impl_->path.warm_starts().back().state.u).size());
  impl_->options.form = std::move(o.form);
}

DistanceForm ShapeObjective::distance_form(const Eigen::VectorXd& u,
                                           const Eigen::VectorXd& xi) const {
  return impl_->form(u, impl_->camera_at(impl_->checked_twist(xi)));
}

HausdorffResult ShapeObjective::fields(const Eigen::VectorXd& u, const Eigen::VectorXd& xi) const {
  const Eigen::VectorXd x = impl_->checked_twist(xi);
  if (impl_->cells) {  // the continuum fields; no cap or camera with cells
    // With a pose (a scan's surface) the target's points are pulled into the body's frame.
    const Eigen::MatrixXd& y = impl_->target.cloud().points();
    const detail::CellForm::Fields f =
        impl_->cells->fields(u, impl_->moved(u, x).points(),
                             impl_->pose ? scan::apply_points(impl_->pose->at(x).inverse(), y) : y);
    const detail::CellRho rho = impl_->pose ? impl_->cells->evaluate(u, impl_->pose->at(x)) : f.rho;
    HausdorffResult r;
    r.rho = rho.rho;
    r.A = std::sqrt(std::sqrt(rho.a.mean));
    r.B = std::sqrt(std::sqrt(rho.b.mean));
    r.field_moving = f.moving;
    r.field_target = f.target;
    if (impl_->cells->surface()) {  // a surface bounds no volume: the body's field collocated
      HausdorffRequest req;
      req.fields = true;
      req.form = impl_->form(u, impl_->camera_at(x));
      r.field_moving = impl_->target.evaluate(impl_->moved(u, x), req).field_moving;
    }
    return r;
  }
  HausdorffRequest req;
  req.fields = true;
  req.form = impl_->form(u, impl_->camera_at(x));
  return impl_->target.evaluate(impl_->moved(u, x), req);
}

scan::Pose pose_at(const ShapeObjective& objective, const Eigen::VectorXd& xi) {
  if (!objective.pose()) return scan::Pose();
  return objective.pose()->at(objective.pose()->checked(xi)).inverse();
}

PointCloud target_frame_cloud(const ShapeObjective& objective, const Eigen::VectorXd& u,
                              const Eigen::VectorXd& xi) {
  const PointCloud X = objective.moving_cloud().at(u);
  return objective.pose() ? objective.pose()->apply(X, objective.pose()->checked(xi)) : X;
}

ShapeEvaluation ShapeObjective::evaluate(const Eigen::VectorXd& m, bool gradient,
                                         const Eigen::VectorXd& xi) {
  if (impl_->projecting() && xi.size() != 0)
    throw InvalidArgument("pose twist has " + std::to_string(xi.size()) +
                          " values, expected 0 (the projection finds it)");
  return impl_->evaluate(m, gradient, impl_->checked_twist(xi));
}

/// J = ρ̃(Q_ξ(X(u(m))), Y) + J_reg(m); with `gradient` the adjoint chain:
///   g_x' = ∂ρ̃/∂x' → (dJ/dξ, g_x = s R_ξᵀ g_x') → g_u = ∂X/∂uᵀ g_x → K λ = g_u → dJ/dm.
/// Projection: ξ = ξ*(u) of the inner minimisation, and the same chain gives
///   dJ/dm = ∂J/∂m at (m, ξ*) (the envelope theorem: ∂ρ̃/∂ξ = 0 there), no dJ/dξ.
ShapeEvaluation ShapeObjective::Impl::evaluate(const Eigen::VectorXd& m, bool gradient,
                                               const Eigen::VectorXd& xi_in,
                                               const fe::State* converged, bool remember) {
  if (m.size() != control.size()) {
    throw InvalidArgument("control has " + std::to_string(m.size()) + " values, expected " +
                          std::to_string(control.size()));
  }
  ShapeEvaluation ev;
  // State: warm start from the kept state with the nearest control.
  auto t0 = std::chrono::steady_clock::now();
  fe::State state;
  const StateSolve ss = converged ? path.resolve(m, *converged, &state) : path.solve(m, &state);
  ev.newton_iterations = ss.newton_iterations;
  ev.factorizations = ss.factorizations;
  ev.seconds_state = seconds_since(t0);
  if (!ss.summary.converged()) {
    ev.failure = ss.summary.BriefReport();
    return ev;
  }
  if (remember) path.remember(m, state);

  // Distance (and its gradient w.r.t. the moved points).
  t0 = std::chrono::steady_clock::now();
  if (cells) return finish_cells(m, gradient, state, t0, std::move(ev));
  HausdorffRequest req;
  Eigen::VectorXd xi = xi_in;
  // This state's visible set, fixed in the gradient (projection: from the warm start's camera,
  // fixed in the inner minimisation too).
  req.form = form(state.u, camera_at(projecting() ? warm_twist : xi));
  if (projecting()) xi = project(state.u, req.form, &ev.pose_iterations);
  req.gradient_points = gradient;
  req.hessian_points = gradient && options.second_order;
  req.gradient_volumes = gradient && options.volumes == ParticleVolumes::deformed;
  // Clamped nodes do not move: skip their position gradients. Their deformed volumes do
  // change with the neighbouring nodes, so with deformed volumes every node is needed; with a
  // pose every point moves with ξ.
  if (gradient && options.volumes == ParticleVolumes::reference && !pose)
    req.differentiate = cloud.free_points();
  const PointCloud x = moved(state.u, xi);
  HausdorffResult r = target.evaluate(x, req);
  ev.seconds_distance = seconds_since(t0);
  ev.rho = r.rho;
  ev.A = r.A;
  ev.B = r.B;
  Eigen::VectorXd reg_gradient;
  add_regularisation(m, gradient ? &reg_gradient : nullptr, &ev);
  if (gradient) {
    t0 = std::chrono::steady_clock::now();
    if (pose) {
      if (!projecting()) ev.pose_gradient = pose->twist_gradient(x.points(), r.gradient_points, xi);
      r.gradient_points = pose->pullback(r.gradient_points, xi);
    }
    const Eigen::VectorXd g = cloud.pullback(state.u, r);
    ev.gradient = reg_gradient + path.adjoint(g, &ev.factorizations);
    ev.seconds_adjoint = seconds_since(t0);
    if (options.second_order) last_gradient = {m, state, std::move(r), path.generation(), true};
  }
  if (pose) ev.pose_twist = xi;
  ev.status = EvaluationStatus::ok;
  return ev;
}

ShapeEvaluation ShapeObjective::Impl::finish_cells(const Eigen::VectorXd& m, bool gradient,
                                                   const fe::State& state,
                                                   std::chrono::steady_clock::time_point t0,
                                                   ShapeEvaluation ev) {
  Eigen::VectorXd g;
  // Projection: ξ* on this state, then ρ̃ and dρ̃/du at it (the envelope theorem, §8.11).
  if (projecting()) ev.pose_twist = project_cells(state.u, &ev.pose_iterations);
  const detail::CellRho r =
      projecting() ? cells->evaluate(state.u, pose->at(ev.pose_twist), gradient ? &g : nullptr)
                   : cells->evaluate(state.u, gradient ? &g : nullptr);
  ev.seconds_distance = seconds_since(t0);
  ev.rho = r.rho;
  ev.A = std::sqrt(std::sqrt(r.a.mean));  // A = (A^4)^(1/4)
  ev.B = std::sqrt(std::sqrt(r.b.mean));
  Eigen::VectorXd reg_gradient;
  add_regularisation(m, gradient ? &reg_gradient : nullptr, &ev);
  if (gradient) {
    t0 = std::chrono::steady_clock::now();
    ev.gradient = reg_gradient + path.adjoint(g, &ev.factorizations);
    ev.seconds_adjoint = seconds_since(t0);
  }
  ev.status = EvaluationStatus::ok;
  return ev;
}

Eigen::VectorXd ShapeObjective::hessian_product(const Eigen::VectorXd& m, const Eigen::VectorXd& v,
                                                HessianPart part, HessianProductStats* stats) {
  return impl_->hessian_product(m, v, part, stats);
}

const ShapeObjective::Impl::HessianPoint& ShapeObjective::Impl::hessian_point(
    const Eigen::VectorXd& m, HessianProductStats* stats) {
  const auto same = [&m](const HessianPoint& p) {
    return p.valid && p.m.size() == m.size() && p.m == m;
  };
  HessianPoint* kept = same(last_gradient)  ? &last_gradient
                       : same(last_product) ? &last_product
                                            : nullptr;
  if (!kept || kept->generation != path.generation()) {  // make m's state current again
    stats->reestablished = true;
    // From m's converged state: the kept point's, else a warm start's for exactly m (a
    // resumed run's first product), else (none) the nearest warm start.
    const fe::State* converged = kept ? &kept->state : nullptr;
    for (const WarmStart& w : path.warm_starts())
      if (!converged && w.m.size() == m.size() && w.m == m) converged = &w.state;
    const std::optional<fe::State> start =
        converged ? std::optional<fe::State>(*converged) : std::nullopt;
    const ShapeEvaluation ev = evaluate(m, true, Eigen::VectorXd(), start ? &*start : nullptr,
                                        /*remember=*/false);
    stats->newton_iterations = ev.newton_iterations;
    stats->factorizations = ev.factorizations;
    if (ev.status != EvaluationStatus::ok)
      throw StateSolveError("hessian_product: the state solve at its control failed: " +
                            ev.failure);
    kept = &last_gradient;  // the evaluation's point
  }
  if (kept != &last_product) last_product = *kept;
  return last_product;
}

/// H v = ∇²J_reg v + s (docs/formulation.md §4.4.1), F(u, m) = ρ̃(X(u)) + J_reg(m) having no
/// m–u cross term and X(u) affine in u:
///   w = (du/dm) v,  V = (∂X/∂u) w,  q = (∂X/∂u)ᵀ ∇²ρ̃ V,  s = the state's side of (v, w, q);
/// J_reg is quadratic and homogeneous, so ∇²J_reg v is its gradient at v.
Eigen::VectorXd ShapeObjective::Impl::hessian_product(const Eigen::VectorXd& m,
                                                      const Eigen::VectorXd& v, HessianPart part,
                                                      HessianProductStats* stats) {
  const auto t0 = std::chrono::steady_clock::now();
  if (!options.second_order)
    throw InvalidArgument(
        "hessian_product needs ShapeObjectiveOptions::second_order (set when the objective is "
        "made)");
  for (const Eigen::VectorXd* x : {&m, &v})
    if (x->size() != control.size() || !x->allFinite())
      throw InvalidArgument("hessian_product: m and v must be finite with " +
                            std::to_string(control.size()) + " values, got " +
                            std::to_string(x->size()));
  HessianProductStats local;
  const HessianPoint& p = hessian_point(m, &local);
  const Eigen::VectorXd w = path.sensitivity(v);
  HausdorffResult q_points;  // ∇²ρ̃ V as a point gradient, for the pull-back
  q_points.gradient_points = target.hessian_product(p.distance, cloud.push_forward(w), part);
  const Eigen::VectorXd q = cloud.pullback(p.state.u, q_points);
  Eigen::VectorXd Hv;
  control.regularisation(v, options.tikhonov_mass, options.tikhonov_gradient, &Hv);
  Hv += path.hessian_product(v, w, q, part);
  local.seconds = seconds_since(t0);
  if (stats) *stats = local;
  return Hv;
}

}  // namespace softhd
