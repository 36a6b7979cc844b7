#include "softhd/control/bounded_optimizer.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <nlopt.hpp>
#include <sstream>

#include "optimizer_backend.hpp"
#include "softhd/enum_names.hpp"
#include "softhd/error.hpp"

namespace softhd {

constexpr auto kAlgorithmNames =
    enum_sequence<Algorithm::newton>({"mma", "ccsaq", "lbfgs", "slsqp", "newton"});

std::string to_string(Algorithm a) { return enum_name(kAlgorithmNames, a); }

Algorithm algorithm_from_string(const std::string& name) {
  return enum_from_name(kAlgorithmNames, name, "algorithm");
}

constexpr auto kStatusNames = enum_sequence<OptimizerStatus::hessian_failed>(
    {"iteration_limit", "evaluation_limit", "time_limit", "relative_change", "target_value",
     "nlopt_converged", "no_progress", "move_limit", "stopped", "start_failed", "nlopt_failure",
     "gradient_tolerance", "hessian_failed"});

namespace {
// A tolerance stop (relative_change, no_progress) under a move limit below
// kCertifyingMoveLimit is status move_limit: its steps were too short to tell a minimum.
void uncertified_by_move_limit(const BoundedOptimizerOptions& options, BoundedOptimizerSummary* s) {
  const bool tolerance =
      s->status == OptimizerStatus::relative_change || s->status == OptimizerStatus::no_progress;
  if (!(tolerance && options.move_limit > 0.0 && options.move_limit < kCertifyingMoveLimit)) return;
  char text[160];
  std::snprintf(text, sizeof text,
                " (move limit %g, below %g: steps too short to tell a minimum; raise it)",
                options.move_limit, kCertifyingMoveLimit);
  s->status = OptimizerStatus::move_limit;
  s->termination += text;
}
}  // namespace

std::string to_string(OptimizerStatus status) { return enum_name(kStatusNames, status); }

bool is_converged(OptimizerStatus status) {
  return status == OptimizerStatus::relative_change || status == OptimizerStatus::target_value ||
         status == OptimizerStatus::nlopt_converged || status == OptimizerStatus::no_progress ||
         status == OptimizerStatus::gradient_tolerance;
}

void BoundedOptimizerOptions::validate() const {
  if (max_iterations < 1) throw InvalidArgument("optimizer: max_iterations must be >= 1");
  if (max_evaluations < 1) throw InvalidArgument("optimizer: max_evaluations must be >= 1");
  if (!(relative_change >= 0.0)) throw InvalidArgument("optimizer: relative_change must be >= 0");
  if (std::isnan(target_value)) throw InvalidArgument("optimizer: target_value is NaN");
  if (!(max_seconds >= 0.0)) throw InvalidArgument("optimizer: max_seconds must be >= 0");
  if (!(move_limit >= 0.0 && move_limit <= 1.0))
    throw InvalidArgument("optimizer: move_limit must be in [0, 1]");
  if (round_evaluations < 2) throw InvalidArgument("optimizer: round_evaluations must be >= 2");
  if (!(failure_penalty > 1.0) || !std::isfinite(failure_penalty))
    throw InvalidArgument("optimizer: failure_penalty must be finite and > 1");
  if (!(gradient_tolerance >= 0.0) || !std::isfinite(gradient_tolerance))
    throw InvalidArgument("optimizer: gradient_tolerance must be finite and >= 0");
  trust_region.validate();
}

void TrustRegionOptions::validate() const {
  const auto finite_at_least = [](double v, double low) { return std::isfinite(v) && v >= low; };
  if (!finite_at_least(initial_radius, 0.0))
    throw InvalidArgument("optimizer: trust_region.initial_radius must be finite and >= 0");
  if (!finite_at_least(cauchy_step, 0.0))
    throw InvalidArgument("optimizer: trust_region.cauchy_step must be finite and >= 0");
  if (!finite_at_least(value_scale, 0.0))
    throw InvalidArgument("optimizer: trust_region.value_scale must be finite and >= 0");
  if (cg_iterations < 1)
    throw InvalidArgument("optimizer: trust_region.cg_iterations must be >= 1");
  if (!(finite_at_least(cg_relative_tolerance, 0.0) && cg_relative_tolerance > 0.0))
    throw InvalidArgument("optimizer: trust_region.cg_relative_tolerance must be finite and > 0");
  if (!(finite_at_least(cg_absolute_tolerance, 0.0) && cg_absolute_tolerance > 0.0))
    throw InvalidArgument("optimizer: trust_region.cg_absolute_tolerance must be finite and > 0");
  if (!(finite_at_least(min_radius, 0.0) && min_radius > 0.0))
    throw InvalidArgument("optimizer: trust_region.min_radius must be finite and > 0");
}

double projected_gradient_norm(const Eigen::VectorXd& x, const Eigen::VectorXd& g,
                               const Eigen::VectorXd& lower, const Eigen::VectorXd& upper) {
  // P(x − g) − x, P the projection onto the box.
  const Eigen::VectorXd step = (x - g).cwiseMax(lower).cwiseMin(upper) - x;
  return step.norm();
}

namespace {

nlopt::algorithm nlopt_algorithm(Algorithm a) {
  switch (a) {
    case Algorithm::ccsaq:
      return nlopt::LD_CCSAQ;
    case Algorithm::lbfgs:
      return nlopt::LD_LBFGS;
    case Algorithm::slsqp:
      return nlopt::LD_SLSQP;
    case Algorithm::mma:
    case Algorithm::newton:  // not an NLopt algorithm: backend_for never passes it here
      break;
  }
  return nlopt::LD_MMA;
}

// Why the driver asked NLopt to stop (NLopt only knows "forced stop").
using detail::Stop;

// The scale of f for one NLopt run. MMA's conservative approximation adds, per variable,
// (|g_j| σ_j + ρ/2) Δz_j² / (σ_j² − Δz_j²) to the linear term, ρ starting at 1 in every run
// and falling 10× per outer iteration. Unless ρ/2 << |g_j| σ_j the first steps are
// Δz_j ≈ −g_j σ_j² / ρ, orders of magnitude below the move limit: the plateaus of issue 12
// (J changing in the 4th digit for 3-5 iterations after every round's restart). Scaling f
// so that the largest gradient component in z is kMmaGradient makes ρ = 1 small against
// the variables that matter from the first step; f / |f(x0)| is kept if it is larger.
// The target is adapted per round (Driver::adapt_mma_gradient): a round whose first step is
// rejected (late in a run, where |g| is small and such a step overshoots) makes the next
// rounds 10x more conservative; a first step accepted relaxes it 2x, up to kMmaGradient.
constexpr double kMmaGradient = 100.0;

double round_scale(const Eigen::VectorXd& gz, double report_scale, double mma_gradient,
                   const BoundedOptimizerOptions& options) {
  if (options.algorithm != Algorithm::mma && options.algorithm != Algorithm::ccsaq)
    return report_scale;
  const double gmax = gz.size() ? gz.lpNorm<Eigen::Infinity>() : 0.0;
  if (!(gmax > 0.0) || !std::isfinite(gmax)) return report_scale;
  return std::min(report_scale, gmax / mma_gradient);
}

struct Driver {
  Driver(const BoundedObjective& f, const BoundedOptimizerOptions& o,
         const std::function<void(const IterationRecord&, const Eigen::VectorXd&)>& cb)
      : objective(f), options(o), on_iteration(cb) {}

  const BoundedObjective& objective;
  const BoundedOptimizerOptions& options;
  const std::function<void(const IterationRecord&, const Eigen::VectorXd&)>& on_iteration;
  Eigen::VectorXd scale;           // x = scale ∘ z
  Eigen::VectorXd zlo, zhi;        // bounds on z
  Eigen::VectorXd box_lo, box_hi;  // the current round's move-limit box (empty: none)
  bool recentre = false;           // the best point reached a side of the box
  double fscale = 1.0;             // f_nlopt = f / fscale (set per round, see round_scale)
  double report_scale = 1.0;       // |f(x0)|: records give gradients of f / |f(x0)|
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  BoundedOptimizerSummary summary;
  double largest_abs = 1.0;  // largest |J| seen, for the failure penalty
  Stop stop = Stop::none;
  int small_changes = 0;  // consecutive iterations with a relative change below tolerance
  // The best point so far with its value and gradient (x units): NLopt's first call of
  // every round asks for it again, and gets it without a new evaluation.
  Eigen::VectorXd z0, g0;
  double f0 = 0.0;
  bool first_pending = true;
  double mma_gradient = kMmaGradient;  // see round_scale
  int round_new_evaluations = 0;       // evaluations made in the current round
  bool round_first_improved = false;   // the round's first new evaluation improved f
  // An exception of the objective or of on_iteration: NLopt would swallow it (its C++
  // wrapper turns exceptions into result codes), so it is kept, NLopt is stopped, and
  // minimise() rethrows it once NLopt has returned.
  std::exception_ptr error;

  /// Keeps the exception being handled and stops NLopt; the value NLopt gets is that of a
  /// failed evaluation (it is never used).
  double stop_on_error(std::vector<double>& grad, nlopt::opt& opt) {
    if (!error) error = std::current_exception();
    opt.force_stop();
    return failed(grad);
  }
  /// The value and zero gradient reported for a failed evaluation.
  double failed(std::vector<double>& grad) const {
    for (double& g : grad) g = 0.0;
    return options.failure_penalty * largest_abs / fscale;
  }

  /// After a round: more conservative after a rejected first step, less after an accepted one.
  void adapt_mma_gradient() {
    if (round_new_evaluations == 0) return;
    mma_gradient =
        round_first_improved ? std::min(kMmaGradient, 2.0 * mma_gradient) : 0.1 * mma_gradient;
  }

  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

  double evaluate(const std::vector<double>& zv, std::vector<double>& grad, nlopt::opt& opt) {
    if (error) return failed(grad);  // asked again before NLopt saw the forced stop
    const Eigen::Map<const Eigen::VectorXd> z(zv.data(), static_cast<Eigen::Index>(zv.size()));
    const bool want_grad = !grad.empty();
    double f = 0.0;
    Eigen::VectorXd gx;
    bool ok = true;
    if (first_pending && z == z0) {
      first_pending = false;
      f = f0;
      gx = g0;
    } else {
      ++summary.evaluations;
      const Eigen::VectorXd x = scale.cwiseProduct(z);
      try {
        ok = objective(x, f, want_grad ? &gx : nullptr) && std::isfinite(f) &&
             (!want_grad || (gx.size() == z.size() && gx.allFinite()));
      } catch (...) {
        return stop_on_error(grad, opt);
      }
      if (round_new_evaluations++ == 0) round_first_improved = ok && f < summary.final_value;
    }
    if (!ok) {
      ++summary.failed_evaluations;
      return failed(grad);
    }
    largest_abs = std::max(largest_abs, std::fabs(f));
    const Eigen::VectorXd gz =
        want_grad ? Eigen::VectorXd(scale.cwiseProduct(gx) / report_scale) : Eigen::VectorXd();
    const double to_nlopt = report_scale / fscale;
    for (size_t k = 0; k < grad.size(); ++k) grad[k] = to_nlopt * gz[static_cast<Eigen::Index>(k)];
    if (f < summary.final_value) {
      z0 = z;
      f0 = f;
      g0 = gx;
      accept(z, f, gz, opt);
    }
    if (options.max_seconds > 0.0 && seconds() > options.max_seconds && stop == Stop::none) {
      stop = Stop::time;
      opt.force_stop();
    }
    return f / fscale;
  }

  void accept(const Eigen::Ref<const Eigen::VectorXd>& z, double f, const Eigen::VectorXd& gz,
              nlopt::opt& opt) {
    const double previous = summary.final_value;
    summary.final_value = f;
    summary.x = scale.cwiseProduct(z);
    IterationRecord rec;
    rec.iteration = ++summary.iterations;
    rec.evaluation = summary.evaluations;
    rec.value = f;
    rec.projected_gradient_norm =
        gz.size() ? projected_gradient_norm(z, gz, zlo, zhi) : std::nan("");
    rec.seconds = seconds();
    summary.history.push_back(rec);
    Stop s = Stop::none;
    try {
      if (on_iteration) on_iteration(rec, summary.x);
    } catch (const StopRequest&) {
      s = Stop::requested;
    } catch (...) {
      error = std::current_exception();
      opt.force_stop();
      return;
    }
    if (std::fabs(previous - f) > options.relative_change * std::fabs(f)) small_changes = 0;
    if (s == Stop::requested) {
      // the caller's observer ended the run
    } else if (f <= options.target_value) {
      s = Stop::target;
    } else if (std::fabs(previous - f) <= options.relative_change * std::fabs(f) &&
               ++small_changes >= 3) {
      s = Stop::relative_change;
    } else if (options.gradient_tolerance > 0.0 &&
               rec.projected_gradient_norm <= options.gradient_tolerance) {
      s = Stop::gradient;
    } else if (summary.iterations >= options.max_iterations) {
      s = Stop::iterations;
    }
    if (s != Stop::none && stop == Stop::none) {
      stop = s;
      opt.force_stop();
    } else if (stop == Stop::none && on_box_side(z)) {
      // Within a round MMA would now converge to the box's constrained optimum, taking
      // tiny steps along its side until the round's evaluations are spent: start the next
      // round around this point instead.
      recentre = true;
      opt.force_stop();
    }
  }

  /// True if z lies on a side of the current move-limit box that is not a bound.
  bool on_box_side(const Eigen::Ref<const Eigen::VectorXd>& z) const {
    if (box_lo.size() != z.size()) return false;
    for (Eigen::Index k = 0; k < z.size(); ++k) {
      const double tiny = 1e-9 * (zhi[k] - zlo[k]);
      if ((z[k] <= box_lo[k] + tiny && box_lo[k] > zlo[k] + tiny) ||
          (z[k] >= box_hi[k] - tiny && box_hi[k] < zhi[k] - tiny))
        return true;
    }
    return false;
  }
};

struct Callback {
  Driver* driver;
  nlopt::opt* opt;
};

double nlopt_callback(const std::vector<double>& z, std::vector<double>& grad, void* data) {
  auto* cb = static_cast<Callback*>(data);
  return cb->driver->evaluate(z, grad, *cb->opt);
}

}  // namespace

void detail::check_problem(const Eigen::VectorXd& x0, const Eigen::VectorXd& lower,
                           const Eigen::VectorXd& upper, const BoundedOptimizerOptions& options) {
  options.validate();
  const Eigen::Index n = x0.size();
  if (n < 1) throw InvalidArgument("optimizer: no variables");
  if (lower.size() != n || upper.size() != n)
    throw InvalidArgument("optimizer: bounds and start have different sizes");
  if (options.move_scale.size() != 0 &&
      (options.move_scale.size() != n || !(options.move_scale.array() > 0.0).all() ||
       !(options.move_scale.array() <= 1.0).all()))
    throw InvalidArgument(
        "optimizer: move_scale must be empty or have one entry in (0, 1] per "
        "variable");
  for (Eigen::Index k = 0; k < n; ++k) {
    if (!std::isfinite(lower[k]) || !std::isfinite(upper[k]) || !(lower[k] <= upper[k])) {
      std::ostringstream m;
      m << "optimizer: bounds of variable " << k << " are invalid: [" << lower[k] << ", "
        << upper[k] << "]";
      throw InvalidArgument(m.str());
    }
    if (!(x0[k] >= lower[k] && x0[k] <= upper[k])) {
      std::ostringstream m;
      m << "optimizer: start of variable " << k << " (" << x0[k] << ") is outside its bounds ["
        << lower[k] << ", " << upper[k] << "]";
      throw InvalidArgument(m.str());
    }
  }
}

namespace {

/// The variables scaled to O(1) (x = scale ∘ z, scale = max(|lower|, |upper|)) and the
/// starting point evaluated once: it fixes the objective's scale. Returns false, with the
/// summary's status set, if the run ends there (a failed start, or the target reached).
bool start(Driver* d, const Eigen::VectorXd& x0, const Eigen::VectorXd& lower,
           const Eigen::VectorXd& upper) {
  const Eigen::Index n = x0.size();
  d->scale = lower.cwiseAbs().cwiseMax(upper.cwiseAbs());
  for (Eigen::Index k = 0; k < n; ++k)
    if (!(d->scale[k] > 0.0)) d->scale[k] = 1.0;  // bounds [0, 0]
  d->zlo = lower.cwiseQuotient(d->scale);
  d->zhi = upper.cwiseQuotient(d->scale);
  d->z0 = x0.cwiseQuotient(d->scale);
  ++d->summary.evaluations;
  Eigen::VectorXd g;
  double f = 0.0;
  if (!d->objective(x0, f, &g) || !std::isfinite(f) || g.size() != n || !g.allFinite()) {
    d->summary.failed_evaluations = 1;
    d->summary.status = OptimizerStatus::start_failed;
    d->summary.termination = "the evaluation at the starting point failed";
    d->summary.x = x0;
    d->summary.initial_value = d->summary.final_value = std::nan("");
    return false;
  }
  d->fscale = d->report_scale = d->summary.value_scale = f != 0.0 ? std::fabs(f) : 1.0;
  d->largest_abs = std::max(1.0, std::fabs(f));
  d->f0 = f;
  d->g0 = g;
  d->summary.initial_value = d->summary.final_value = f;
  d->summary.x = x0;
  if (f <= d->options.target_value) {
    d->summary.status = OptimizerStatus::target_value;
    d->summary.termination = "the starting value already reaches the target value";
    return false;
  }
  return true;
}

/// Why NLopt returned, when the driver did not stop it.
struct NloptEnd {
  OptimizerStatus status = OptimizerStatus::nlopt_failure;
  std::string reason;
};

/// One NLopt run on the box [lo, hi] from the best point, at most `evaluations` new
/// evaluations. Rethrows an exception of the objective or the observer.
void run_round(Driver* d, const Eigen::VectorXd& lo, const Eigen::VectorXd& hi, int evaluations,
               NloptEnd* end) {
  const Eigen::Index n = d->z0.size();
  d->recentre = false;
  d->fscale =
      round_scale(d->scale.cwiseProduct(d->g0), d->report_scale, d->mma_gradient, d->options);
  d->round_new_evaluations = 0;
  nlopt::opt opt(nlopt_algorithm(d->options.algorithm), static_cast<unsigned>(n));
  opt.set_lower_bounds(std::vector<double>(lo.data(), lo.data() + n));
  opt.set_upper_bounds(std::vector<double>(hi.data(), hi.data() + n));
  opt.set_maxeval(1 + evaluations);  // + 1: the first call of a round returns the cached best point
  Callback cb{d, &opt};
  opt.set_min_objective(nlopt_callback, &cb);
  std::vector<double> z(d->z0.data(), d->z0.data() + n);
  d->first_pending = d->g0.size() == n;
  double fmin = 0.0;
  try {
    const nlopt::result r = opt.optimize(z, fmin);
    switch (r) {
      case nlopt::MAXEVAL_REACHED:
        *end = {OptimizerStatus::evaluation_limit, "the evaluation limit was reached"};
        break;
      case nlopt::FTOL_REACHED:
      case nlopt::XTOL_REACHED:
      case nlopt::SUCCESS:
        *end = {OptimizerStatus::nlopt_converged, "NLopt reports convergence"};
        break;
      default:
        *end = {OptimizerStatus::nlopt_failure,
                "NLopt stopped (result code " + std::to_string(static_cast<int>(r)) + ")"};
    }
  } catch (const nlopt::forced_stop&) {
    // The driver's own stopping rules; see d->stop.
  } catch (const nlopt::roundoff_limited&) {
    *end = {OptimizerStatus::nlopt_failure, "NLopt stopped: progress limited by round-off"};
  } catch (const std::invalid_argument& e) {
    *end = {OptimizerStatus::nlopt_failure, std::string("NLopt rejected the problem: ") + e.what()};
  } catch (const std::runtime_error& e) {
    if (d->stop == Stop::none)
      *end = {OptimizerStatus::nlopt_failure, std::string("NLopt failed: ") + e.what()};
  }
  if (d->error) std::rethrow_exception(d->error);
}

/// NLopt on the whole box, or in rounds on a moving box of half-width
/// move_limit · (upper − lower) around the best point (move limits): the next round keeps the
/// move limit after progress (or a recentring), halves it otherwise.
NloptEnd run_rounds(Driver* d) {
  const BoundedOptimizerOptions& options = d->options;
  const Eigen::Index n = d->z0.size();
  NloptEnd end;
  double delta = options.move_limit;
  while (true) {
    Eigen::VectorXd lo = d->zlo, hi = d->zhi;
    if (delta > 0.0) {
      Eigen::VectorXd half = delta * (d->zhi - d->zlo);  // the box's half-width per variable
      if (options.move_scale.size() == n) half = half.cwiseProduct(options.move_scale);
      lo = d->zlo.cwiseMax(d->z0 - half);
      hi = d->zhi.cwiseMin(d->z0 + half);
    }
    const int remaining = options.max_evaluations - d->summary.evaluations;
    if (remaining <= 0)
      return {OptimizerStatus::evaluation_limit, "the evaluation limit was reached"};
    if (delta > 0.0) {
      d->box_lo = lo;
      d->box_hi = hi;
    }
    const double round_start = d->summary.final_value;
    run_round(d, lo, hi, delta > 0.0 ? std::min(remaining, options.round_evaluations) : remaining,
              &end);
    if (d->stop != Stop::none || delta <= 0.0) return end;
    d->adapt_mma_gradient();
    if (d->recentre) continue;  // progress up to the box's side: same move limit, new centre
    if (!(d->summary.final_value < round_start)) delta *= 0.5;
    if (delta < options.move_limit * 1e-3)
      return {OptimizerStatus::no_progress, "no progress within the smallest move limit"};
  }
}

/// The summary's status and termination text from why the run stopped: the driver's own
/// stop, or (none) why NLopt returned.
void set_termination(Stop stop, const NloptEnd& end, BoundedOptimizerSummary* s) {
  s->status = end.status;
  s->termination = end.reason;
  detail::set_stop(stop, s);
}

class NloptBackend : public detail::OptimizerBackend {
 public:
  BoundedOptimizerSummary minimise(const detail::BoundedProblem& p) const override {
    Driver d(p.objective, p.options, p.on_iteration);
    if (start(&d, p.x0, p.lower, p.upper)) {
      // Run first, then read d.stop: in one call's arguments their order is unspecified (GCC
      // ran run_rounds first, clang read d.stop first and reported every stop as none).
      const NloptEnd end = run_rounds(&d);
      set_termination(d.stop, end, &d.summary);
    }
    uncertified_by_move_limit(p.options, &d.summary);
    d.summary.seconds = d.seconds();
    return d.summary;
  }
};

const detail::OptimizerBackend& backend_for(Algorithm algorithm) {
  return algorithm == Algorithm::newton ? detail::rol_backend() : detail::nlopt_backend();
}

}  // namespace

const detail::OptimizerBackend& detail::nlopt_backend() {
  static const NloptBackend backend;
  return backend;
}

BoundedOptimizerSummary minimise(
    const BoundedObjective& objective, const BoundedHessVec& hess_vec, const Eigen::VectorXd& x0,
    const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
    const BoundedOptimizerOptions& options,
    const std::function<void(const IterationRecord&, const Eigen::VectorXd&)>& on_iteration) {
  detail::check_problem(x0, lower, upper, options);
  const detail::BoundedProblem problem{objective, hess_vec, x0,          lower,
                                       upper,     options,  on_iteration};
  return backend_for(options.algorithm).minimise(problem);
}

BoundedOptimizerSummary minimise(
    const BoundedObjective& objective, const Eigen::VectorXd& x0, const Eigen::VectorXd& lower,
    const Eigen::VectorXd& upper, const BoundedOptimizerOptions& options,
    const std::function<void(const IterationRecord&, const Eigen::VectorXd&)>& on_iteration) {
  return minimise(objective, BoundedHessVec(), x0, lower, upper, options, on_iteration);
}

namespace detail {

bool set_stop(Stop stop, BoundedOptimizerSummary* s) {
  struct Reason {
    Stop stop;
    OptimizerStatus status;
    const char* text;
  };
  static constexpr Reason kReasons[] = {
      {Stop::iterations, OptimizerStatus::iteration_limit, "the iteration limit was reached"},
      {Stop::evaluations, OptimizerStatus::evaluation_limit, "the evaluation limit was reached"},
      {Stop::relative_change, OptimizerStatus::relative_change,
       "the relative change of J fell below the tolerance"},
      {Stop::gradient, OptimizerStatus::gradient_tolerance,
       "the projected gradient norm fell below the tolerance"},
      {Stop::target, OptimizerStatus::target_value, "J reached the target value"},
      {Stop::time, OptimizerStatus::time_limit, "the wall-clock limit was reached"},
      {Stop::requested, OptimizerStatus::stopped, "stopped by the caller"},
      {Stop::radius, OptimizerStatus::no_progress,
       "no progress: rejected steps shrank the trust radius below min_radius"},
      {Stop::hessian, OptimizerStatus::hessian_failed, "a Hessian-vector product failed"},
  };
  for (const Reason& r : kReasons) {
    if (r.stop == stop) {
      s->status = r.status;
      s->termination = r.text;
      return true;
    }
  }
  return false;
}

}  // namespace detail

}  // namespace softhd
