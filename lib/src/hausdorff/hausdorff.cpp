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

namespace {
constexpr EnumNames<Sides, 3> kSidesNames{{{Sides::symmetric, "symmetric"},
                                           {Sides::scan_to_body, "scan_to_body"},
                                           {Sides::visible, "visible"}}};
}  // namespace

std::string to_string(Sides sides) { return enum_name(kSidesNames, sides); }

Sides sides_from_string(const std::string& name) {
  return enum_from_name(kSidesNames, name, "distance");
}

void DistanceForm::validate(Eigen::Index moving_points) const {
  if (!(cap.c == 0.0 || (std::isfinite(cap.c) && cap.c > 0.0))) {
    throw InvalidArgument("distance cap.c must be 0 (no cap) or finite and > 0, got " +
                          std::to_string(cap.c));
  }
  if (!(std::isfinite(cap.q) && cap.q > 0.0)) {
    throw InvalidArgument("distance cap.q must be finite and > 0, got " + std::to_string(cap.q));
  }
  if (sides != Sides::visible) {
    if (visible.size() != 0)
      throw InvalidArgument("distance visible: a mask is given but the distance is " +
                            to_string(sides));
    return;
  }
  if (visible.size() != moving_points) {
    throw InvalidArgument("distance visible: the mask has " + std::to_string(visible.size()) +
                          " entries for " + std::to_string(moving_points) + " moving points");
  }
  if (!visible.any()) throw InvalidArgument("distance visible: no moving point is marked visible");
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
  // The seam of issue 32: the forms beyond the symmetric, uncapped ρ̃ are not evaluated yet.
  if (request.form.sides != Sides::symmetric || request.form.cap.c != 0.0) {
    throw InvalidArgument("distance " + to_string(request.form.sides) +
                          (request.form.cap.c != 0.0 ? " with a cap" : "") +
                          " is not implemented yet");
  }
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

// Exact Hausdorff distance: A = max_j dist(y_j, X), B = max_i dist(x_i, Y), ρ = max(A, B).
HausdorffResult HausdorffTarget::Impl::evaluate_nearest(const PointCloud& X,
                                                        const HausdorffRequest& req) const {
  const int threads = resolve_threads(options.threads);
  const WorkShare* share = options.share.get();
  const detail::NearestIndex moving_tree(X.points());
  check_interrupt("between distance passes");
  Eigen::VectorXd dist_target = moving_tree.distances(cloud.points(), threads, share);
  check_interrupt("between distance passes");
  Eigen::VectorXd dist_moving = tree->distances(X.points(), threads, share);
  HausdorffResult r;
  r.A = dist_target.maxCoeff();
  r.B = dist_moving.maxCoeff();
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
  const Eigen::VectorXd scale_x =
      detail::nearest_distances(*kd, *x_kd, set.threads, set.share).array() + eps;
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
  const double A = detail::power_mean(dt_y, w, beta);

  // Coefficients carried into pass 2: g_j = ∂A/∂d̃_j · (d̃_j + ε)/S_j, with
  // ∂A/∂d̃_j = (W_j/|Y|)(d̃_j/A)^(β−1).
  Eigen::VectorXd a_y, g_y;
  if (req.any_gradient()) {
    a_y.resize(M);
    for (Eigen::Index j = 0; j < M; ++j)
      a_y[j] = detail::power_mean_derivative(dt_y[j], w[j], A, beta);
    g_y = a_y.array() * (dt_y.array() + eps) / p1.S.array();
  }

  // Pass 2, sources over targets: S_i = Σ_j (W_j/|Y|) ((r_min(x_i)+ε)/(r_ij+ε))^α, with
  // G_i = Σ_j (W_j/|Y|) p_ij t_ij (x_i − y_j)/r_ij, and the pass-1 terms scaled by y_j's
  // own scale: H_i = Σ_j g_j p'_ij, G2_i = Σ_j g_j p'_ij t_ij (x_i − y_j)/r_ij.
  const bool need_inner = req.gradient_points || req.gradient_volumes;
  detail::PassSources src_y{&Y.points(), kd.get(), w.data(), nullptr, nullptr};
  detail::PassOuter out_x{&X.points(), x_kd.get(), scale_x.data(), kOuterSum, nullptr};
  if (req.gradient_points) out_x.flags |= kOuterGrad;
  if (need_inner) {
    out_x.flags |= kInner;
    src_y.coef = g_y.data();
    src_y.scale = scale_y.data();
  }
  if (req.differentiate.size() != 0) out_x.mask = &req.differentiate;
  detail::PassSums p2 = detail::run_pass(*backend, src_y, out_x, set);
  account(r, p2);
  if (clip) p2.S = p2.S.cwiseMin(1.0);
  const Eigen::VectorXd dt_x = fields_of(scale_x, p2.S, alpha, eps);  // d̃_Y(x_i)
  const double B = detail::power_mean(dt_x, v, beta);
  const double rho = detail::combine_means(A, B, prm.gamma);

  r.A = A;
  r.B = B;
  r.rho = rho;
  if (req.fields) {
    r.field_target = dt_y;
    r.field_moving = dt_x;
  }
  if (!req.any_gradient()) return r;

  // ∂ρ̃/∂A = ½ (A/ρ̃)^(γ−1), ∂ρ̃/∂B = ½ (B/ρ̃)^(γ−1).
  const double rho_A = detail::power_mean_derivative(A, 0.5, rho, prm.gamma);
  const double rho_B = detail::power_mean_derivative(B, 0.5, rho, prm.gamma);
  // b_i = ∂B/∂d̃_i = (V_i/|X|)(d̃_i/B)^(β−1);  f_i = b_i (d̃_i + ε)/S_i.
  Eigen::VectorXd f_x(N);
  for (Eigen::Index i = 0; i < N; ++i)
    f_x[i] = detail::power_mean_derivative(dt_x[i], v[i], B, beta) * (dt_x[i] + eps) / p2.S[i];
  auto differentiated = [&](Eigen::Index i) {
    return req.differentiate.size() == 0 || req.differentiate[i];
  };

  if (req.gradient_points) {
    // ∂ρ̃/∂x_i = ρ̃_A (V_i/|X|) G2_i + ρ̃_B f_i G_i
    r.gradient_points.setZero(N, d);
    for (Eigen::Index i = 0; i < N; ++i)
      if (differentiated(i))
        r.gradient_points.row(i) = rho_A * v[i] * p2.G2.row(i) + rho_B * f_x[i] * p2.G.row(i);
  }
  if (req.gradient_volumes) {
    // ∂ρ̃/∂V_i = −ρ̃_A/(α|X|) (H_i − Σ_j a_j (d̃_j + ε)) + ρ̃_B B/(β|X|) ((d̃_i/B)^β − 1)
    const double sum_a = (a_y.array() * (dt_y.array() + eps)).sum();
    const double volX = X.total_volume();
    r.gradient_volumes.setZero(N);
    for (Eigen::Index i = 0; i < N; ++i) {
      if (!differentiated(i)) continue;
      const double dA = -(p2.H[i] - sum_a) / (alpha * volX);
      const double dB = B > 0.0 ? B / (beta * volX) * (std::pow(dt_x[i] / B, beta) - 1.0) : 0.0;
      r.gradient_volumes[i] = rho_A * dA + rho_B * dB;
    }
  }
  if (req.gradient_target) {
    // Pass 3, targets over sources with x_i's own scales: G3_j = Σ_i f_i p'_ij t_ij
    // (y_j − x_i)/r_ij. Then ∂ρ̃/∂y_j = ρ̃_A a_j (d̃_j+ε)/S_j G_j + ρ̃_B (W_j/|Y|) G3_j.
    src_x.coef = f_x.data();
    src_x.scale = scale_x.data();
    out_y.flags = kInner;
    const detail::PassSums p3 = detail::run_pass(*backend, src_x, out_y, set);
    account(r, p3);
    r.gradient_target.resize(M, d);
    for (Eigen::Index j = 0; j < M; ++j)
      r.gradient_target.row(j) = rho_A * g_y[j] * p1.G.row(j) + rho_B * w[j] * p3.G2.row(j);
  }
  return r;
}

HausdorffResult hausdorff(const PointCloud& moving, const PointCloud& target,
                          const HausdorffOptions& options, const HausdorffRequest& request) {
  return HausdorffTarget(target, options).evaluate(moving, request);
}

}  // namespace softhd
