// Orchestration of the regularised Hausdorff evaluation (docs/formulation.md §2): nearest
// distances, the two pair passes (and a third for target gradients), the means and the chain rule.

#include "softhd/hausdorff.hpp"

#include <algorithm>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <sstream>

#include "dual_tree.hpp"
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

namespace {
constexpr EnumNames<Method, 3> kMethodNames{
    {{Method::exact, "exact"}, {Method::tree, "tree"}, {Method::nearest, "nearest"}}};
}  // namespace

std::string to_string(Method method) { return enum_name(kMethodNames, method); }

Method method_from_string(const std::string& name) {
  return enum_from_name(kMethodNames, name, "method");
}

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
};

HausdorffTarget::HausdorffTarget(PointCloud target, HausdorffOptions options) {
  options.validate();
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
    if (request.any_gradient()) {
      throw InvalidArgument("method nearest computes no gradient (use method exact or tree)");
    }
    result = impl_->evaluate_nearest(moving, request);
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
                               ? form.visible.select(dist_moving.array(), 0.0).maxCoeff()
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

HausdorffResult HausdorffTarget::Impl::evaluate_sums(const PointCloud& X,
                                                     const HausdorffRequest& req) const {
  using detail::kInner;
  using detail::kOuterGrad;
  using detail::kOuterSum;
  const PointCloud& Y = cloud;
  const HausdorffParams& prm = options.params;
  const DistanceForm& form = req.form;
  const bool one_sided = form.sides == Sides::scan_to_body;
  const double alpha = prm.alpha, beta = prm.beta, eps = prm.epsilon;
  const int d = X.dim();
  const Eigen::Index N = X.size(), M = Y.size();
  const detail::KernelPower power(alpha);
  detail::PassSettings set;
  set.power = &power;
  set.eps = eps;
  set.tau = options.tolerance;
  set.threads = resolve_threads(options.threads);
  set.share = options.share.get();
  const Eigen::VectorXd v = X.volumes() / X.total_volume();  // V_i/|X|
  const Eigen::VectorXd& w = weights;                        // W_j/|Y|

  // Scales c = r_min + ε of every point, from the k-d trees, leaf by leaf (each leaf's
  // candidates found once).
  const auto x_kd = std::make_unique<detail::KdTree>(X.points(), detail::kLeafSize);
  const Eigen::VectorXd scale_y =
      detail::nearest_distances(*x_kd, *kd, set.threads, set.share).array() + eps;
  // x_i's scales serve pass 2 (and 3), which scan_to_body skips for its value alone.
  const bool need_inner = req.gradient_points || req.gradient_volumes;
  const bool pass2 = !one_sided || req.fields || need_inner;
  Eigen::VectorXd scale_x;
  if (pass2) scale_x = detail::nearest_distances(*kd, *x_kd, set.threads, set.share).array() + eps;
  // Every exact S is ≤ 1 (each term ≤ its weight, the weights sum to 1), so clipping an
  // approximate sum at 1 only moves it towards the exact value and keeps d̃ ≥ r_min ≥ 0.
  const bool clip = options.method != Method::exact;
  HausdorffResult r;

  // Pass 1, targets over sources: S_j = Σ_i (V_i/|X|) ((r_min(y_j)+ε)/(r_ij+ε))^α, and for
  // target gradients G_j = Σ_i (V_i/|X|) p_ij t_ij (y_j − x_i)/r_ij.
  detail::PassSources src_x{&X.points(), x_kd.get(), v.data(), nullptr, nullptr};
  detail::PassOuter out_y{&Y.points(), kd.get(), scale_y.data(), kOuterSum, nullptr};
  if (req.gradient_target) out_y.flags |= kOuterGrad;
  detail::PassSums p1 = detail::run_pass(*backend, src_x, out_y, set);
  account(r, p1);
  if (clip) p1.S = p1.S.cwiseMin(1.0);
  const Eigen::VectorXd dt_y = fields_of(scale_y, p1.S, alpha, eps);  // d̃_X(y_j)
  // A = (Σ_j (W_j/|Y|) ψ(d̃_j)^β)^(1/β); a_j = ∂A/∂d̃_j = (W_j/|Y|)(ψ_j/A)^(β−1) ψ'_j.
  const detail::SideMean mean_a = detail::side_mean(dt_y, w, form.cap, beta, req.any_gradient());
  const double A = mean_a.value;
  const Eigen::VectorXd& a_y = mean_a.slope;

  // Coefficients carried into pass 2: g_j = a_j (d̃_j + ε)/S_j.
  Eigen::VectorXd g_y;
  if (req.any_gradient()) g_y = a_y.array() * (dt_y.array() + eps) / p1.S.array();

  // Pass 2, sources over targets: S_i = Σ_j (W_j/|Y|) ((r_min(x_i)+ε)/(r_ij+ε))^α, with
  // G_i = Σ_j (W_j/|Y|) p_ij t_ij (x_i − y_j)/r_ij, and the pass-1 terms scaled by y_j's
  // own scale: H_i = Σ_j g_j p'_ij, G2_i = Σ_j g_j p'_ij t_ij (x_i − y_j)/r_ij.
  // scan_to_body needs neither S_i (but for the fields) nor G_i: only H_i, G2_i for A.
  detail::PassSources src_y{&Y.points(), kd.get(), w.data(), nullptr, nullptr};
  detail::PassOuter out_x{&X.points(), x_kd.get(), scale_x.data(), 0u, nullptr};
  if (!one_sided || req.fields) out_x.flags |= kOuterSum;
  if (req.gradient_points && !one_sided) out_x.flags |= kOuterGrad;
  if (need_inner) {
    out_x.flags |= kInner;
    src_y.coef = g_y.data();
    src_y.scale = scale_y.data();
  }
  // The mask leaves masked points with S alone: only where S is summed anyway.
  if (req.differentiate.size() != 0 && (out_x.flags & kOuterSum)) out_x.mask = &req.differentiate;
  detail::PassSums p2;
  if (pass2) {
    p2 = detail::run_pass(*backend, src_y, out_x, set);
    account(r, p2);
  }
  Eigen::VectorXd dt_x;  // d̃_Y(x_i)
  if (out_x.flags & kOuterSum) {
    if (clip) p2.S = p2.S.cwiseMin(1.0);
    dt_x = fields_of(scale_x, p2.S, alpha, eps);
  }
  // B = (Σ_i u_i ψ(d̃_i)^β)^(1/β), u_i = V_i/|X| (symmetric) or V_i/|V| on the visible
  // points (B_V, |V| = Σ_{k visible} V_k); b_i = ∂B/∂d̃_i = u_i (ψ_i/B)^(β−1) ψ'_i.
  double volume_b = 0.0;
  detail::SideMean mean_b;
  if (!one_sided)
    mean_b = detail::side_mean(dt_x, detail::b_weights(X, form, volume_b), form.cap, beta,
                               req.any_gradient(),
                               form.sides == Sides::visible ? &form.visible : nullptr);
  const double B = mean_b.value;
  const double rho = one_sided ? A : detail::combine_means(A, B, prm.gamma);

  r.A = A;
  r.B = B;
  r.rho = rho;
  if (req.fields) {
    r.field_target = dt_y;
    r.field_moving = dt_x;
  }
  if (!req.any_gradient()) return r;

  const auto [rho_A, rho_B] = detail::rho_slopes(A, B, rho, prm.gamma, form.sides);
  // f_i = b_i (d̃_i + ε)/S_i (zero for scan_to_body).
  Eigen::VectorXd f_x = Eigen::VectorXd::Zero(N);
  if (!one_sided) f_x = mean_b.slope.array() * (dt_x.array() + eps) / p2.S.array();
  auto differentiated = [&](Eigen::Index i) {
    return req.differentiate.size() == 0 || req.differentiate[i];
  };

  if (req.gradient_points) {
    // ∂ρ̃/∂x_i = ρ̃_A (V_i/|X|) G2_i + ρ̃_B f_i G_i
    r.gradient_points.setZero(N, d);
    for (Eigen::Index i = 0; i < N; ++i) {
      if (!differentiated(i)) continue;
      r.gradient_points.row(i) = rho_A * v[i] * p2.G2.row(i);
      if (!one_sided) r.gradient_points.row(i) += rho_B * f_x[i] * p2.G.row(i);
    }
  }
  if (req.gradient_volumes) {
    // ∂ρ̃/∂V_i = −ρ̃_A/(α|X|) (H_i − Σ_j a_j (d̃_j + ε)) + ρ̃_B ∂B/∂V_i, with
    // ∂B/∂V_i = B/(β|U|) ((ψ_i/B)^β − 1) for the points in B's mean (|U| = |X| or |V|),
    // 0 for the others.
    const double sum_a = (a_y.array() * (dt_y.array() + eps)).sum();
    const double volX = X.total_volume();
    r.gradient_volumes.setZero(N);
    for (Eigen::Index i = 0; i < N; ++i) {
      if (!differentiated(i)) continue;
      const double dA = -(p2.H[i] - sum_a) / (alpha * volX);
      const bool in_b = !one_sided && (form.sides != Sides::visible || form.visible[i]);
      const double dB = in_b && B > 0.0
                            ? B / (beta * volume_b) * (std::pow(mean_b.capped[i] / B, beta) - 1.0)
                            : 0.0;
      r.gradient_volumes[i] = rho_A * dA + rho_B * dB;
    }
  }
  if (req.gradient_target) {
    // ∂ρ̃/∂y_j = ρ̃_A g_j G_j + ρ̃_B (W_j/|Y|) G3_j, with pass 3 (B's part; not for
    // scan_to_body), targets over sources with x_i's own scales:
    // G3_j = Σ_i f_i p'_ij t_ij (y_j − x_i)/r_ij.
    r.gradient_target.resize(M, d);
    for (Eigen::Index j = 0; j < M; ++j) r.gradient_target.row(j) = rho_A * g_y[j] * p1.G.row(j);
    if (!one_sided) {
      src_x.coef = f_x.data();
      src_x.scale = scale_x.data();
      out_y.flags = kInner;
      const detail::PassSums p3 = detail::run_pass(*backend, src_x, out_y, set);
      account(r, p3);
      for (Eigen::Index j = 0; j < M; ++j) r.gradient_target.row(j) += rho_B * w[j] * p3.G2.row(j);
    }
  }
  return r;
}

HausdorffResult hausdorff(const PointCloud& moving, const PointCloud& target,
                          const HausdorffOptions& options, const HausdorffRequest& request) {
  return HausdorffTarget(target, options).evaluate(moving, request);
}

}  // namespace softhd
