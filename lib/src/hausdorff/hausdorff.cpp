// Orchestration of the regularised Hausdorff evaluation (docs/formulation.md §2): nearest
// distances, the two pair passes (and a third for target gradients), the means and the chain rule.

#include "softhd/hausdorff.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include "kd_tree.hpp"
#include "nearest_index.hpp"
#include "pair_kernel.hpp"
#include "scaled_means.hpp"
#include "softhd/error.hpp"
#include "tree_sums.hpp"

namespace softhd {

namespace {

void check_positive(double value, const char* name) {
  if (!std::isfinite(value) || !(value > 0.0)) {
    std::ostringstream msg;
    msg << "Hausdorff parameter " << name << " must be finite and > 0, got " << value;
    throw InvalidArgument(msg.str());
  }
}

/// Inner points of a pass in structure-of-arrays form. Eigen's N by d column-major
/// storage already has one contiguous array per coordinate.
detail::PairSources sources_of(const PointCloud& cloud) {
  detail::PairSources s;
  s.dim = cloud.dim();
  s.size = cloud.size();
  for (int k = 0; k < s.dim; ++k) s.coord[k] = cloud.points().col(k).data();
  return s;
}

constexpr int kLeafSize = 32;  // points per leaf: fewest kernel evaluations (docs/benchmarks.md)

/// The sources of one pair pass: all of them (method exact), or a tree over them with
/// node moments (method tree, `tree.tree` set).
struct PassSources {
  detail::PairSources src;  // caller's order (exact) or tree order (tree)
  detail::TreePass tree;
};

/// Computes the pair sums of every point of `outer` (OpenMP over the outer points; each
/// result depends on its own point only, so any thread count gives the same bits), in
/// the order `visit` (empty: 0..n−1; tree order keeps neighbouring points together).
/// `flags_of(i)` selects the sums needed for outer point i. Returns the number of
/// kernel evaluations made.
template <class Flags, class Store>
std::int64_t sweep(const PointCloud& outer, const Eigen::VectorXd& outer_scale,
                   const std::vector<Eigen::Index>& visit, const PassSources& pass,
                   const detail::KernelPower& power, double eps, double tau, int threads,
                   Flags flags_of, Store store) {
  const Eigen::Index n = outer.size();
  const int d = outer.dim();
  const Eigen::MatrixXd& P = outer.points();
  const bool use_tree = pass.tree.tree != nullptr;
  const double work = static_cast<double>(n) * static_cast<double>(pass.src.size);
  const bool parallel = use_tree ? n > 64 : work > 2.0e4;
  std::int64_t evaluations = 0;
#pragma omp parallel for schedule(dynamic, 16) num_threads(threads) if (parallel) \
    reduction(+ : evaluations)
  for (Eigen::Index q = 0; q < n; ++q) {
    const Eigen::Index i = visit.empty() ? q : visit[static_cast<size_t>(q)];
    double o[3] = {0.0, 0.0, 0.0};
    for (int k = 0; k < d; ++k) o[k] = P(i, k);
    if (use_tree) {
      store(i, detail::tree_sums(o, outer_scale[i], pass.tree, power, eps, tau, flags_of(i),
                                 evaluations));
    } else {
      store(i, detail::pair_sums(o, outer_scale[i], pass.src, power, eps, flags_of(i)));
    }
  }
  return use_tree ? evaluations : static_cast<std::int64_t>(n) * pass.src.size;
}

}  // namespace

void HausdorffParams::validate() const {
  check_positive(alpha, "alpha");
  check_positive(beta, "beta");
  check_positive(gamma, "gamma");
  check_positive(epsilon, "epsilon");
}

namespace {
void validate_options(const HausdorffOptions& options) {
  options.params.validate();
  if (options.threads < 0) throw InvalidArgument("threads must be >= 0 (0: OpenMP default)");
  if (!(options.tolerance > 0.0 && options.tolerance < 1.0)) {
    std::ostringstream msg;
    msg << "Hausdorff option tolerance must be in (0, 1), got " << options.tolerance;
    throw InvalidArgument(msg.str());
  }
}
// Refuses coordinates whose squares could overflow (see kMaxCoordinate).
void check_coordinates(const PointCloud& cloud, const char* which) {
  const double largest = cloud.points().cwiseAbs().maxCoeff();
  if (largest > kMaxCoordinate) {
    std::ostringstream msg;
    msg << which << " cloud has a coordinate of magnitude " << largest << ", above the limit of "
        << kMaxCoordinate << " (rescale the clouds and epsilon)";
    throw InvalidArgument(msg.str());
  }
}
}  // namespace

std::string to_string(Method method) {
  switch (method) {
    case Method::exact:
      return "exact";
    case Method::tree:
      return "tree";
    case Method::nearest:
      return "nearest";
  }
  return "unknown";
}

Method method_from_string(const std::string& name) {
  if (name == "exact") return Method::exact;
  if (name == "tree") return Method::tree;
  if (name == "nearest") return Method::nearest;
  throw InvalidArgument("unknown method '" + name + "' (expected exact, tree or nearest)");
}

struct HausdorffTarget::Impl {
  Impl(PointCloud c, HausdorffOptions o) : cloud(std::move(c)), options(o), tree(cloud.points()) {
    weights = cloud.volumes() / cloud.total_volume();  // W_j/|Y|
    if (options.method == Method::tree) {
      // Pass-2 sources are the target: its tree and the moments of W_j/|Y|, once.
      kd = std::make_unique<detail::KdTree>(cloud.points(), kLeafSize);
      kd_weights = kd->permute(weights);
      kd_moments = detail::node_moments(*kd, kd_weights.data(), nullptr,
                                        detail::KernelPower(options.params.alpha));
    }
  }
  PointCloud cloud;
  HausdorffOptions options;
  detail::NearestIndex tree;  // over cloud.points(): must be declared after cloud
  Eigen::VectorXd weights;
  // Method tree only.
  std::unique_ptr<detail::KdTree> kd;
  Eigen::VectorXd kd_weights;                   // weights in kd's order
  std::vector<detail::NodeMoments> kd_moments;  // of kd_weights

  HausdorffResult evaluate_nearest(const PointCloud& X, const HausdorffRequest& req) const;
  HausdorffResult evaluate_sums(const PointCloud& X, const HausdorffRequest& req) const;
};

HausdorffTarget::HausdorffTarget(PointCloud target, HausdorffOptions options) {
  validate_options(options);
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
  const int threads = detail::resolve_threads(options.threads);
  const detail::NearestIndex moving_tree(X.points());
  Eigen::VectorXd dist_target = moving_tree.distances(cloud.points(), threads);
  Eigen::VectorXd dist_moving = tree.distances(X.points(), threads);
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

HausdorffResult HausdorffTarget::Impl::evaluate_sums(const PointCloud& X,
                                                     const HausdorffRequest& req) const {
  using detail::kInner;
  using detail::kOuterGrad;
  using detail::kOuterSum;
  const PointCloud& Y = cloud;
  const HausdorffParams& prm = options.params;
  const double alpha = prm.alpha, beta = prm.beta, eps = prm.epsilon;
  const int threads = detail::resolve_threads(options.threads);
  const int d = X.dim();
  const Eigen::Index N = X.size(), M = Y.size();
  const detail::KernelPower power(alpha);
  const Eigen::VectorXd v = X.volumes() / X.total_volume();  // V_i/|X|
  const Eigen::VectorXd& w = weights;                        // W_j/|Y|
  auto differentiated = [&](Eigen::Index i) {
    return req.differentiate.size() == 0 || req.differentiate[i];
  };

  // Scales c = r_min + ε of every point, from the k-d trees.
  const detail::NearestIndex moving_tree(X.points());
  const Eigen::VectorXd scale_y = moving_tree.distances(Y.points(), threads).array() + eps;
  const Eigen::VectorXd scale_x = tree.distances(X.points(), threads).array() + eps;

  // Method tree: the moving cloud's tree and the moments of V_i/|X|, per evaluation (the
  // target's were built with the target). Source arrays are then in tree order, and the
  // outer points are visited in the other cloud's tree order.
  const bool use_tree = options.method == Method::tree;
  const double tau = options.tolerance;
  std::unique_ptr<detail::KdTree> x_kd;
  Eigen::VectorXd x_v;
  std::vector<detail::NodeMoments> x_moments;
  const std::vector<Eigen::Index> natural;
  if (use_tree) {
    x_kd = std::make_unique<detail::KdTree>(X.points(), kLeafSize);
    x_v = x_kd->permute(v);
    x_moments = detail::node_moments(*x_kd, x_v.data(), nullptr, power);
  }
  // Every exact S is ≤ 1 (each term ≤ its weight, the weights sum to 1), so clipping a
  // tree sum at 1 only moves it towards the exact value and keeps d̃ ≥ r_min ≥ 0.
  const std::vector<Eigen::Index>& visit_y = use_tree ? kd->order() : natural;
  const std::vector<Eigen::Index>& visit_x = use_tree ? x_kd->order() : natural;
  auto tree_sources = [&](const detail::KdTree& t) {
    detail::PairSources s;
    s.dim = t.dim();
    s.size = t.size();
    for (int k = 0; k < s.dim; ++k) s.coord[k] = t.points().col(k).data();
    return s;
  };
  std::int64_t evaluations = 0;

  // Pass 1, targets over sources: S_j = Σ_i (V_i/|X|) ((r_min(y_j)+ε)/(r_ij+ε))^α, and for
  // target gradients G_j = Σ_i (V_i/|X|) p_ij t_ij (y_j − x_i)/r_ij.
  PassSources pass_x;
  pass_x.src = use_tree ? tree_sources(*x_kd) : sources_of(X);
  pass_x.src.weight = use_tree ? x_v.data() : v.data();
  if (use_tree) {
    pass_x.tree.tree = x_kd.get();
    pass_x.tree.src = pass_x.src;
    pass_x.tree.outer = x_moments.data();
  }
  Eigen::VectorXd S_y(M);
  Eigen::MatrixXd G_y;
  if (req.gradient_target) G_y.resize(M, d);
  const unsigned pass1 = req.gradient_target ? (kOuterSum | kOuterGrad) : kOuterSum;
  evaluations += sweep(
      Y, scale_y, visit_y, pass_x, power, eps, tau, threads, [&](Eigen::Index) { return pass1; },
      [&](Eigen::Index j, const detail::PairSums& s) {
        S_y[j] = use_tree ? std::min(s.S, 1.0) : s.S;  // exact S ≤ 1 (tree: see below)
        if (req.gradient_target)
          for (int k = 0; k < d; ++k) G_y(j, k) = s.G[k];
      });
  Eigen::VectorXd dt_y(M);  // d̃_X(y_j)
  for (Eigen::Index j = 0; j < M; ++j)
    dt_y[j] = detail::regularised_distance(scale_y[j] - eps, S_y[j], alpha, eps);
  const double A = detail::power_mean(dt_y, w, beta);

  // Coefficients carried into pass 2: g_j = ∂A/∂d̃_j · (d̃_j + ε)/S_j, with
  // ∂A/∂d̃_j = (W_j/|Y|)(d̃_j/A)^(β−1).
  const bool need_inner = req.gradient_points || req.gradient_volumes;
  Eigen::VectorXd a_y, g_y;
  if (req.any_gradient()) {
    a_y.resize(M);
    for (Eigen::Index j = 0; j < M; ++j)
      a_y[j] = detail::power_mean_derivative(dt_y[j], w[j], A, beta);
    g_y = a_y.array() * (dt_y.array() + eps) / S_y.array();
  }

  // Pass 2, sources over targets: S_i = Σ_j (W_j/|Y|) ((r_min(x_i)+ε)/(r_ij+ε))^α, with
  // G_i = Σ_j (W_j/|Y|) p_ij t_ij (x_i − y_j)/r_ij, and the pass-1 terms scaled by y_j's
  // own scale: H_i = Σ_j g_j p'_ij, G2_i = Σ_j g_j p'_ij t_ij (x_i − y_j)/r_ij.
  PassSources pass_y;
  Eigen::VectorXd g_kd, scale_kd;  // g_y, scale_y in the target tree's order
  std::vector<detail::NodeMoments> g_moments;
  if (use_tree) {
    pass_y.src = tree_sources(*kd);
    pass_y.src.weight = kd_weights.data();
    pass_y.tree.tree = kd.get();
    pass_y.tree.outer = kd_moments.data();
    if (need_inner) {
      g_kd = kd->permute(g_y);
      scale_kd = kd->permute(scale_y);
      g_moments = detail::node_moments(*kd, g_kd.data(), scale_kd.data(), power);
      pass_y.src.coef = g_kd.data();
      pass_y.src.scale = scale_kd.data();
      pass_y.tree.inner = g_moments.data();
    }
    pass_y.tree.src = pass_y.src;
  } else {
    pass_y.src = sources_of(Y);
    pass_y.src.weight = w.data();
    pass_y.src.coef = need_inner ? g_y.data() : nullptr;
    pass_y.src.scale = scale_y.data();
  }
  Eigen::VectorXd S_x(N), H_x;
  Eigen::MatrixXd G_x, G2_x;
  if (req.gradient_points) {
    G_x.setZero(N, d);
    G2_x.setZero(N, d);
  }
  if (req.gradient_volumes) H_x.setZero(N);
  unsigned pass2_grad = kOuterSum;
  if (req.gradient_points) pass2_grad |= kOuterGrad | kInner;
  if (req.gradient_volumes) pass2_grad |= kInner;
  evaluations += sweep(
      X, scale_x, visit_x, pass_y, power, eps, tau, threads,
      [&](Eigen::Index i) { return differentiated(i) ? pass2_grad : unsigned{kOuterSum}; },
      [&](Eigen::Index i, const detail::PairSums& s) {
        S_x[i] = use_tree ? std::min(s.S, 1.0) : s.S;
        if (!differentiated(i)) return;
        if (req.gradient_points) {
          for (int k = 0; k < d; ++k) {
            G_x(i, k) = s.G[k];
            G2_x(i, k) = s.G2[k];
          }
        }
        if (req.gradient_volumes) H_x[i] = s.H;
      });
  Eigen::VectorXd dt_x(N);  // d̃_Y(x_i)
  for (Eigen::Index i = 0; i < N; ++i)
    dt_x[i] = detail::regularised_distance(scale_x[i] - eps, S_x[i], alpha, eps);
  const double B = detail::power_mean(dt_x, v, beta);
  const double rho = detail::combine_means(A, B, prm.gamma);

  HausdorffResult r;
  r.A = A;
  r.B = B;
  r.rho = rho;
  r.kernel_evaluations = evaluations;
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
    f_x[i] = detail::power_mean_derivative(dt_x[i], v[i], B, beta) * (dt_x[i] + eps) / S_x[i];

  if (req.gradient_points) {
    // ∂ρ̃/∂x_i = ρ̃_A (V_i/|X|) G2_i + ρ̃_B f_i G_i
    r.gradient_points.resize(N, d);
    for (Eigen::Index i = 0; i < N; ++i)
      r.gradient_points.row(i) = rho_A * v[i] * G2_x.row(i) + rho_B * f_x[i] * G_x.row(i);
  }
  if (req.gradient_volumes) {
    // ∂ρ̃/∂V_i = −ρ̃_A/(α|X|) (H_i − Σ_j a_j (d̃_j + ε)) + ρ̃_B B/(β|X|) ((d̃_i/B)^β − 1)
    const double sum_a = (a_y.array() * (dt_y.array() + eps)).sum();
    const double volX = X.total_volume();
    r.gradient_volumes.setZero(N);
    for (Eigen::Index i = 0; i < N; ++i) {
      if (!differentiated(i)) continue;
      const double dA = -(H_x[i] - sum_a) / (alpha * volX);
      const double dB = B > 0.0 ? B / (beta * volX) * (std::pow(dt_x[i] / B, beta) - 1.0) : 0.0;
      r.gradient_volumes[i] = rho_A * dA + rho_B * dB;
    }
  }
  if (req.gradient_target) {
    // Pass 3, targets over sources with x_i's own scales: G3_j = Σ_i f_i p'_ij t_ij
    // (y_j − x_i)/r_ij. Then ∂ρ̃/∂y_j = ρ̃_A a_j (d̃_j+ε)/S_j G_j + ρ̃_B (W_j/|Y|) G3_j.
    Eigen::VectorXd f_kd, sx_kd;  // f_x, scale_x in the moving tree's order
    std::vector<detail::NodeMoments> f_moments;
    if (use_tree) {
      f_kd = x_kd->permute(f_x);
      sx_kd = x_kd->permute(scale_x);
      f_moments = detail::node_moments(*x_kd, f_kd.data(), sx_kd.data(), power);
      pass_x.src.coef = f_kd.data();
      pass_x.src.scale = sx_kd.data();
      pass_x.tree.src = pass_x.src;
      pass_x.tree.inner = f_moments.data();
    } else {
      pass_x.src.coef = f_x.data();
      pass_x.src.scale = scale_x.data();
    }
    Eigen::MatrixXd G3(M, d);
    r.kernel_evaluations += sweep(
        Y, scale_y, visit_y, pass_x, power, eps, tau, threads,
        [](Eigen::Index) { return unsigned{kInner}; },
        [&](Eigen::Index j, const detail::PairSums& s) {
          for (int k = 0; k < d; ++k) G3(j, k) = s.G2[k];
        });
    r.gradient_target.resize(M, d);
    for (Eigen::Index j = 0; j < M; ++j)
      r.gradient_target.row(j) = rho_A * g_y[j] * G_y.row(j) + rho_B * w[j] * G3.row(j);
  }
  return r;
}

HausdorffResult hausdorff(const PointCloud& moving, const PointCloud& target,
                          const HausdorffOptions& options, const HausdorffRequest& request) {
  return HausdorffTarget(target, options).evaluate(moving, request);
}

}  // namespace softhd
