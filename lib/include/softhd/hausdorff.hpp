#pragma once
/// \file hausdorff.hpp
/// The regularised Hausdorff distance between two weighted point clouds (docs/formulation.md §2).
///
/// Moving cloud X = {x_i, V_i} (N points), target cloud Y = {y_j, W_j} (M points):
///
///     I_X(y) = ((1/|X|) Σ_i V_i φ(|y − x_i|)^α)^(1/α),  d̃_X(y) = φ⁻¹(I_X(y)),  φ(t) = 1/(t + ε)
///     A = ((1/|Y|) Σ_j W_j d̃_X(y_j)^β)^(1/β),  B = ((1/|X|) Σ_i V_i d̃_Y(x_i)^β)^(1/β)
///     ρ̃ = ((A^γ + B^γ)/2)^(1/γ)
///
/// HausdorffRequest::form selects the one-sided (ρ̃ = A), visible (B over marked moving points)
/// and soft-capped forms of docs/formulation.md §8 (DistanceForm).
///
/// Typical use: build a HausdorffTarget once (it owns the target's k-d tree), then call
/// evaluate() for each moving cloud, asking only for what is needed.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string>

#include "softhd/hessian_part.hpp"
#include "softhd/point_cloud.hpp"
#include "softhd/work_share.hpp"

namespace softhd {

/// Largest |coordinate| the distance accepts: squared distances between points this far
/// out (up to (2·1e150)²·3 ≈ 1.2e301) and their sums stay finite in double. Clouds beyond it
/// are refused (InvalidArgument naming the limit); rescale them (ρ̃ scales with the
/// coordinates when ε is scaled along).
constexpr double kMaxCoordinate = 1e150;

/// Throws InvalidArgument "<which> cloud: point i has a coordinate of magnitude ..." (i from 1)
/// if a coordinate of `cloud` exceeds kMaxCoordinate. Every evaluation checks it; callers that
/// read a cloud from a file call it with the file's name so the message names it.
void check_coordinates(const PointCloud& cloud, const std::string& which);

/// Smallest ε the distance accepts (HausdorffParams::validate refuses less, naming this bound).
/// 1/ε is the kernel's value at a coincident pair and the scale of the gradient terms: it
/// overflows below ε = 1/DBL_MAX ≈ 5.6e-309, where the gradients of coincident clouds turn NaN
/// (at ε = 1e-320); at 1e-300 it stays 1e8 below overflow. ε is a length, as the
/// coordinates: rescaled clouds (down to |x| ~ 1e-150) rescale ε along within the range.
constexpr double kMinEpsilon = 1e-300;

/// The functional's parameters; defaults are the paper's.
struct HausdorffParams {
  double alpha = 4.0;     ///< exponent of the kernel mean I (α > 0); larger is closer to min
  double beta = 4.0;      ///< exponent of the means A and B (β > 0); larger is closer to max
  double gamma = 2.0;     ///< exponent combining A and B (γ > 0)
  double epsilon = 1e-3;  ///< kernel offset ε ≥ kMinEpsilon (an absolute length)

  /// Throws InvalidArgument naming the first parameter that is not finite and > 0, or below the
  /// smallest normal double, or `epsilon` below kMinEpsilon (the messages give the bound).
  void validate() const;
};

/// How the pair sums are evaluated.
enum class Method {
  exact,    ///< all N·M pairs (the reference)
  tree,     ///< dual-tree far field (Chebyshev interpolation, pruning) within relative
            ///< tolerance τ; sums a pass exactly where that is cheaper
  nearest,  ///< the unregularised Hausdorff distance by nearest-neighbour queries
};

/// "exact" / "tree" / "nearest"; method_from_string throws InvalidArgument for other names.
std::string to_string(Method method);
/// The Method named "exact", "tree" or "nearest".
Method method_from_string(const std::string& name);

/// Where the distance's integrals are evaluated (docs/formulation.md §2.8).
enum class Quadrature {
  collocation,  ///< at the clouds' points with their volumes (the paper's; the default)
  /// over the two bodies' cells: needs bodies with cells (an objective whose target has cells,
  /// ShapeObjectiveOptions::target_cells); the point-cloud API refuses it
  cells,
};
/// "collocation" / "cells"; quadrature_from_string throws InvalidArgument naming `quadrature`.
std::string to_string(Quadrature quadrature);
/// The Quadrature named "collocation" or "cells".
Quadrature quadrature_from_string(const std::string& name);

/// Evaluation settings.
struct HausdorffOptions {
  HausdorffParams params;         ///< α, β, γ, ε (paper defaults)
  Method method = Method::exact;  ///< pair-sum evaluation method
  int threads = 0;  ///< OpenMP threads, 0 to kMaxThreads (parallel.hpp); 0: OpenMP's default
  /// Method tree only: guaranteed bound τ ∈ (0, 1) on the relative error of every
  /// kernel sum, |S − S_exact| ≤ τ S_exact (likewise the volume-gradient sums H), and of
  /// every vector gradient sum relative to the sum of its terms' norms,
  /// ‖G − G_exact‖ ≤ τ Σ‖terms‖ (G itself may cancel). Up to rounding of the sums.
  /// Consequences (docs/tree_tolerance.md), with e = (1 − τ)^(−1/α) − 1 ≈ τ/α:
  ///     |Δd̃| ≤ e (d̃ + ε) for every field value,
  ///     |ΔA| ≤ e (A + ε), |ΔB| ≤ e (B + ε) for β ≥ 1,
  ///     |Δρ̃| ≤ e (ρ̃ + ε) for β, γ ≥ 1.
  /// Validated (InvalidArgument naming `tolerance`) for every method.
  double tolerance = 1e-6;
  /// Method tree only: sum a pass over all pairs, as method exact does, when its cost
  /// model predicts that is cheaper than the tree (small clouds, tight τ; see
  /// docs/tree_tolerance.md §8). false forces the tree (tests, measurements).
  bool tree_fallback = true;
  /// The processes that share each evaluation's pair sums and nearest-distance queries
  /// (softhd/work_share.hpp; MPI builds: softhd::mpi::work_share(comm)). Every process
  /// gets the whole result, equal to the serial one. Null (default): this process does all.
  std::shared_ptr<const WorkShare> share;
  /// collocation (default) or cells. HausdorffTarget (hence softhd::hausdorff) refuses cells
  /// (InvalidArgument naming `quadrature`): point clouds have no cells; ShapeObjective
  /// integrates over the body's cells and its target's (ShapeObjectiveOptions::target_cells).
  Quadrature quadrature = Quadrature::collocation;

  /// Throws InvalidArgument naming the first invalid field: a parameter
  /// (HausdorffParams::validate), `threads` (check_threads) or `tolerance`. Called by the
  /// HausdorffTarget constructor, hence by every front end (CLI, Python, the objective).
  void validate() const;
};

/// Which directed terms make ρ̃ (docs/formulation.md §8). The moving cloud X is the body,
/// the target Y the scan: A (the mean over Y of d̃_X) is scan → body, B body → scan.
enum class Sides {
  symmetric,     ///< ρ̃ = ((A^γ + B^γ)/2)^(1/γ) (§2; the default)
  scan_to_body,  ///< ρ̃ = A: a partial scan does not punish the body's hidden parts
  visible,  ///< ρ̃ = ((A^γ + B_V^γ)/2)^(1/γ), B_V the β-mean over the moving points marked
            ///< in DistanceForm::camera_mask, their weights renormalised over them
};

/// "symmetric" / "scan_to_body" / "visible"; sides_from_string throws InvalidArgument for
/// other names (naming `distance`, the key and flag that select it).
std::string to_string(Sides sides);
/// The Sides named "symmetric", "scan_to_body" or "visible".
Sides sides_from_string(const std::string& name);

/// The robust soft cap applied to every field value d̃ before its β-mean (docs/formulation.md
/// §8): ψ_c(d) = (d^(−q) + c^(−q))^(−1/q), ψ_c'(d) = (ψ_c(d)/d)^(q+1); ψ_c(d) → d for d ≪ c
/// and → c for d ≫ c, so one outlier moves A^β by at most about c^β/M.
struct SoftCap {
  /// The cap (a length); 0: no cap (ψ = identity). Else finite and at least L 2^(−1022/(q+1)),
  /// L the diagonal of the two clouds' common bounding box (checked per evaluation).
  double c = 0.0;
  double q = 4.0;  ///< sharpness q ≥ kMinQ (finite)
  /// The smallest q: ψ_c/min(d, c) = (1 + s^q)^(−1/q) ≥ 2^(−1/q) stays a normal double and
  /// its scaled evaluation accurate to about ε_mach/q (docs/formulation.md §8.3).
  static constexpr double kMinQ = 1e-3;
};

/// The form of the functional one evaluation computes: the sides, the cap and, for
/// Sides::visible, the moving points that enter B. Set per evaluation (the target's trees
/// do not depend on it), so a caller can tighten the cap or renew the visible set between
/// evaluations. Held fixed in the gradient (the visible set is piecewise constant).
struct DistanceForm {
  Sides sides = Sides::symmetric;  ///< which directed terms make ρ̃
  SoftCap cap;                     ///< the soft cap on every field value (default: none)
  /// Sides::visible only: the camera mask, N entries, true for the moving points a camera
  /// sees (those in B_V; at least one).
  Eigen::Array<bool, Eigen::Dynamic, 1> camera_mask;

  /// Throws InvalidArgument naming `cap.c`, `cap.q` or `camera_mask` (its size against N, none
  /// marked, or a mask given for other sides). Every evaluation calls it.
  void validate(Eigen::Index moving_points) const;
};

/// Throws InvalidArgument unless the cap c is 0 or at least L 2^(−1022/(q+1)), L the diagonal
/// of the two clouds' common bounding box (every field value d̃ ≤ L): below it the slope
/// ψ_c'(d) ≈ (c/d)^(q+1) of the largest fields underflows and ρ̃ is the constant c
/// (docs/formulation.md §8.3). HausdorffTarget::evaluate calls it.
void check_cap_length(const SoftCap& cap, const PointCloud& X, const PointCloud& Y);

/// The cap of the rule "c = factor × the quantile-`quantile` value of `field`" (docs/formulation.md
/// §8.3), with `field` typically HausdorffResult::field_target (d̃_X(y_j), the scan's field) at
/// the starting state. The quantile is unweighted and interpolates linearly between order
/// statistics: Q(p) = x_(k) + (h − k)(x_(k+1) − x_(k)), h = (n − 1)p, k = ⌊h⌋. Throws
/// InvalidArgument naming `quantile` (outside [0, 1]), `factor` (not finite and > 0), an empty
/// or non-finite field, or a cap that comes out 0.
double cap_from_quantile(const Eigen::VectorXd& field, double quantile, double factor);

/// What to compute beyond ρ̃, A and B. Nothing is computed that is not asked for.
struct HausdorffRequest {
  /// The functional's form (default: the symmetric ρ̃ of §2 without a cap).
  DistanceForm form;
  bool fields = false;            ///< per-point fields d̃_X(y_j) and d̃_Y(x_i)
  bool gradient_points = false;   ///< ∂ρ̃/∂x_i (N by d)
  bool gradient_volumes = false;  ///< ∂ρ̃/∂V_i (N)
  bool gradient_target = false;   ///< ∂ρ̃/∂y_j (M by d)
  /// Keep what HausdorffTarget::hessian_product needs (HausdorffResult::hessian): the
  /// point gradient's passes are made (the gradient itself is returned only with
  /// gradient_points) and their per-point quantities stored (docs/formulation.md §2.7).
  bool hessian_points = false;
  /// Optional mask of N entries: moving points with `false` are not differentiated
  /// (their gradient rows are zero; e.g. clamped nodes). Empty: all points.
  Eigen::Array<bool, Eigen::Dynamic, 1> differentiate;

  /// True if any gradient is requested.
  bool any_gradient() const { return gradient_points || gradient_volumes || gradient_target; }
};

/// The per-point quantities of one evaluation at X that Hessian-vector products reuse
/// (defined in lib/src/hausdorff/hessian.hpp; opaque to callers).
struct HausdorffHessian;

/// Where the pair-sum work of one evaluation went, summed over its passes (2 or 3; 1 or 2
/// for Sides::scan_to_body, which needs no pass for B's value).
struct SumWork {
  std::int64_t near_pairs = 0;  ///< source–outer pairs summed directly (near field, or all)
  std::int64_t far_kernel = 0;  ///< method tree: kernel evaluations at interpolation points
  std::int64_t far_basis = 0;   ///< method tree: point–interpolation-point basis products
  std::int64_t node_pairs = 0;  ///< method tree: node pairs visited by the traversal
  std::int64_t bound_axes = 0;  ///< method tree: per-axis remainder bounds it computed
  double plan_seconds = 0.0;    ///< method tree: traversal wall time
  double run_seconds = 0.0;     ///< wall time of the sums (including the traversal)
  int passes = 0;               ///< pair passes made
  int exact_passes = 0;         ///< method tree: passes its cost model summed exactly
};

/// The result of one evaluation. Optional members are empty unless requested.
struct HausdorffResult {
  double rho = 0.0;  ///< ρ̃ of the request's form (method nearest: the Hausdorff distance)
  /// Target-over-moving mean of ψ(d̃_X(y_j)) (ψ the cap, identity without one; method nearest:
  /// max_j ψ(dist(y_j, X))).
  double A = 0.0;
  /// Moving-over-target mean of ψ(d̃_Y(x_i)): over all moving points (symmetric), over the
  /// visible ones with renormalised weights (B_V, visible); method nearest: the max of
  /// ψ(dist(x_i, Y)) over the same points. Sides::scan_to_body: 0, not computed (ρ̃ = A).
  double B = 0.0;
  /// M: d̃_X(y_j) (nearest: dist(y_j, X)). The raw field values, before the cap.
  Eigen::VectorXd field_target;
  /// N: d̃_Y(x_i) for every moving point, visible or not (nearest: dist(x_i, Y)). The raw
  /// values, before the cap. With scan_to_body it is computed only for this field.
  Eigen::VectorXd field_moving;
  Eigen::MatrixXd gradient_points;   ///< N by d: ∂ρ̃/∂x_i
  Eigen::VectorXd gradient_volumes;  ///< N: ∂ρ̃/∂V_i (volumes of X, Y held otherwise fixed)
  Eigen::MatrixXd gradient_target;   ///< M by d: ∂ρ̃/∂y_j
  /// HausdorffRequest::hessian_points: the state hessian_product reuses (shared, immutable;
  /// it holds a copy of the moving cloud, O(N + M) numbers).
  std::shared_ptr<const HausdorffHessian> hessian;
  /// Pair kernel evaluations made: exact N·M per pass; tree counts the pairs summed
  /// directly plus the evaluations at interpolation points (N·M for a pass it sums
  /// exactly; docs/tree_tolerance.md §6).
  std::int64_t kernel_evaluations = 0;
  SumWork work;          ///< the split of the pair-sum work
  double seconds = 0.0;  ///< wall time of the evaluation
};

/// A target cloud prepared for repeated evaluations: it owns a copy of the cloud and
/// its k-d trees (and, for method tree, the node moments of the target weights), built
/// once in the constructor.
class HausdorffTarget {
 public:
  /// Throws InvalidArgument for invalid options.
  explicit HausdorffTarget(PointCloud target, HausdorffOptions options = {});
  ~HausdorffTarget();
  /// Moves the cloud and its trees; the moved-from target must not be evaluated.
  HausdorffTarget(HausdorffTarget&&) noexcept;
  /// Moves the cloud and its trees; the moved-from target must not be evaluated.
  HausdorffTarget& operator=(HausdorffTarget&&) noexcept;

  /// The target cloud Y (the target's own copy).
  const PointCloud& cloud() const;
  /// The options fixed at construction.
  const HausdorffOptions& options() const;

  /// ρ̃(moving, target) and what `request` asks for. Throws InvalidArgument when the
  /// dimensions differ, the mask has the wrong size, or a gradient is requested from
  /// method nearest. Thread-safe (const, no shared scratch).
  HausdorffResult evaluate(const PointCloud& moving, const HausdorffRequest& request = {}) const;

  /// H·v: the Hessian of ρ̃ w.r.t. the moving points' coordinates (N·d of them, volumes held
  /// fixed), or its Gauss–Newton part, applied to the direction `v` (N by d), at the moving
  /// cloud of `at`, an evaluate() result of this target with HausdorffRequest::hessian_points
  /// (same form, same differentiate mask). Reuses `at`'s fields, means and slopes; makes two
  /// all-pairs passes (for method tree too: docs/formulation.md §2.7). Rows of points not
  /// differentiated are zero and their rows of v ignored. `work` (optional) gets the passes'
  /// counts. Throws InvalidArgument if `at` has no Hessian state, is of another target, or v
  /// is not N by d. Thread-safe (const).
  Eigen::MatrixXd hessian_product(const HausdorffResult& at, const Eigen::MatrixXd& v,
                                  HessianPart part = HessianPart::full,
                                  SumWork* work = nullptr) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// One-shot convenience: builds a HausdorffTarget for `target` and evaluates.
HausdorffResult hausdorff(const PointCloud& moving, const PointCloud& target,
                          const HausdorffOptions& options = {},
                          const HausdorffRequest& request = {});

}  // namespace softhd
