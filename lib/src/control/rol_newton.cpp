// Algorithm::newton: a bound-constrained trust-region Newton–CG, ROL's Lin–Moré algorithm
// (docs/formulation.md §4.5.1). The only translation unit that includes Trilinos: ROL's
// templates stay here.

#include <ROL_Bounds.hpp>
#include <ROL_Objective.hpp>
#include <ROL_StatusTest.hpp>
#include <ROL_StdVector.hpp>
#include <ROL_TypeB_LinMoreAlgorithm.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <ostream>
#include <vector>

#include "optimizer_backend.hpp"
#include "softhd/error.hpp"

namespace softhd {
namespace {

using LinMore = ROL::TypeB::LinMoreAlgorithm<double>;
using RolVector = ROL::Vector<double>;

// ROL keeps two numbers of Lin–Moré's state private: the Cauchy-point step length α, carried
// from one iteration to the next (a restart must set it to continue identically), and the CG
// iterations of the last step (for the records). An explicit instantiation may name private
// members ([temp.explicit]: access is not checked there), which lets the friend function
// `member` return pointers to them. ROL 13.2's names; another version fails to compile here.
template <class Tag, typename Tag::type Member>
struct PrivateMember {
  friend typename Tag::type member(Tag) { return Member; }
};
struct CauchyStep {
  using type = double LinMore::*;
  friend type member(CauchyStep);
};
struct StepCgIterations {
  using type = int LinMore::*;
  friend type member(StepCgIterations);
};
template struct PrivateMember<CauchyStep, &LinMore::alpha_>;
template struct PrivateMember<StepCgIterations, &LinMore::SPiter_>;

Eigen::Map<const Eigen::VectorXd> view(const RolVector& v) {
  const std::vector<double>& d = *dynamic_cast<const ROL::StdVector<double>&>(v).getVector();
  return {d.data(), static_cast<Eigen::Index>(d.size())};
}
Eigen::Map<Eigen::VectorXd> view(RolVector& v) {
  std::vector<double>& d = *dynamic_cast<ROL::StdVector<double>&>(v).getVector();
  return {d.data(), static_cast<Eigen::Index>(d.size())};
}
ROL::Ptr<ROL::StdVector<double>> rol_vector(const Eigen::VectorXd& v) {
  return ROL::makePtr<ROL::StdVector<double>>(
      ROL::makePtr<std::vector<double>>(v.data(), v.data() + v.size()));
}

/// The smallest power of 2 ≥ v > 0: with it, x / s and s z are exact.
double power_of_two_above(double v) {
  int e = 0;
  const double m = std::frexp(v, &e);  // v = m 2^e, m ∈ [0.5, 1)
  return std::ldexp(1.0, m == 0.5 ? e - 1 : e);
}

/// The products already computed at one point z, kept as an orthonormal basis Q of the
/// vectors multiplied and HQ = ∇²f̃ Q (docs/formulation.md §4.5.1). ROL asks for many
/// products at the same z whose vectors lie in the span of earlier ones: the Cauchy search's
/// steps along one projected gradient, the projected search's step (a combination of the CG
/// directions), and after a rejected step the next trial's Cauchy steps and first CG direction
/// (g + αHg, in the span of g and Hg). For v with ‖v − QQᵀv‖ ≤ kSpan ‖v‖ the product is
/// HQ (Qᵀv), by linearity, without a product.
class ProductSpan {
 public:
  /// The relative distance from the span below which v counts as in it (round-off of the
  /// projected steps P(z + s) − z, about ε |z| / |s| per component, stays far below).
  static constexpr double kSpan = 1e-10;
  /// A vector joins the basis only if at least this part of it is new: the basis vector
  /// (v − QQᵀv) / ‖v − QQᵀv‖ amplifies the product's round-off by at most its inverse.
  static constexpr double kNew = 1e-3;

  /// Forget the products (a new point z).
  void reset(const Eigen::Ref<const Eigen::VectorXd>& z) {
    z_ = z;
    q_.resize(z.size(), 0);
    hq_.resize(z.size(), 0);
  }
  bool at(const Eigen::Ref<const Eigen::VectorXd>& z) const {
    return z_.size() == z.size() && z_ == z;
  }
  /// HQ Qᵀv into hv if v lies in the span; false otherwise.
  bool apply(const Eigen::VectorXd& v, Eigen::Ref<Eigen::VectorXd> hv) const {
    if (q_.cols() == 0) return false;
    const Eigen::VectorXd c = q_.transpose() * v;
    if ((v - q_ * c).norm() > kSpan * v.norm()) return false;
    hv = hq_ * c;
    return true;
  }
  /// Adds the computed product hv = H v: q = r / ‖r‖, Hq = (hv − HQ Qᵀv) / ‖r‖ with
  /// r = v − QQᵀv (twice projected, for an orthonormal Q).
  void add(const Eigen::VectorXd& v, const Eigen::VectorXd& hv) {
    Eigen::VectorXd c = Eigen::VectorXd::Zero(q_.cols()), r = v;
    for (int pass = 0; pass < 2; ++pass) {
      const Eigen::VectorXd d = q_.transpose() * r;
      r -= q_ * d;
      c += d;
    }
    const double rn = r.norm();
    if (!(rn >= kNew * v.norm()) || rn == 0.0) return;
    const Eigen::Index k = q_.cols();
    q_.conservativeResize(Eigen::NoChange, k + 1);
    hq_.conservativeResize(Eigen::NoChange, k + 1);
    q_.col(k) = r / rn;
    hq_.col(k) = (hv - hq_.leftCols(k) * c) / rn;
  }

 private:
  Eigen::VectorXd z_;
  Eigen::MatrixXd q_, hq_;
};

// Why the run stopped, when we stopped it (ROL itself only stops through our status test).
using detail::Stop;

// A Hessian-vector product failed: thrown through ROL to end the run at the best point.
struct HessianFailed {};

// One minimise() call: the scaled problem, the last evaluation, the summary.
struct Run {
  explicit Run(const detail::BoundedProblem& problem) : p(problem) {}

  const detail::BoundedProblem& p;
  Eigen::VectorXd scale, zlo, zhi;  // x = scale ∘ z; bounds on z
  double fscale = 1.0;              // f̃ = f / fscale
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  BoundedOptimizerSummary summary;
  // The last evaluation (always with the gradient: ROL asks for it at every accepted trial).
  Eigen::VectorXd z_eval, gz_eval;  // gz = ∇_z f̃ = s ∘ ∇f / fscale
  double f_eval = 0.0;
  bool ok_eval = false;
  bool accepted = false;   // ROL accepted a step since the last status check
  int products_since = 0;  // Hessian-vector products since the last record
  int small_changes = 0;   // consecutive iterations with a relative change below tolerance
  Stop stop = Stop::none;
  const LinMore* algorithm = nullptr;
  ProductSpan span;  // the products at the current iterate

  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

  /// f and ∇f at z into the cache, unless z is the cached point (bitwise).
  void evaluate(const Eigen::Ref<const Eigen::VectorXd>& z) {
    if (z_eval.size() == z.size() && z_eval == z) return;
    z_eval = z;
    ++summary.evaluations;
    Eigen::VectorXd g;
    double f = 0.0;
    ok_eval = p.objective(scale.cwiseProduct(z), f, &g) && std::isfinite(f) &&
              g.size() == z.size() && g.allFinite();
    if (!ok_eval) {
      ++summary.failed_evaluations;
      return;
    }
    f_eval = f;
    gz_eval = scale.cwiseProduct(g) / fscale;
  }

  /// ∇²f̃ v in z: s ∘ H (s ∘ v) / fscale, H at x = s ∘ z; from the span of the products
  /// already computed at z where v lies in it (ProductSpan), else computed and counted.
  void hess_vec(const Eigen::Ref<const Eigen::VectorXd>& z, const Eigen::VectorXd& v,
                Eigen::Ref<Eigen::VectorXd> hv) {
    if (!span.at(z)) span.reset(z);
    if (span.apply(v, hv)) {
      ++summary.hessian_products_reused;
      return;
    }
    compute_hess_vec(z, v, hv);
    span.add(v, hv);
  }
  void compute_hess_vec(const Eigen::Ref<const Eigen::VectorXd>& z, const Eigen::VectorXd& v,
                        Eigen::Ref<Eigen::VectorXd> hv) {
    ++summary.hessian_products;
    ++products_since;
    Eigen::VectorXd h;
    if (!p.hess_vec(scale.cwiseProduct(z), scale.cwiseProduct(v), &h) || h.size() != v.size() ||
        !h.allFinite())
      throw HessianFailed{};
    hv = scale.cwiseProduct(h) / fscale;
  }

  bool check(const ROL::TypeB::AlgorithmState<double>& state);
  void record(const ROL::TypeB::AlgorithmState<double>& state);
};

// f̃(z) for ROL: the user's objective through the cache. A failed evaluation is NaN, which
// ROL's ratio test rejects (TRNAN) and answers by shrinking the radius to ¼ min(‖s‖, Δ).
class ScaledObjective : public ROL::Objective<double> {
 public:
  explicit ScaledObjective(Run& run) : run_(run) {}
  void update(const RolVector&, ROL::UpdateType type, int) override {
    if (type == ROL::UpdateType::Accept) run_.accepted = true;
  }
  double value(const RolVector& z, double&) override {
    run_.evaluate(view(z));
    return run_.ok_eval ? run_.f_eval / run_.fscale : std::numeric_limits<double>::quiet_NaN();
  }
  void gradient(RolVector& g, const RolVector& z, double&) override {
    run_.evaluate(view(z));
    if (!run_.ok_eval) throw InternalError("newton: ROL asked for the gradient at a failed point");
    view(g) = run_.gz_eval;
  }
  void hessVec(RolVector& hv, const RolVector& v, const RolVector& z, double&) override {
    run_.hess_vec(view(z), view(v), view(hv));
  }

 private:
  Run& run_;
};

// Our stopping rules, and the records of accepted iterations, checked by ROL before every
// iteration (after accepted and rejected steps alike).
class RunStatus : public ROL::StatusTest<double> {
 public:
  explicit RunStatus(Run& run) : run_(run) {}
  bool check(ROL::AlgorithmState<double>& state) override {
    // Lin–Moré's state is the TypeB one (its trust radius).
    return run_.check(static_cast<ROL::TypeB::AlgorithmState<double>&>(state));
  }

 private:
  Run& run_;
};

bool Run::check(const ROL::TypeB::AlgorithmState<double>& state) {
  if (accepted) {
    accepted = false;
    record(state);
  } else if (state.iter == 0) {
    // The start: converged already if its projected gradient is within the tolerance.
    const double pg = projected_gradient_norm(z_eval, gz_eval, zlo, zhi);
    if (pg <= p.options.gradient_tolerance) stop = Stop::gradient;
  }
  if (stop != Stop::none) return false;
  const BoundedOptimizerOptions& o = p.options;
  if (summary.evaluations >= o.max_evaluations)
    stop = Stop::evaluations;  // each iteration evaluates once: never more than the limit
  else if (o.max_seconds > 0.0 && seconds() > o.max_seconds)
    stop = Stop::time;
  else if (state.searchSize < o.trust_region.min_radius)
    stop = Stop::radius;
  return stop == Stop::none;
}

void Run::record(const ROL::TypeB::AlgorithmState<double>& state) {
  const double previous = summary.final_value, f = f_eval;
  summary.final_value = f;
  summary.x = scale.cwiseProduct(z_eval);
  IterationRecord rec;
  rec.iteration = ++summary.iterations;
  rec.evaluation = summary.evaluations;
  rec.value = f;
  rec.projected_gradient_norm = projected_gradient_norm(z_eval, gz_eval, zlo, zhi);
  rec.seconds = seconds();
  rec.cg_iterations = algorithm->*member(StepCgIterations{});
  rec.hessian_products = products_since;
  rec.trust_radius = state.searchSize;
  rec.cauchy_step = algorithm->*member(CauchyStep{});
  products_since = 0;
  summary.history.push_back(rec);
  try {
    if (p.on_iteration) p.on_iteration(rec, summary.x);
  } catch (const StopRequest&) {
    stop = Stop::requested;
  }
  const BoundedOptimizerOptions& o = p.options;
  const bool small = std::fabs(previous - f) <= o.relative_change * std::fabs(f);
  small_changes = small ? small_changes + 1 : 0;
  if (stop != Stop::none) return;
  if (f <= o.target_value)
    stop = Stop::target;
  else if (small && small_changes >= 3)
    stop = Stop::relative_change;
  else if (rec.projected_gradient_norm <= o.gradient_tolerance)
    stop = Stop::gradient;
  else if (summary.iterations >= o.max_iterations)
    stop = Stop::iterations;
}

/// The largest trust radius (scaled variables): the move limit's counterpart,
/// Δ_max = move_limit ‖z_hi − z_lo‖₂ (a Cauchy or CG step of root-mean-square at most
/// move_limit × the bound range); ∞ (ROL's default) without a move limit.
double max_radius(const BoundedOptimizerOptions& o, const Eigen::VectorXd& zlo,
                  const Eigen::VectorXd& zhi) {
  if (!(o.move_limit > 0.0)) return std::numeric_limits<double>::infinity();
  return o.move_limit * (zhi - zlo).norm();
}

/// Lin–Moré's parameters from ours; ROL's defaults otherwise (ROL_TypeB_LinMoreAlgorithm_Def).
/// Δ₀ = trust_region.initial_radius, or min(‖∇f̃(z₀)‖, Δ_max) where it is 0 (ROL starts from
/// ‖∇f̃(z₀)‖ and caps only later radii); α₀ = trust_region.cauchy_step, or Δ₀/‖∇f̃(z₀)‖.
ROL::ParameterList lin_more_parameters(const TrustRegionOptions& t, double gradient_norm,
                                       double radius_max) {
  ROL::ParameterList list;
  list.sublist("General").set("Output Level", 0);
  ROL::ParameterList& krylov = list.sublist("General").sublist("Krylov");
  krylov.set("Iteration Limit", t.cg_iterations);
  krylov.set("Absolute Tolerance", t.cg_absolute_tolerance);
  krylov.set("Relative Tolerance", t.cg_relative_tolerance);
  ROL::ParameterList& tr = list.sublist("Step").sublist("Trust Region");
  const double radius =
      t.initial_radius > 0.0 ? t.initial_radius : std::min(gradient_norm, radius_max);
  tr.set("Initial Radius", radius);
  if (std::isfinite(radius_max)) tr.set("Maximum Radius", radius_max);
  ROL::ParameterList& lm = tr.sublist("Lin-More");
  lm.set("Relative Tolerance Exponent", 2.0);  // CG tolerance ∝ ‖g_free‖²: quadratic
  // α₀ = Δ₀/‖∇f̃(z₀)‖ unless given: the first Cauchy trial lands on the radius.
  const double alpha = t.cauchy_step > 0.0                   ? t.cauchy_step
                       : gradient_norm > 0.0 && radius > 0.0 ? radius / gradient_norm
                                                             : 1.0;
  lm.sublist("Cauchy Point").set("Initial Step Size", alpha);
  return list;
}

/// The scaled variables and the start's evaluation. Returns false, with the summary's
/// status set, if the run ends there (a failed start, or the target reached).
bool start(Run* r) {
  const detail::BoundedProblem& p = r->p;
  const Eigen::Index n = p.x0.size();
  r->scale.resize(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    const double m = std::max(std::fabs(p.lower[k]), std::fabs(p.upper[k]));
    r->scale[k] = m > 0.0 ? power_of_two_above(m) : 1.0;
  }
  r->zlo = p.lower.cwiseQuotient(r->scale);
  r->zhi = p.upper.cwiseQuotient(r->scale);
  r->fscale = 1.0;
  r->evaluate(p.x0.cwiseQuotient(r->scale));
  r->summary.x = p.x0;
  if (!r->ok_eval) {
    r->summary.status = OptimizerStatus::start_failed;
    r->summary.termination = "the evaluation at the starting point failed";
    r->summary.initial_value = r->summary.final_value = std::nan("");
    return false;
  }
  const double f = r->f_eval, given = p.options.trust_region.value_scale;
  r->fscale = r->summary.value_scale = given > 0.0 ? given : (f != 0.0 ? std::fabs(f) : 1.0);
  r->gz_eval /= r->fscale;  // evaluated with fscale 1
  r->summary.initial_value = r->summary.final_value = f;
  if (f <= p.options.target_value) {
    r->summary.status = OptimizerStatus::target_value;
    r->summary.termination = "the starting value already reaches the target value";
    return false;
  }
  return true;
}

void set_termination(Stop stop, BoundedOptimizerSummary* s) {
  if (detail::set_stop(stop, s)) return;
  s->status = OptimizerStatus::nlopt_failure;
  s->termination = "ROL stopped for no reason of ours";
}

class RolBackend : public detail::OptimizerBackend {
 public:
  BoundedOptimizerSummary minimise(const detail::BoundedProblem& p) const override {
    if (!p.hess_vec)
      throw InvalidArgument(
          "optimizer: algorithm newton needs a Hessian-vector product (hess_vec is empty)");
    Run run(p);
    if (start(&run)) {
      const double radius_max = max_radius(p.options, run.zlo, run.zhi);
      ROL::ParameterList list =
          lin_more_parameters(p.options.trust_region, run.gz_eval.norm(), radius_max);
      LinMore algorithm(list);
      run.algorithm = &algorithm;
      algorithm.setStatusTest(ROL::makePtr<RunStatus>(run), false);  // ours alone
      ScaledObjective objective(run);
      ROL::Bounds<double> bounds(rol_vector(run.zlo), rol_vector(run.zhi));
      const ROL::Ptr<ROL::StdVector<double>> z = rol_vector(run.z_eval);
      std::ostream quiet(nullptr);
      try {
        algorithm.run(*z, objective, bounds, quiet);
      } catch (const HessianFailed&) {
        run.stop = Stop::hessian;
      }
      set_termination(run.stop, &run.summary);
    }
    run.summary.seconds = run.seconds();
    return run.summary;
  }
};

}  // namespace

const detail::OptimizerBackend& detail::rol_backend() {
  static const RolBackend backend;
  return backend;
}

}  // namespace softhd
