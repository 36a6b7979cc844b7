#include "softhd/control/shape_objective.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <optional>

#include "softhd/enum_names.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/adjoint.hpp"
#include "softhd/fe/boundary.hpp"
#include "softhd/fe/cloud.hpp"
#include "softhd/fe/geometry.hpp"
#include "softhd/fe/grid_sequencing.hpp"
#include "softhd/fe/state_solver.hpp"
#include "softhd/scan/visibility.hpp"

namespace softhd {

namespace {
constexpr EnumNames<Particles, 3> kParticles{{{Particles::nodes, "nodes"},
                                              {Particles::quadrature, "quadrature"},
                                              {Particles::boundary, "boundary"}}};
constexpr EnumNames<ParticleVolumes, 2> kVolumes{
    {{ParticleVolumes::reference, "reference"}, {ParticleVolumes::deformed, "deformed"}}};
constexpr EnumNames<EvaluationStatus, 2> kEvaluationStatus{
    {{EvaluationStatus::ok, "ok"}, {EvaluationStatus::state_failed, "state_failed"}}};
}  // namespace

std::string to_string(EvaluationStatus s) { return enum_name(kEvaluationStatus, s); }

std::string to_string(Particles p) { return enum_name(kParticles, p); }
std::string to_string(ParticleVolumes v) { return enum_name(kVolumes, v); }
Particles particles_from_string(const std::string& name) {
  return enum_from_name(kParticles, name, "particles");
}
ParticleVolumes particle_volumes_from_string(const std::string& name) {
  return enum_from_name(kVolumes, name, "volumes");
}

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

struct ShapeObjective::Impl {
  Impl(const fe::Assembler& a, const fe::ControlSpace& c, HausdorffTarget t,
       ShapeObjectiveOptions o, const fe::StateSolverFactory& make_solver)
      : assembler(a),
        control(c),
        target(std::move(t)),
        options(std::move(o)),
        solver(make_solver(options.newton)) {
    if (!solver) throw InvalidArgument("ShapeObjective: the state solver factory made none");
    const fe::Mesh& mesh = a.mesh();
    dim = mesh.dim;
    if (options.pose && dim != 3)
      throw InvalidArgument("pose: a pose (target in the camera's frame) needs a 3D body");
    // With a pose the boundary is kept too: set_form may choose the visible distance later.
    if (options.particles == Particles::boundary || options.camera || options.pose) {
      if (dim != 3)
        throw InvalidArgument(options.particles == Particles::boundary
                                  ? "particles boundary needs a 3D body"
                                  : "a camera (distance visible) needs a 3D body");
      facets = fe::boundary_facets(mesh);
    }
    // Clamped nodes (no free dof) are not differentiated.
    if (options.particles != Particles::quadrature) {
      const bool all = options.particles == Particles::nodes;
      const Eigen::Index N = all ? mesh.num_nodes() : Eigen::Index(facets.nodes.size());
      differentiate.setConstant(N, false);
      for (Eigen::Index i = 0; i < N; ++i) {
        const Eigen::Index n = all ? i : facets.nodes[i];
        for (int c = 0; c < dim; ++c)
          if (a.dofs().free_index[n * dim + c] >= 0) differentiate[i] = true;
      }
    }
    cache.push_back({Eigen::VectorXd(), fe::rest_state(a)});
    if (options.pose) {
      start_inverse = options.pose->inverse();
      const Eigen::Vector3d mean = particles(cache.front().state.u).points().colwise().mean();
      centre = scan::apply_points(start_inverse, mean.transpose()).row(0).transpose();
    }
  }

  const fe::Assembler& assembler;
  const fe::ControlSpace& control;
  HausdorffTarget target;
  ShapeObjectiveOptions options;
  std::unique_ptr<fe::StateEquation> solver;  // the fine state equation, any backend
  int dim = 3;
  Eigen::Array<bool, Eigen::Dynamic, 1> differentiate;
  fe::BoundaryFacets facets;    // particles boundary or distance visible (3D)
  std::deque<WarmStart> cache;  // most recent first
  // Two-level starts (use_coarse_level): the coarse body and its solver.
  const fe::Assembler* coarse = nullptr;
  std::optional<fe::NewtonSolver> coarse_newton;
  bool coarse_active = true;           // false after a small step, until a hard fine solve
  std::deque<WarmStart> coarse_cache;  // coarse equilibria by control, most recent first
  // With a pose (docs/formulation.md §8.10): Q₀ = P₀⁻¹ and the twist's centre c.
  scan::Pose start_inverse;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();

  int pose_variables() const {
    if (!options.pose) return 0;
    return options.pose_kind == scan::PoseKind::similarity ? 7 : 6;
  }
  /// ξ checked (size, finite); empty means 0.
  Eigen::VectorXd checked_twist(const Eigen::VectorXd& xi) const {
    const int n = pose_variables();
    if (xi.size() == 0) return Eigen::VectorXd::Zero(n);
    if (xi.size() != n)
      throw InvalidArgument("pose twist has " + std::to_string(xi.size()) + " values, expected " +
                            std::to_string(n));
    if (!xi.allFinite()) throw InvalidArgument("pose twist is not finite");
    return xi;
  }
  /// Q_ξ = T_ξ ∘ Q₀ (body → camera frame): T_ξ(z) = c + e^σ E (z − c) + v, E = exp([ω]×).
  scan::Pose target_map(const Eigen::VectorXd& xi) const {
    const Eigen::Matrix3d E = scan::rotation_exp(xi.head<3>());
    const double es = xi.size() == 7 ? std::exp(xi[6]) : 1.0;
    scan::Pose q;
    q.R = E * start_inverse.R;
    q.s = es * start_inverse.s;
    q.t = centre + es * (E * (start_inverse.t - centre)) + xi.segment<3>(3);
    return q;
  }
  /// The camera in the body's frame at ξ: the options' camera, or P_ξ's with a pose.
  std::optional<Eigen::Vector3d> camera_at(const Eigen::VectorXd& xi) const {
    if (!options.pose) return options.camera;
    return target_map(xi).inverse().camera_position();
  }
  /// The moving cloud of u in the target's frame at ξ (Q_ξ applied; volumes unchanged: ρ̃ uses
  /// V_i/|X|).
  PointCloud moved_particles(const Eigen::VectorXd& u, const Eigen::VectorXd& xi) const {
    PointCloud X = particles(u);
    if (!options.pose) return X;
    return PointCloud(scan::apply_points(target_map(xi), X.points()), X.volumes());
  }
  /// dJ/dξ from g_i = ∂ρ̃/∂x'_i at the moved points x'_i (y_i = x'_i − c − v):
  ///   ∂/∂v = Σ g_i,  ∂/∂ω = J_l(ω)ᵀ Σ y_i × g_i,  ∂/∂σ = Σ y_i·g_i.
  Eigen::VectorXd twist_gradient(const Eigen::MatrixXd& moved, const Eigen::MatrixXd& g,
                                 const Eigen::VectorXd& xi) const {
    const Eigen::Vector3d base = centre + xi.segment<3>(3);
    Eigen::Vector3d gv = Eigen::Vector3d::Zero(), gw = Eigen::Vector3d::Zero();
    double gs = 0.0;
    for (Eigen::Index i = 0; i < moved.rows(); ++i) {
      const Eigen::Vector3d y = moved.row(i).transpose() - base;
      const Eigen::Vector3d gi = g.row(i).transpose();
      gv += gi;
      gw += y.cross(gi);
      gs += y.dot(gi);
    }
    Eigen::VectorXd out(xi.size());
    out.head<3>() = scan::rotation_left_jacobian(xi.head<3>()).transpose() * gw;
    out.segment<3>(3) = gv;
    if (xi.size() == 7) out[6] = gs;
    return out;
  }

  Eigen::MatrixXd coarse_control(const Eigen::VectorXd& m) const {
    return fe::control_on_quadrature(*coarse, assembler.mesh(), control.kind(), m,
                                     control.regions());
  }
  /// The fine start u + P(u_c(m) − u_c(m_old)): the coarse equilibria at the warm start's
  /// control m_old (kept from an earlier evaluation, else solved from the restricted warm
  /// state) and at m, their difference prolongated. Returns false if a coarse solve fails;
  /// `iterations` counts the coarse iterations to m.
  bool coarse_corrected(const Eigen::VectorXd& m, const WarmStart& warm, fe::State* start,
                        int* iterations) {
    const Eigen::VectorXd m_old = warm.m.size() ? warm.m : Eigen::VectorXd::Zero(m.size());
    fe::State c;
    if (!kept_coarse_state(m_old, &c)) {
      c = {fe::prolongate(assembler.mesh(), warm.state.u, coarse->mesh()), coarse_control(m_old)};
      if (!coarse_newton->solve(c.m_qp, &c).converged()) return false;
    }
    const Eigen::VectorXd u_old = c.u;
    const fe::NewtonSummary to_m = coarse_newton->solve(coarse_control(m), &c);
    *iterations = to_m.newton_iterations;
    if (!to_m.converged()) return false;
    coarse_cache.push_front({m, c});
    while (static_cast<int>(coarse_cache.size()) > options.warm_start_states)
      coarse_cache.pop_back();
    start->u = warm.state.u + fe::prolongate(coarse->mesh(), c.u - u_old, assembler.mesh());
    start->m_qp = control.to_quadrature(m);
    return true;
  }
  /// The coarse equilibrium kept for exactly the control m, if any.
  bool kept_coarse_state(const Eigen::VectorXd& m, fe::State* state) const {
    for (const WarmStart& w : coarse_cache) {
      if (w.m.size() == m.size() && w.m == m) {
        *state = w.state;
        return true;
      }
    }
    return false;
  }

  fe::CloudPoints cloud_points() const {
    return options.particles == Particles::nodes ? fe::CloudPoints::kNodes
                                                 : fe::CloudPoints::kQuadraturePoints;
  }
  fe::CloudVolumes cloud_volumes() const {
    return options.volumes == ParticleVolumes::reference ? fe::CloudVolumes::kReference
                                                         : fe::CloudVolumes::kDeformed;
  }
  PointCloud particles(const Eigen::VectorXd& u) const {
    if (options.particles == Particles::boundary)
      return fe::boundary_cloud(assembler.mesh(), facets, u, cloud_volumes());
    return fe::deformed_cloud(assembler, u, cloud_points(), cloud_volumes());
  }
  /// ∂ρ̃/∂u (num_dofs) from the cloud gradients w.r.t. particle positions and volumes.
  Eigen::VectorXd displacement_gradient(const Eigen::VectorXd& u, const HausdorffResult& r) const {
    if (options.particles == Particles::boundary)
      return fe::boundary_cloud_pullback(assembler.mesh(), facets, u, cloud_volumes(),
                                         r.gradient_points, r.gradient_volumes);
    return fe::cloud_pullback(assembler, u, cloud_points(), cloud_volumes(), r.gradient_points,
                              r.gradient_volumes);
  }
  /// The distance's form at u: for Sides::visible the moving points seen from the camera on
  /// the boundary deformed by u (the cloud's own points for boundary particles, the boundary
  /// nodes among all nodes for node particles).
  DistanceForm form(const Eigen::VectorXd& u, const std::optional<Eigen::Vector3d>& camera) const {
    DistanceForm f = options.form;
    if (f.sides != Sides::visible || !camera) return f;  // no mask to make
    const Eigen::Array<bool, Eigen::Dynamic, 1> seen =
        scan::visible_points(fe::boundary_surface(assembler.mesh(), facets, u), *camera);
    if (!seen.any())
      throw InvalidArgument("distance visible: the camera sees no boundary point of the body");
    if (options.particles == Particles::boundary) {
      f.visible = seen;
    } else {
      f.visible.setConstant(assembler.mesh().num_nodes(), false);
      for (size_t k = 0; k < facets.nodes.size(); ++k)
        f.visible[facets.nodes[k]] = seen[static_cast<Eigen::Index>(k)];
    }
    return f;
  }

  /// The cached state whose control is nearest to m (the rest state counts as m = 0).
  const WarmStart& nearest(const Eigen::VectorXd& m) const {
    size_t best = 0;
    double best_d = INFINITY;
    for (size_t k = 0; k < cache.size(); ++k) {
      const double d = cache[k].m.size() ? (cache[k].m - m).norm() : m.norm();
      if (d < best_d) {
        best_d = d;
        best = k;
      }
    }
    return cache[best];
  }

  /// The fine solve to m from `start`; its end state (converged or not) in *state.
  fe::NewtonSummary solve_from(const fe::State& start, const Eigen::VectorXd& m, fe::State* state) {
    solver->set_state(start);
    const fe::NewtonSummary s = solver->solve(m);
    *state = solver->state();
    return s;
  }

  /// The state at m (docs/formulation.md §4.7) from the warm start nearest to m, or after
  /// a large step from the coarse-corrected start. Adds the fine iterations to `ev`.
  fe::NewtonSummary solve_state(const Eigen::VectorXd& m, fe::State* state, ShapeEvaluation* ev) {
    const WarmStart& warm = nearest(m);
    const auto counted = [ev](const fe::NewtonSummary& s) {
      ev->newton_iterations += s.newton_iterations;
      ev->factorizations += s.factorizations;
      return s;
    };
    if (coarse && coarse_active) {
      int iterations = 0;
      fe::State start;
      const bool ok = coarse_corrected(m, warm, &start, &iterations);
      if (ok && iterations >= options.coarse_correction_iterations) {
        const fe::NewtonSummary s = counted(solve_from(start, m, state));
        if (s.converged()) return s;
      } else if (ok && iterations > 0) {
        coarse_active = false;  // small steps now: the coarse solves would only cost
      }
    }
    const fe::NewtonSummary s = counted(solve_from(warm.state, m, state));
    // A hard fine solve: large steps again, so the coarse level is tried again.
    if (coarse && s.newton_iterations >= 2 * options.coarse_correction_iterations)
      coarse_active = true;
    return s;
  }
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
    if (form.visible.size() != 0)
      throw InvalidArgument(
          "form.visible: with a camera the objective marks the visible points (leave it empty)");
    DistanceForm cap_only = form;
    cap_only.sides = Sides::symmetric;
    cap_only.validate(0);
  } else {  // a given mask, checked against the moving cloud's size by the objective
    if (form.sides == Sides::visible && form.visible.size() == 0)
      throw InvalidArgument(
          "camera: distance visible needs the camera position (or a mask in form.visible)");
    form.validate(form.sides == Sides::visible ? form.visible.size() : 0);
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

PointCloud ShapeObjective::particles(const Eigen::VectorXd& u) const { return impl_->particles(u); }
const fe::State& ShapeObjective::last_state() const { return impl_->cache.front().state; }
void ShapeObjective::remember_state(const Eigen::VectorXd& m, const fe::State& state) {
  impl_->cache.push_front({m, state});
  while (static_cast<int>(impl_->cache.size()) > impl_->options.warm_start_states)
    impl_->cache.pop_back();
}
const HausdorffTarget& ShapeObjective::target() const { return impl_->target; }
const ShapeObjectiveOptions& ShapeObjective::options() const { return impl_->options; }
const fe::Assembler& ShapeObjective::assembler() const { return impl_->assembler; }

const std::deque<WarmStart>& ShapeObjective::warm_starts() const { return impl_->cache; }

void ShapeObjective::use_coarse_level(const fe::Assembler& coarse) {
  Impl& d = *impl_;
  d.coarse = &coarse;
  d.coarse_newton.emplace(coarse, d.options.newton);
}

const fe::Assembler* ShapeObjective::coarse_level() const { return impl_->coarse; }

void ShapeObjective::reset_solver() {
  impl_->solver->reset();
  if (impl_->coarse) impl_->coarse_newton.emplace(*impl_->coarse, impl_->options.newton);
  impl_->coarse_active = true;
  impl_->coarse_cache.clear();  // like the solver's, not in a checkpoint
}

void ShapeObjective::restore_warm_starts(const std::vector<WarmStart>& states) {
  Impl& d = *impl_;
  if (states.empty() || static_cast<int>(states.size()) > d.options.warm_start_states)
    throw InvalidArgument("warm starts: expected 1 to " +
                          std::to_string(d.options.warm_start_states) + " states, got " +
                          std::to_string(states.size()));
  const fe::State& rest = d.cache.back().state;  // the shapes every state has
  for (const WarmStart& w : states) {
    if ((w.m.size() != 0 && w.m.size() != d.control.size()) || w.state.u.size() != rest.u.size() ||
        w.state.m_qp.rows() != rest.m_qp.rows() || w.state.m_qp.cols() != rest.m_qp.cols() ||
        !w.state.u.allFinite() || !w.state.m_qp.allFinite() || !w.m.allFinite())
      throw InvalidArgument("warm starts: a state does not fit this problem");
  }
  d.cache.assign(states.begin(), states.end());
}

void ShapeObjective::set_form(DistanceForm form) {
  ShapeObjectiveOptions o = impl_->options;
  o.form = std::move(form);
  o.validate();  // the camera's rules
  if (!o.camera && !o.pose) o.form.validate(impl_->particles(impl_->cache.back().state.u).size());
  impl_->options.form = std::move(o.form);
}

DistanceForm ShapeObjective::distance_form(const Eigen::VectorXd& u) const {
  return distance_form(u, Eigen::VectorXd());
}
DistanceForm ShapeObjective::distance_form(const Eigen::VectorXd& u,
                                           const Eigen::VectorXd& xi) const {
  return impl_->form(u, impl_->camera_at(impl_->checked_twist(xi)));
}

HausdorffResult ShapeObjective::fields(const Eigen::VectorXd& u) const {
  return fields(u, Eigen::VectorXd());
}
HausdorffResult ShapeObjective::fields(const Eigen::VectorXd& u, const Eigen::VectorXd& xi) const {
  const Eigen::VectorXd x = impl_->checked_twist(xi);
  HausdorffRequest req;
  req.fields = true;
  req.form = impl_->form(u, impl_->camera_at(x));
  return impl_->target.evaluate(impl_->moved_particles(u, x), req);
}

int ShapeObjective::pose_variables() const { return impl_->pose_variables(); }
scan::Pose ShapeObjective::pose_at(const Eigen::VectorXd& xi) const {
  if (!impl_->options.pose) return scan::Pose();
  return impl_->target_map(impl_->checked_twist(xi)).inverse();
}
Eigen::Vector3d ShapeObjective::pose_centre() const { return impl_->centre; }
PointCloud ShapeObjective::target_frame_particles(const Eigen::VectorXd& u,
                                                  const Eigen::VectorXd& xi) const {
  return impl_->moved_particles(u, impl_->checked_twist(xi));
}

ShapeEvaluation ShapeObjective::evaluate(const Eigen::VectorXd& m, bool gradient) {
  return evaluate(m, Eigen::VectorXd(), gradient);
}

ShapeEvaluation ShapeObjective::evaluate(const Eigen::VectorXd& m, const Eigen::VectorXd& xi_in,
                                         bool gradient) {
  Impl& d = *impl_;
  const Eigen::VectorXd xi = d.checked_twist(xi_in);
  if (m.size() != d.control.size()) {
    throw InvalidArgument("control has " + std::to_string(m.size()) + " values, expected " +
                          std::to_string(d.control.size()));
  }
  ShapeEvaluation ev;
  // State: warm start from the cached state with the nearest control.
  auto t0 = std::chrono::steady_clock::now();
  fe::State state;
  const fe::NewtonSummary ns = d.solve_state(m, &state, &ev);
  ev.seconds_state = seconds_since(t0);
  if (!ns.converged()) {
    ev.failure = ns.BriefReport();
    return ev;
  }
  remember_state(m, state);

  // Distance (and its gradient w.r.t. the particles).
  t0 = std::chrono::steady_clock::now();
  HausdorffRequest req;
  req.form = d.form(state.u, d.camera_at(xi));  // this state's visible set, fixed in the gradient
  req.gradient_points = gradient;
  req.gradient_volumes = gradient && d.options.volumes == ParticleVolumes::deformed;
  // Clamped nodes do not move: skip their position gradients. Their deformed volumes do
  // change with the neighbouring nodes, so with deformed volumes every node is needed; with a
  // pose every point moves with ξ.
  if (gradient && d.options.volumes == ParticleVolumes::reference && !d.options.pose)
    req.differentiate = d.differentiate;
  const PointCloud moved = d.moved_particles(state.u, xi);
  HausdorffResult r = d.target.evaluate(moved, req);
  ev.seconds_distance = seconds_since(t0);
  ev.rho = r.rho;
  ev.A = r.A;
  ev.B = r.B;
  Eigen::VectorXd reg_gradient;
  ev.regularisation = d.control.regularisation(
      m, d.options.tikhonov_mass, d.options.tikhonov_gradient, gradient ? &reg_gradient : nullptr);
  ev.J = ev.rho + ev.regularisation;
  if (gradient) {
    // Adjoint: K λ = ∂ρ̃/∂u, then dJ/dm = ∂J_reg/∂m + ∫ M_k (F a₀)·(∇λ a₀) dX.
    t0 = std::chrono::steady_clock::now();
    if (d.options.pose) {
      // x'_i = s_Q R_Q x_i + t_Q: dJ/dξ from g_i = ∂ρ̃/∂x'_i, and ∂ρ̃/∂x_i = s_Q R_Qᵀ g_i.
      ev.pose_gradient = d.twist_gradient(moved.points(), r.gradient_points, xi);
      const scan::Pose Q = d.target_map(xi);
      r.gradient_points = Q.s * (r.gradient_points * Q.R);
    }
    const Eigen::VectorXd g = d.displacement_gradient(state.u, r);
    ev.gradient = reg_gradient + d.solver->gradient(g);
    ev.factorizations += d.solver->adjoint_factorizations();
    ev.seconds_adjoint = seconds_since(t0);
  }
  ev.status = EvaluationStatus::ok;
  return ev;
}

}  // namespace softhd
