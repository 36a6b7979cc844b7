// align(): the pose of a scan found by the distance itself (docs/formulation.md §8.5).

#include "softhd/scan/align.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <memory>
#include <numeric>
#include <string>

#include "align_internal.hpp"
#include "softhd/enum_names.hpp"
#include "softhd/error.hpp"
#include "softhd/parallel.hpp"

namespace softhd::scan {

namespace {

constexpr auto kAlignStatusNames =
    enum_sequence<AlignStatus::failed>({"converged", "iteration_limit", "failed"});
constexpr auto kCandidateScoreNames = enum_sequence<CandidateScore::rho>({"coverage", "rho"});

void require(bool ok, const std::string& what) {
  if (!ok) throw InvalidArgument("align: " + what);
}

Eigen::MatrixXd rows_of(const Eigen::MatrixXd& m, const std::vector<Eigen::Index>& rows) {
  Eigen::MatrixXd out(static_cast<Eigen::Index>(rows.size()), m.cols());
  for (size_t k = 0; k < rows.size(); ++k) out.row(static_cast<Eigen::Index>(k)) = m.row(rows[k]);
  return out;
}

Eigen::VectorXd entries_of(const Eigen::VectorXd& v, const std::vector<Eigen::Index>& rows) {
  Eigen::VectorXd out(static_cast<Eigen::Index>(rows.size()));
  for (size_t k = 0; k < rows.size(); ++k) out[static_cast<Eigen::Index>(k)] = v[rows[k]];
  return out;
}

/// f(k) for k = 0..n−1 in parallel (OpenMP, dynamic schedule); the first exception (in the
/// order of k) is rethrown after the loop.
template <class F>
void parallel_each(int n, int threads, const F& f) {
  std::vector<std::exception_ptr> errors(static_cast<size_t>(n));
#pragma omp parallel for schedule(dynamic) num_threads(resolve_threads(threads)) if (n > 1)
  for (int k = 0; k < n; ++k) {
    try {
      f(static_cast<size_t>(k));
    } catch (...) {
      errors[static_cast<size_t>(k)] = std::current_exception();
    }
  }
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
}

/// A level of detail: the body and scan subsampled to `points` each, ε given.
detail::PoseObjective make_level(const PointCloud& body, const PointCloud& scan,
                                 Eigen::Index points, double epsilon, int threads,
                                 const AlignOptions& o) {
  const Eigen::Index nb = points > 0 ? points : body.size();
  const Eigen::Index ns = points > 0 ? points : scan.size();
  const auto ib = detail::subsample(body.size(), nb, 1u);
  const auto is = detail::subsample(scan.size(), ns, 2u);
  HausdorffOptions d = o.distance;
  d.params.epsilon = epsilon;
  d.threads = threads;
  // A cap is never below 3ε of the level: an inlier's field value is about ε there, and a cap
  // below it would flatten the coarse levels.
  DistanceForm form = o.form;
  if (form.cap.c > 0.0) form.cap.c = std::max(form.cap.c, 3.0 * epsilon);
  return detail::PoseObjective(
      rows_of(body.points(), ib), entries_of(body.volumes(), ib),
      PointCloud(rows_of(scan.points(), is), entries_of(scan.volumes(), is)), d, form);
}

detail::LocalSettings local_settings(const AlignOptions& o, double L, int iterations,
                                     double tolerance, const FixtureConstraint* fixture) {
  detail::LocalSettings st;
  if (fixture != nullptr) st.subspace = fixture->tangent();  // the table's 3 free variables
  st.max_iterations = iterations;
  st.step_tolerance = tolerance;
  st.size = L;
  st.similarity = o.kind == PoseKind::similarity;
  st.log_scale_min = -std::log(o.scale_max);  // Q = P⁻¹ has scale 1/s
  st.log_scale_max = -std::log(o.scale_min);
  return st;
}

/// The starting poses Q (body → scan frame) of the global search: each rotation of the grid
/// and the 4 principal-axis matches, the body's centroid put on the scan's.
std::vector<Pose> starting_poses(const Eigen::MatrixXd& body, const Eigen::MatrixXd& scan,
                                 int rotations) {
  std::vector<Eigen::Matrix3d> Rs = detail::rotation_grid(rotations);
  const Eigen::Matrix3d Ab = detail::principal_axes(body), As = detail::principal_axes(scan);
  for (int k = 0; k < 4; ++k) {  // proper sign flips of the axes
    const Eigen::Vector3d d(k & 1 ? -1 : 1, k & 2 ? -1 : 1, (k == 1 || k == 2) ? -1 : 1);
    Rs.push_back(As * d.asDiagonal() * Ab.transpose());
  }
  const Eigen::Vector3d cb = body.colwise().mean().transpose(),
                        cs = scan.colwise().mean().transpose();
  std::vector<Pose> out;
  for (const Eigen::Matrix3d& R : Rs) {
    Pose Q;
    Q.R = R;
    Q.t = cs - R * cb;
    out.push_back(Q);
  }
  return out;
}

/// The starting poses with a fixture: `count` angles 2πk/count about the table's normal, the
/// body's centroid over the scan's along the table, at the fixture's height; with a clamp side,
/// those on its side only.
std::vector<Pose> fixture_starts(const Eigen::MatrixXd& body, const Eigen::MatrixXd& scan,
                                 int count, const FixtureConstraint& fixture) {
  const Eigen::Vector3d cb = body.colwise().mean().transpose(),
                        cs = scan.colwise().mean().transpose();
  std::vector<Pose> out;
  for (int k = 0; k < count; ++k) {
    const Pose Q = fixture.start(2.0 * M_PI * k / count, cb, cs);
    if (fixture.allows(Q)) out.push_back(Q);  // the clamp's side
  }
  return out;
}

/// Global start: every starting pose minimised briefly on the coarse level (in parallel over
/// the poses), then the `keep` best that differ by more than 10° or L/10. `tried`: the count
/// of starting poses.
std::vector<Pose> global_candidates(const PointCloud& body, const PointCloud& scan, double L,
                                    const AlignOptions& o, const FixtureConstraint* fixture,
                                    const detail::BodySurface* surface, int* tried) {
  const detail::PoseObjective coarse =
      make_level(body, scan, o.coarse_points, o.coarse_epsilon * L, 1, o);
  const std::vector<Pose> starts =
      fixture != nullptr ? fixture_starts(body.points(), scan.points(), o.rotations, *fixture)
                         : starting_poses(body.points(), scan.points(), o.rotations);
  *tried = static_cast<int>(starts.size());
  const detail::LocalSettings st = local_settings(o, L, 20, 1e-4, fixture);
  std::vector<detail::LocalResult> found(starts.size());
  const int n = static_cast<int>(starts.size());
  parallel_each(n, o.threads,
                [&](size_t i) { found[i] = detail::minimise_pose(coarse, starts[i], st); });
  std::vector<double> score(found.size());
  for (size_t k = 0; k < found.size(); ++k) score[k] = found[k].rho;
  if (fixture != nullptr)  // the clamp's side: poses on the other side are not kept
    for (size_t k = 0; k < found.size(); ++k)
      if (!fixture->allows(found[k].pose)) score[k] = INFINITY;
  if (o.score == CandidateScore::coverage) {  // rank by the coverage score instead
    const detail::CoverageScore coverage(body.points(), scan.points(), L, o.score_truncation,
                                         o.threads, surface);
    for (size_t k = 0; k < found.size(); ++k)
      if (std::isfinite(score[k])) score[k] = coverage.value(found[k].pose);
  }
  std::vector<size_t> order(found.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return score[a] < score[b]; });
  std::vector<Pose> kept;
  for (size_t k : order) {
    const Pose& q = found[k].pose;
    bool distinct = std::isfinite(score[k]);
    for (const Pose& p : kept)
      if (rotation_angle_between(p.R, q.R) < 10.0 * M_PI / 180.0 && (p.t - q.t).norm() < 0.1 * L)
        distinct = false;
    if (distinct) kept.push_back(q);
    if (static_cast<int>(kept.size()) >= o.keep) break;
  }
  return kept;
}

/// The global start's candidates and the user's start, which competes with them (none: the
/// identity; with a fixture, moved onto its constraint about the body's centroid).
std::vector<Pose> all_candidates(const PointCloud& body, const PointCloud& scan, double L,
                                 const AlignOptions& options, const FixtureConstraint* fixture,
                                 const detail::BodySurface* surface, int* starts) {
  std::vector<Pose> candidates;
  if (options.global_start)
    candidates = global_candidates(body, scan, L, options, fixture, surface, starts);
  if (options.initial) candidates.push_back(options.initial->inverse());
  if (candidates.empty()) candidates.push_back(Pose());
  if (fixture != nullptr && (options.initial || !options.global_start)) {
    Pose& Q = candidates.back();
    const Eigen::Vector3d c = Q.R * body.points().colwise().mean().transpose() + Q.t;
    Q = fixture->project(Q, c);
  }
  return candidates;
}

/// Residuals (true nearest distances of the moved scan to the body's points, or to its
/// surface when it has one), overlap (the fraction within inlier_distance × L) and the rmse of
/// those residuals.
void report_nearest(const detail::NearestPoints& nearest, const detail::BodySurface* surface,
                    const PointCloud& scan, const AlignOptions& options, double L,
                    AlignSummary* out) {
  const Eigen::MatrixXd moved = apply_points(out->pose, scan.points());
  if (surface != nullptr) {
    const auto q = surface->at_rows(moved, resolve_threads(options.threads));
    out->residuals.resize(moved.rows());
    for (Eigen::Index j = 0; j < moved.rows(); ++j)
      out->residuals[j] = std::abs(q[static_cast<size_t>(j)].sd);
  } else {
    std::vector<Eigen::Index> index;
    nearest.nearest(moved, &index, &out->residuals, options.threads);
  }
  out->inlier_distance = options.inlier_distance * L;
  double sum2 = 0.0;
  Eigen::Index inliers = 0;
  for (Eigen::Index j = 0; j < out->residuals.size(); ++j) {
    if (out->residuals[j] <= out->inlier_distance) {
      ++inliers;
      sum2 += out->residuals[j] * out->residuals[j];
    }
  }
  out->overlap = static_cast<double>(inliers) / static_cast<double>(scan.size());
  out->rmse = inliers > 0 ? std::sqrt(sum2 / static_cast<double>(inliers)) : 0.0;
}

}  // namespace

std::string to_string(AlignStatus status) { return enum_name(kAlignStatusNames, status); }
std::string to_string(CandidateScore score) { return enum_name(kCandidateScoreNames, score); }
CandidateScore candidate_score_from_string(const std::string& name) {
  if (name == "visible")
    throw InvalidArgument("score \"visible\" is now \"coverage\" (the same score)");
  return enum_from_name(kCandidateScoreNames, name, "score");
}

void AlignOptions::validate() const {
  require(std::isfinite(scale_min) && scale_min > 0.0 && scale_min <= 1.0,
          "scale_min must be in (0, 1] (the bounds must include s = 1), got " +
              std::to_string(scale_min));
  require(std::isfinite(scale_max) && scale_max >= 1.0,
          "scale_max must be finite and >= 1 (the bounds must include s = 1), got " +
              std::to_string(scale_max));
  distance.validate();
  require(distance.method != Method::nearest, "distance.method nearest has no gradient");
  require(form.sides != Sides::visible,
          "distance visible is not supported (align has no camera model; use scan_to_body for "
          "a partial view)");
  form.validate(form.camera_mask.size() > 0 ? form.camera_mask.size() : 1);
  if (fixture) {
    fixture->validate();
    require(table.has_value(),
            "fixture needs the scan's table plane (table: the dominant plane found in the scan)");
    require(kind == PoseKind::rigid,
            "fixture needs a rigid alignment (a scale would change the table's height)");
    require(rotations >= 1, "rotations must be >= 1 with a fixture (the angles about the table)");
  }
  if (initial) {
    require(initial->R.allFinite() && initial->t.allFinite() && std::isfinite(initial->s) &&
                initial->s > 0.0,
            "initial pose is not finite");
    char scale[32];
    std::snprintf(scale, sizeof scale, "%.10g", initial->s);
    require(kind == PoseKind::similarity || initial->rigid(),
            std::string("initial pose has scale ") + scale +
                "; a rigid alignment keeps scale 1 (align a similarity, or give a rigid pose)");
  }
  require(rotations >= 0 && rotations <= 100000, "rotations must be in [0, 100000]");
  require(coarse_points >= 10, "coarse_points must be >= 10");
  require(std::isfinite(coarse_epsilon) && coarse_epsilon > 0.0, "coarse_epsilon must be > 0");
  require(keep >= 1, "keep must be >= 1");
  require(refine_points == 0 || refine_points >= 10, "refine_points must be 0 or >= 10");
  require(candidate_points >= 10, "candidate_points must be >= 10");
  require(max_iterations >= 0, "max_iterations must be >= 0");
  require(std::isfinite(tolerance) && tolerance > 0.0, "tolerance must be > 0");
  require(std::isfinite(score_truncation) && score_truncation > 0.0,
          "score_truncation must be > 0");
  require(nearest_iterations >= 0, "nearest_iterations must be >= 0");
  // A threshold of L or more counts every scan point near the body's box: no overlap measure.
  require(std::isfinite(inlier_distance) && inlier_distance > 0.0 && inlier_distance < 1.0,
          "inlier_distance must be in (0, 1) (a fraction of the body size L), got " +
              std::to_string(inlier_distance));
  check_threads(threads);
}

void check_fixes_pose(const PointCloud& cloud, const std::string& what) {
  const Eigen::Index n = cloud.size();
  if (n == 0) throw InvalidArgument(what + ": it has no points");
  // The covariance C = Dᵀ D / n of the centred points D (scaled by their largest entry, so
  // nothing overflows), eigenvalues λ₁ ≤ λ₂ ≤ λ₃: the points span a plane iff λ₂ > 1e-12 λ₃
  // (their spread across the line is more than 1e-6 of that along it).
  Eigen::MatrixXd D = cloud.points().rowwise() - cloud.points().colwise().mean();
  const double scale = D.cwiseAbs().maxCoeff();
  const std::string points = std::to_string(n) + " points";
  if (!(scale > 0.0))
    throw InvalidArgument(what +
                          (n == 1 ? ": it has a single point" : ": its " + points + " coincide") +
                          ", which fixes no pose (align needs points that span a plane)");
  D /= scale;
  const Eigen::Matrix3d C = D.transpose() * D / static_cast<double>(n);
  const Eigen::Vector3d l =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(C, Eigen::EigenvaluesOnly).eigenvalues();
  if (l[1] <= 1e-12 * l[2])
    throw InvalidArgument(what + ": its " + points +
                          " are collinear (to 1e-6 of their spread along the line), which fixes "
                          "no rotation about the line (align needs points that span a plane)");
}

double body_size(const PointCloud& body) {
  return (body.points().colwise().maxCoeff() - body.points().colwise().minCoeff()).norm();
}

std::string AlignSummary::BriefReport() const {
  char line[256];
  std::snprintf(line, sizeof line,
                "align %s: rotation %.6g deg, translation (%.6g %.6g %.6g), scale %.6g, rho %.6g, "
                "overlap %.4f, rmse %.6g, %d iterations, %.3g s",
                to_string(status).c_str(), rotation_log(pose.R).norm() * 180.0 / M_PI, pose.t.x(),
                pose.t.y(), pose.t.z(), pose.s, rho, overlap, rmse, iterations, seconds);
  return line;
}

AlignSummary align(const PointCloud& body, const PointCloud& scan, const AlignOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  require(body.dim() == 3 && scan.dim() == 3, "the body and the scan must be 3D clouds");
  check_coordinates(body, "body");
  check_coordinates(scan, "scan");
  check_fixes_pose(body, "align: the body");  // before the options: ε defaults to L/1000
  check_fixes_pose(scan, "align: the scan");
  options.validate();
  const double L = body_size(body);

  std::optional<FixtureConstraint> constraint;
  if (options.fixture) constraint.emplace(*options.fixture, *options.table, scan.points());
  const FixtureConstraint* fixture = constraint ? &*constraint : nullptr;
  const std::unique_ptr<detail::BodySurface> surface = detail::make_body_surface(body, options);

  AlignSummary out;
  const std::vector<Pose> candidates =
      all_candidates(body, scan, L, options, fixture, surface.get(), &out.starts);
  out.candidates = static_cast<int>(candidates.size());

  // Refinement: continuation in ε (a hundredth of L, then the user's) on the refine level.
  std::vector<double> eps;
  if (options.distance.params.epsilon < 0.01 * L) eps.push_back(0.01 * L);
  eps.push_back(options.distance.params.epsilon);
  bool limit = false;
  {
    // Every candidate on the first level, one per thread, each evaluation serial (small
    // clouds parallelise poorly); then the best of them on the finer levels, its evaluations
    // threaded when they are large (above 4e6 pairs).
    const Eigen::Index nb = std::min<Eigen::Index>(
        body.size(), options.refine_points > 0 ? options.refine_points : body.size());
    const Eigen::Index ns = std::min<Eigen::Index>(
        scan.size(), options.refine_points > 0 ? options.refine_points : scan.size());
    out.refine_body_points = nb;
    out.refine_scan_points = ns;
    const int eval_threads =
        static_cast<double>(nb) * static_cast<double>(ns) > 4e6 ? options.threads : 1;
    const bool spread = candidates.size() > 1;
    const detail::LocalSettings st =
        local_settings(options, L, options.max_iterations, options.tolerance, fixture);
    std::vector<detail::LocalResult> refined(candidates.size());
    {
      // Several candidates are compared on smaller clouds (candidate_points each).
      const Eigen::Index points = spread && options.refine_points != 0
                                      ? std::min(options.candidate_points, options.refine_points)
                                      : options.refine_points;
      const detail::PoseObjective first =
          make_level(body, scan, points, eps[0], spread ? 1 : eval_threads, options);
      parallel_each(
          static_cast<int>(candidates.size()), spread ? options.threads : 1,
          [&](size_t k) { refined[k] = detail::minimise_pose(first, candidates[k], st); });
    }
    const size_t best =
        detail::choose_candidate(body, scan, L, options, fixture, surface.get(), &refined);
    out.iterations = refined[best].iterations;
    // The best on the refinement clouds: at the first ε again if it was compared on
    // smaller clouds, then at the others.
    for (size_t l = spread && eps.size() == 1 ? 0 : 1; l < eps.size(); ++l) {
      const detail::PoseObjective level =
          make_level(body, scan, options.refine_points, eps[l], eval_threads, options);
      refined[best] = detail::minimise_pose(level, refined[best].pose, st);
      out.iterations += refined[best].iterations;
    }
    out.pose = refined[best].pose.inverse();
    limit = !refined[best].converged;
  }
  // Nearest-point finish and the report in true nearest distances.
  const detail::NearestPoints nearest(body.points());
  if (options.nearest_iterations > 0) {
    int it = 0;
    out.pose = detail::nearest_refinement(nearest, body.points(), surface.get(), scan.points(),
                                          out.pose, options, fixture, L, &it);
    out.iterations += it;
  }
  report_nearest(nearest, surface.get(), scan, options, L, &out);
  {  // ρ̃ at the final pose, on the refine level at the user's ε
    const detail::PoseObjective final_level =
        make_level(body, scan, options.refine_points, options.distance.params.epsilon,
                   options.threads, options);
    out.rho = final_level.value(out.pose.inverse(), nullptr, nullptr);
  }
  out.status = !std::isfinite(out.rho) ? AlignStatus::failed
               : limit                 ? AlignStatus::iteration_limit
                                       : AlignStatus::converged;
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace softhd::scan
