// Orchestration of the regularised Hausdorff evaluation (docs/formulation.md §2): nearest
// distances, the two pair passes (and a third for target gradients), the means and the chain rule.

#include "softhd/hausdorff.hpp"

#include <algorithm>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <sstream>

#include "dual_tree.hpp"
#include "hessian.hpp"
#include "nearest_index.hpp"
#include "pair_backend.hpp"
#include "scaled_means.hpp"
#include "side_means.hpp"
#include "softhd/enum_names.hpp"
#include "softhd/error.hpp"
#include "softhd/interrupt.hpp"
#include "softhd/parallel.hpp"

namespace softhd {

namespace {

// Finite and at least `least` (> 0), `why` saying where that bound comes from.
void check_positive(double value, const char* name, double least, const char* why) {
  std::ostringstream msg;
  msg << "Hausdorff parameter " << name;
  if (!std::isfinite(value) || !(value > 0.0)) {
    msg << " must be finite and > 0, got " << value;
    throw InvalidArgument(msg.str());
  }
  if (value < least) {
    msg << " must be at least " << least << ", got " << value << " (" << why << ")";
    throw InvalidArgument(msg.str());
  }
}

}  // namespace

void HausdorffParams::validate() const {
  // Subnormal exponents: their inverses overflow.
  const char* normal = "the smallest normal double";
  check_positive(alpha, "alpha", DBL_MIN, normal);
  check_positive(beta, "beta", DBL_MIN, normal);
  check_positive(gamma, "gamma", DBL_MIN, normal);
  check_positive(epsilon, "epsilon", kMinEpsilon, "below it 1/epsilon overflows the gradients");
}

void HausdorffOptions::validate() const {
  params.validate();
  check_threads(threads);
  if (!(tolerance > 0.0 && tolerance < 1.0)) {
    std::ostringstream msg;
    msg << "Hausdorff option tolerance must be in (0, 1), got " << tolerance;
    throw InvalidArgument(msg.str());
  }
}

void check_coordinates(const PointCloud& cloud, const std::string& which) {
  Eigen::Index row = 0, col = 0;
  const double largest = cloud.points().cwiseAbs().maxCoeff(&row, &col);
  if (largest > kMaxCoordinate) {
    std::ostringstream msg;
    msg << which << " cloud: point " << row + 1 << " has a coordinate of magnitude " << largest
        << ", above the limit of " << kMaxCoordinate << " (rescale the clouds and epsilon)";
    throw InvalidArgument(msg.str());
  }
}

constexpr auto kMethodNames = enum_sequence<Method::nearest>({"exact", "tree", "nearest"});

std::string to_string(Method method) { return enum_name(kMethodNames, method); }

Method method_from_string(const std::string& name) {
  return enum_from_name(kMethodNames, name, "method");
}

constexpr auto kQuadratureNames = enum_sequence<Quadrature::cells>({"collocation", "cells"});

std::string to_string(Quadrature quadrature) { return enum_name(kQuadratureNames, quadrature); }

Quadrature quadrature_from_string(const std::string& name) {
  return enum_from_name(kQuadratureNames, name, "quadrature");
}

struct SumsEvaluation;  // one evaluation by pair sums, step by step (below)

struct HausdorffTarget::Impl {
  Impl(PointCloud c, HausdorffOptions o) : cloud(std::move(c)), options(o) {
    weights = cloud.volumes() / cloud.total_volume();  // W_j/|Y|
    if (options.method == Method::nearest) {
      tree = std::make_unique<detail::NearestIndex>(cloud.points());
    } else {
      if (options.method == Method::tree) {
        detail::DualTreeConfig config;
        config.cost_model = options.tree_fallback;
        backend = detail::make_dual_tree_backend(config, nullptr);
      } else {
        backend = detail::make_exact_backend();
      }
      // The target's tree serves every evaluation: the nearest-source distances both ways
      // (every backend), and with a tree backend the sources of pass 2, the outer points
      // of passes 1 and 3.
      kd = std::make_unique<detail::KdTree>(cloud.points(), detail::kLeafSize);
    }
  }
  PointCloud cloud;
  HausdorffOptions options;
  std::unique_ptr<detail::NearestIndex> tree;  // method nearest
  Eigen::VectorXd weights;
  std::unique_ptr<detail::PairSumBackend> backend;
  std::unique_ptr<detail::KdTree> kd;  // methods exact and tree

  HausdorffResult evaluate_nearest(const PointCloud& X, const HausdorffRequest& req) const;
  HausdorffResult evaluate_sums(const PointCloud& X, const HausdorffRequest& req) const;
  // The steps of evaluate_sums.
  void nearest_scales(SumsEvaluation* e) const;
  void pass_a(SumsEvaluation* e, HausdorffResult* r) const;
  void pass_b(SumsEvaluation* e, HausdorffResult* r) const;
  void point_gradient(const SumsEvaluation& e, double rho_A, double rho_B,
                      HausdorffResult* r) const;
  void volume_gradient(const SumsEvaluation& e, double rho_A, double rho_B,
                       HausdorffResult* r) const;
  void target_gradient(SumsEvaluation* e, double rho_A, double rho_B, HausdorffResult* r) const;
  std::shared_ptr<const HausdorffHessian> hessian_state(const SumsEvaluation& e,
                                                        const HausdorffResult& r, double rho_A,
                                                        double rho_B) const;
};

HausdorffTarget::HausdorffTarget(PointCloud target, HausdorffOptions options) {
  options.validate();
  if (options.quadrature == Quadrature::cells)
    throw InvalidArgument(
        "quadrature cells needs bodies with cells (an objective with a target that has cells); "
        "a point cloud target uses quadrature collocation");
  check_coordinates(target, "target");
  impl_ = std::make_unique<Impl>(std::move(target), options);
}
HausdorffTarget::~HausdorffTarget() = default;
HausdorffTarget::HausdorffTarget(HausdorffTarget&&) noexcept = default;
HausdorffTarget& HausdorffTarget::operator=(HausdorffTarget&&) noexcept = default;

const PointCloud& HausdorffTarget::cloud() const { return impl_->cloud; }
const HausdorffOptions& HausdorffTarget::options() const { return impl_->options; }

HausdorffResult HausdorffTarget::evaluate(const PointCloud& moving,
                                          const HausdorffRequest& request) const {
  const auto start = std::chrono::steady_clock::now();
  if (moving.dim() != impl_->cloud.dim()) {
    throw InvalidArgument("moving cloud is " + std::to_string(moving.dim()) +
                          "D but the target is " + std::to_string(impl_->cloud.dim()) + "D");
  }
  check_coordinates(moving, "moving");
  if (request.differentiate.size() != 0 && request.differentiate.size() != moving.size()) {
    throw InvalidArgument("differentiate mask has " + std::to_string(request.differentiate.size()) +
                          " entries for " + std::to_string(moving.size()) + " moving points");
  }
  request.form.validate(moving.size());
  check_cap_length(request.form.cap, moving, impl_->cloud);
  HausdorffResult result;
  if (impl_->options.method == Method::nearest) {
    if (request.any_gradient() || request.hessian_points) {
      throw InvalidArgument("method nearest computes no gradient (use method exact or tree)");
    }
    result = impl_->evaluate_nearest(moving, request);
  } else if (request.hessian_points && !request.gradient_points) {
    // The Hessian's state comes from the point gradient's passes; the gradient is not returned.
    HausdorffRequest with_gradient = request;
    with_gradient.gradient_points = true;
    result = impl_->evaluate_sums(moving, with_gradient);
    result.gradient_points.resize(0, 0);
  } else {
    result = impl_->evaluate_sums(moving, request);  // exact or tree
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

// Exact Hausdorff distance: A = max_j ψ(dist(y_j, X)), B = max_i ψ(dist(x_i, Y)) (over the
// visible points for Sides::visible; 0 for scan_to_body, whose query is made for the fields
// only), ρ = max(A, B) (scan_to_body: A). ψ is monotone, so ψ(max) = max ψ.
HausdorffResult HausdorffTarget::Impl::evaluate_nearest(const PointCloud& X,
                                                        const HausdorffRequest& req) const {
  const int threads = resolve_threads(options.threads);
  const WorkShare* share = options.share.get();
  const DistanceForm& form = req.form;
  const bool one_sided = form.sides == Sides::scan_to_body;
  const detail::NearestIndex moving_tree(X.points());
  check_interrupt("between distance passes");
  Eigen::VectorXd dist_target = moving_tree.distances(cloud.points(), threads, share);
  Eigen::VectorXd dist_moving;
  if (!one_sided || req.fields) {
    check_interrupt("between distance passes");
    dist_moving = tree->distances(X.points(), threads, share);
  }
  HausdorffResult r;
  r.A = detail::soft_cap(dist_target.maxCoeff(), form.cap.c, form.cap.q);
  if (!one_sided) {
    const double largest = form.sides == Sides::visible
                               ? form.camera_mask.select(dist_moving.array(), 0.0).maxCoeff()
                               : dist_moving.maxCoeff();
    r.B = detail::soft_cap(largest, form.cap.c, form.cap.q);
  }
  r.rho = std::max(r.A, r.B);
  if (req.fields) {
    r.field_target = std::move(dist_target);
    r.field_moving = std::move(dist_moving);
  }
  return r;
}

namespace {

/// Adds one pass's counts to the evaluation's.
void account(HausdorffResult& r, const detail::PassSums& p) {
  r.kernel_evaluations += p.kernel_evaluations;
  r.work.near_pairs += p.stats.near_pairs;
  r.work.far_kernel += p.stats.far_kernel;
  r.work.far_basis += p.stats.far_basis;
  r.work.node_pairs += p.stats.node_pairs;
  r.work.bound_axes += p.stats.bound_axes;
  r.work.plan_seconds += p.stats.plan_seconds;
  r.work.run_seconds += p.stats.run_seconds;
  r.work.exact_passes += p.stats.fell_back ? 1 : 0;
  r.work.passes += 1;
}

/// d̃ of every outer point from its scale c = r_min + ε and kernel sum S.
Eigen::VectorXd fields_of(const Eigen::VectorXd& scale, const Eigen::VectorXd& S, double alpha,
                          double eps) {
  Eigen::VectorXd dt(S.size());
  for (Eigen::Index j = 0; j < S.size(); ++j)
    dt[j] = detail::regularised_distance(scale[j] - eps, S[j], alpha, eps);
  return dt;
}

}  // namespace

/// One evaluation by pair sums, step by step: its inputs, the scales c = r_min + ε of every
/// point, the two (or three) passes' sums, the fields, the β-means and their slopes.
struct SumsEvaluation {
  SumsEvaluation(const PointCloud& moving, const PointCloud& target, const HausdorffRequest& r,
                 const HausdorffParams& params)
      : X(moving), Y(target), req(r), prm(params), one_sided(r.form.sides == Sides::scan_to_body) {}
  const PointCloud& X;
  const PointCloud& Y;
  const HausdorffRequest& req;
  const HausdorffParams& prm;
  bool one_sided, need_inner = false, pass2 = false, clip = false;
  detail::PassSettings set;
  Eigen::VectorXd v;  // V_i/|X|
  std::unique_ptr<detail::KdTree> x_kd;
  Eigen::VectorXd scale_y, scale_x;
  detail::PassSums p1, p2;
  Eigen::VectorXd dt_y, dt_x;  // d̃_X(y_j), d̃_Y(x_i)
  detail::SideMean mean_a, mean_b;
  double volume_b = 0.0;
  Eigen::VectorXd g_y, f_x;  // pass-2 and pass-3 coefficients
};

HausdorffResult HausdorffTarget::Impl::evaluate_sums(const PointCloud& X,
                                                     const HausdorffRequest& req) const {
  SumsEvaluation e(X, cloud, req, options.params);
  const detail::KernelPower power(e.prm.alpha);
  e.set.power = &power;
  e.set.eps = e.prm.epsilon;
  e.set.tau = options.tolerance;
  e.set.threads = resolve_threads(options.threads);
  e.set.share = options.share.get();
  e.v = X.volumes() / X.total_volume();
  // Every exact S is ≤ 1 (each term ≤ its weight, the weights sum to 1), so clipping an
  // approximate sum at 1 only moves it towards the exact value and keeps d̃ ≥ r_min ≥ 0.
  e.clip = options.method != Method::exact;
  nearest_scales(&e);
  HausdorffResult r;
  pass_a(&e, &r);
  pass_b(&e, &r);
  r.A = e.mean_a.value;
  r.B = e.mean_b.value;
  r.rho = e.one_sided ? r.A : detail::combine_means(r.A, r.B, e.prm.gamma);
  if (req.fields) {
    r.field_target = e.dt_y;
    r.field_moving = e.dt_x;
  }
  if (!req.any_gradient()) return r;
  const auto [rho_A, rho_B] = detail::rho_slopes(r.A, r.B, r.rho, e.prm.gamma, req.form.sides);
  // f_i = b_i (d̃_i + ε)/S_i (zero for scan_to_body).
  e.f_x = Eigen::VectorXd::Zero(X.size());
  if (!e.one_sided)
    e.f_x = e.mean_b.slope.array() * (e.dt_x.array() + e.prm.epsilon) / e.p2.S.array();
  if (req.gradient_points) point_gradient(e, rho_A, rho_B, &r);
  if (req.gradient_volumes) volume_gradient(e, rho_A, rho_B, &r);
  if (req.gradient_target) target_gradient(&e, rho_A, rho_B, &r);
  if (req.hessian_points) r.hessian = hessian_state(e, r, rho_A, rho_B);
  return r;
}

/// The scales c = r_min + ε of every point, from the k-d trees, leaf by leaf (each leaf's
/// candidates found once). x_i's scales serve pass 2 (and 3), which scan_to_body skips for
/// its value alone.
void HausdorffTarget::Impl::nearest_scales(SumsEvaluation* e) const {
  const double eps = e->prm.epsilon;
  e->x_kd = std::make_unique<detail::KdTree>(e->X.points(), detail::kLeafSize);
  e->scale_y = detail::nearest_distances(*e->x_kd, *kd, e->set.threads, e->set.share).array() + eps;
  e->need_inner = e->req.gradient_points || e->req.gradient_volumes;
  e->pass2 = !e->one_sided || e->req.fields || e->need_inner;
  if (e->pass2)
    e->scale_x =
        detail::nearest_distances(*kd, *e->x_kd, e->set.threads, e->set.share).array() + eps;
}

/// Pass 1, targets over sources: S_j = Σ_i (V_i/|X|) ((r_min(y_j)+ε)/(r_ij+ε))^α, and for
/// target gradients G_j = Σ_i (V_i/|X|) p_ij t_ij (y_j − x_i)/r_ij; then the fields d̃_X(y_j)
/// and A = (Σ_j (W_j/|Y|) ψ(d̃_j)^β)^(1/β) with a_j = ∂A/∂d̃_j = (W_j/|Y|)(ψ_j/A)^(β−1) ψ'_j,
/// and the coefficients carried into pass 2: g_j = a_j (d̃_j + ε)/S_j.
void HausdorffTarget::Impl::pass_a(SumsEvaluation* e, HausdorffResult* r) const {
  const double eps = e->prm.epsilon;
  detail::PassSources src_x{&e->X.points(), e->x_kd.get(), e->v.data(), nullptr, nullptr};
  detail::PassOuter out_y{&e->Y.points(), kd.get(), e->scale_y.data(), detail::kOuterSum, nullptr};
  if (e->req.gradient_target) out_y.flags |= detail::kOuterGrad;
  e->p1 = detail::run_pass(*backend, src_x, out_y, e->set);
  account(*r, e->p1);
  if (e->clip) e->p1.S = e->p1.S.cwiseMin(1.0);
  e->dt_y = fields_of(e->scale_y, e->p1.S, e->prm.alpha, eps);
  e->mean_a =
      detail::side_mean(e->dt_y, weights, e->req.form.cap, e->prm.beta, e->req.any_gradient());
  if (e->req.any_gradient())
    e->g_y = e->mean_a.slope.array() * (e->dt_y.array() + eps) / e->p1.S.array();
}

/// Pass 2, sources over targets: S_i = Σ_j (W_j/|Y|) ((r_min(x_i)+ε)/(r_ij+ε))^α, with
/// G_i = Σ_j (W_j/|Y|) p_ij t_ij (x_i − y_j)/r_ij, and the pass-1 terms scaled by y_j's
/// own scale: H_i = Σ_j g_j p'_ij, G2_i = Σ_j g_j p'_ij t_ij (x_i − y_j)/r_ij.
/// scan_to_body needs neither S_i (but for the fields) nor G_i: only H_i, G2_i for A.
/// Then d̃_Y(x_i) and B = (Σ_i u_i ψ(d̃_i)^β)^(1/β), u_i = V_i/|X| (symmetric) or V_i/|V| on the
/// visible points (B_V, |V| = Σ_{k visible} V_k); b_i = ∂B/∂d̃_i = u_i (ψ_i/B)^(β−1) ψ'_i.
void HausdorffTarget::Impl::pass_b(SumsEvaluation* e, HausdorffResult* r) const {
  const HausdorffRequest& req = e->req;
  detail::PassSources src_y{&e->Y.points(), kd.get(), weights.data(), nullptr, nullptr};
  detail::PassOuter out_x{&e->X.points(), e->x_kd.get(), e->scale_x.data(), 0u, nullptr};
  if (!e->one_sided || req.fields) out_x.flags |= detail::kOuterSum;
  if (req.gradient_points && !e->one_sided) out_x.flags |= detail::kOuterGrad;
  if (e->need_inner) {
    out_x.flags |= detail::kInner;
    src_y.coef = e->g_y.data();
    src_y.scale = e->scale_y.data();
  }
  // The mask leaves masked points with S alone: only where S is summed anyway.
  if (req.differentiate.size() != 0 && (out_x.flags & detail::kOuterSum))
    out_x.mask = &req.differentiate;
  if (e->pass2) {
    e->p2 = detail::run_pass(*backend, src_y, out_x, e->set);
    account(*r, e->p2);
  }
  if (out_x.flags & detail::kOuterSum) {
    if (e->clip) e->p2.S = e->p2.S.cwiseMin(1.0);
    e->dt_x = fields_of(e->scale_x, e->p2.S, e->prm.alpha, e->prm.epsilon);
  }
  if (!e->one_sided)
    e->mean_b = detail::side_mean(
        e->dt_x, detail::b_weights(e->X, req.form, e->volume_b), req.form.cap, e->prm.beta,
        req.any_gradient(), req.form.sides == Sides::visible ? &req.form.camera_mask : nullptr);
}

/// ∂ρ̃/∂x_i = ρ̃_A (V_i/|X|) G2_i + ρ̃_B f_i G_i.
void HausdorffTarget::Impl::point_gradient(const SumsEvaluation& e, double rho_A, double rho_B,
                                           HausdorffResult* r) const {
  const HausdorffRequest& req = e.req;
  r->gradient_points.setZero(e.X.size(), e.X.dim());
  for (Eigen::Index i = 0; i < e.X.size(); ++i) {
    if (req.differentiate.size() != 0 && !req.differentiate[i]) continue;
    r->gradient_points.row(i) = rho_A * e.v[i] * e.p2.G2.row(i);
    if (!e.one_sided) r->gradient_points.row(i) += rho_B * e.f_x[i] * e.p2.G.row(i);
  }
}

/// ∂ρ̃/∂V_i = −ρ̃_A/(α|X|) (H_i − Σ_j a_j (d̃_j + ε)) + ρ̃_B ∂B/∂V_i, with
/// ∂B/∂V_i = B/(β|U|) ((ψ_i/B)^β − 1) for the points in B's mean (|U| = |X| or |V|),
/// 0 for the others.
void HausdorffTarget::Impl::volume_gradient(const SumsEvaluation& e, double rho_A, double rho_B,
                                            HausdorffResult* r) const {
  const HausdorffRequest& req = e.req;
  const double alpha = e.prm.alpha, beta = e.prm.beta, B = e.mean_b.value;
  const double sum_a = (e.mean_a.slope.array() * (e.dt_y.array() + e.prm.epsilon)).sum();
  const double volX = e.X.total_volume();
  r->gradient_volumes.setZero(e.X.size());
  for (Eigen::Index i = 0; i < e.X.size(); ++i) {
    if (req.differentiate.size() != 0 && !req.differentiate[i]) continue;
    const double dA = -(e.p2.H[i] - sum_a) / (alpha * volX);
    const bool in_b = !e.one_sided && (req.form.sides != Sides::visible || req.form.camera_mask[i]);
    const double dB = in_b && B > 0.0
                          ? B / (beta * e.volume_b) * (std::pow(e.mean_b.capped[i] / B, beta) - 1.0)
                          : 0.0;
    r->gradient_volumes[i] = rho_A * dA + rho_B * dB;
  }
}

/// ∂ρ̃/∂y_j = ρ̃_A g_j G_j + ρ̃_B (W_j/|Y|) G3_j, with pass 3 (B's part; not for
/// scan_to_body), targets over sources with x_i's own scales:
/// G3_j = Σ_i f_i p'_ij t_ij (y_j − x_i)/r_ij.
void HausdorffTarget::Impl::target_gradient(SumsEvaluation* e, double rho_A, double rho_B,
                                            HausdorffResult* r) const {
  const Eigen::Index M = e->Y.size();
  r->gradient_target.resize(M, e->Y.dim());
  for (Eigen::Index j = 0; j < M; ++j)
    r->gradient_target.row(j) = rho_A * e->g_y[j] * e->p1.G.row(j);
  if (e->one_sided) return;
  detail::PassSources src_x{&e->X.points(), e->x_kd.get(), e->v.data(), e->f_x.data(),
                            e->scale_x.data()};
  detail::PassOuter out_y{&e->Y.points(), kd.get(), e->scale_y.data(), detail::kInner, nullptr};
  const detail::PassSums p3 = detail::run_pass(*backend, src_x, out_y, e->set);
  account(*r, p3);
  for (Eigen::Index j = 0; j < M; ++j)
    r->gradient_target.row(j) += rho_B * weights[j] * p3.G2.row(j);
}

/// What a Hessian-vector product reuses (hessian.hpp): the moving points, the scales, sums,
/// fields (D = d̃ + ε), capped fields and slopes of both sides, n_i = G_i/S_i, ρ̃ and its slopes.
std::shared_ptr<const HausdorffHessian> HausdorffTarget::Impl::hessian_state(
    const SumsEvaluation& e, const HausdorffResult& r, double rho_A, double rho_B) const {
  auto h = std::make_shared<HausdorffHessian>();
  h->owner = this;
  h->x = e.X.points();
  h->v = e.v;
  h->form = e.req.form;
  h->differentiate = e.req.differentiate;
  h->prm = e.prm;
  h->A = r.A;
  h->B = r.B;
  h->rho = r.rho;
  h->rho_A = rho_A;
  h->rho_B = rho_B;
  h->scale_y = e.scale_y;
  h->S_y = e.p1.S;
  h->D_y = e.dt_y.array() + e.prm.epsilon;
  h->a = e.mean_a.slope;
  h->psi_y = e.mean_a.capped;
  if (!e.one_sided) {
    h->scale_x = e.scale_x;
    h->S_x = e.p2.S;
    h->D_x = e.dt_x.array() + e.prm.epsilon;
    h->b = e.mean_b.slope;
    h->psi_x = e.mean_b.capped;
    h->n_x = e.p2.G.array().colwise() / e.p2.S.array();
  }
  return h;
}

Eigen::MatrixXd HausdorffTarget::hessian_product(const HausdorffResult& at,
                                                 const Eigen::MatrixXd& v, HessianPart part,
                                                 SumWork* work) const {
  if (at.hessian == nullptr)
    throw InvalidArgument(
        "hessian_product: the result has no Hessian state (evaluate with hessian_points)");
  const HausdorffHessian& h = *at.hessian;
  if (h.owner != impl_.get())
    throw InvalidArgument("hessian_product: the result was evaluated against another target");
  if (v.rows() != h.x.rows() || v.cols() != h.x.cols()) {
    throw InvalidArgument("hessian_product: the direction is " + std::to_string(v.rows()) + " by " +
                          std::to_string(v.cols()) + " for " + std::to_string(h.x.rows()) +
                          " moving points in " + std::to_string(h.x.cols()) + "D");
  }
  SumWork local;
  Eigen::MatrixXd out = detail::hessian_product(h, impl_->cloud.points(), impl_->weights, v, part,
                                                resolve_threads(impl_->options.threads), &local);
  // Method tree: the product's pairs are all summed directly (docs/formulation.md §2.7).
  if (impl_->options.method == Method::tree) local.exact_passes = local.passes;
  if (work != nullptr) *work = local;
  return out;
}

HausdorffResult hausdorff(const PointCloud& moving, const PointCloud& target,
                          const HausdorffOptions& options, const HausdorffRequest& request) {
  return HausdorffTarget(target, options).evaluate(moving, request);
}

}  // namespace softhd
