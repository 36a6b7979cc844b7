// The coverage score by which align() ranks its starts and chooses among its refined
// candidates (docs/formulation.md §8.5): a flipped one-sided view shows the camera the side
// of the body the scan does not have.

#include <algorithm>
#include <cmath>
#include <limits>

#include "align_internal.hpp"
#include "softhd/parallel.hpp"

namespace softhd::scan::detail {

CoverageScore::CoverageScore(const Eigen::MatrixXd& body, const Eigen::MatrixXd& scan, double size,
                             double truncation, int threads, const BodySurface* surface)
    : body_(body),
      scan_(scan),
      size_(size),
      truncation_(truncation),
      threads_(threads),
      body_tree_(body_),
      scan_tree_(scan_),
      surface_(surface) {
  // The image: the camera at the origin looking at the scan's centroid (e3), pinhole
  // coordinates (p·e1, p·e2)/(p·e3); pixels of width L/n at the centroid's depth,
  // n = clamp(√N_body / 1.5, 8, 200) (a few body points per pixel on a surface).
  const Eigen::Vector3d mean = scan.colwise().mean().transpose();
  e3_ = mean.norm() > 0.0 ? Eigen::Vector3d(mean.normalized()) : Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d a =
      std::abs(e3_.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  e1_ = e3_.cross(a).normalized();
  e2_ = e3_.cross(e1_);
  const double n = std::clamp(std::sqrt(static_cast<double>(body.rows())) / 1.5, 8.0, 200.0);
  const double depth = std::max(mean.dot(e3_), 1e-12 * size);
  pixel_ = size / (n * depth);  // in pinhole units
  depth_tolerance_ = 0.5 * size / n;
  lo_u_ = lo_v_ = std::numeric_limits<double>::infinity();
  double hi_u = -lo_u_, hi_v = -lo_v_;
  for (Eigen::Index j = 0; j < scan.rows(); ++j) {
    const Eigen::Vector3d p = scan.row(j).transpose();
    if (p.dot(e3_) <= 0.0) continue;
    const double u = p.dot(e1_) / p.dot(e3_), v = p.dot(e2_) / p.dot(e3_);
    lo_u_ = std::min(lo_u_, u);
    lo_v_ = std::min(lo_v_, v);
    hi_u = std::max(hi_u, u);
    hi_v = std::max(hi_v, v);
  }
  const double cells_max = 4.0 * n;  // outliers far off may stretch the box: cap the grid
  if (std::isfinite(lo_u_)) {
    pixel_ = std::max({pixel_, (hi_u - lo_u_) / cells_max, (hi_v - lo_v_) / cells_max});
    nu_ = static_cast<Eigen::Index>((hi_u - lo_u_) / pixel_) + 1;
    nv_ = static_cast<Eigen::Index>((hi_v - lo_v_) / pixel_) + 1;
  }
  footprint_.assign(static_cast<size_t>(nu_ * nv_), 0);
  for (Eigen::Index j = 0; j < scan.rows(); ++j) {
    const Eigen::Index k = pixel_of(scan.row(j).transpose());
    if (k >= 0) footprint_[static_cast<size_t>(k)] = 1;
  }
}

Eigen::Index CoverageScore::pixel_of(const Eigen::Vector3d& p) const {
  const double z = p.dot(e3_);
  if (!(z > 0.0) || nu_ == 0) return -1;
  const double fu = std::floor((p.dot(e1_) / z - lo_u_) / pixel_);
  const double fv = std::floor((p.dot(e2_) / z - lo_v_) / pixel_);
  if (!(fu >= 0.0 && fv >= 0.0 && fu < static_cast<double>(nu_) && fv < static_cast<double>(nv_)))
    return -1;
  return static_cast<Eigen::Index>(fv) * nu_ + static_cast<Eigen::Index>(fu);
}

double CoverageScore::value(const Pose& Q) const {
  // In the scan's frame (Q(B) has size s_Q L), c = truncation · s_Q L:
  //   S = ½ [(1/M) Σ_j min(d(y_j, Q(B)), c) + (1/|V|) Σ_{x∈V} min(d(x, Y), c)] / (s_Q L),
  // V the moved body points within half a pixel width of the nearest to the camera in their
  // pixel, over the pixels that hold scan points.
  const Eigen::MatrixXd X = apply_points(Q, body_);
  const double Lq = size_ * Q.s, c = truncation_ * Lq;
  std::vector<double> zmin(footprint_.size(), std::numeric_limits<double>::infinity());
  std::vector<Eigen::Index> pix(static_cast<size_t>(X.rows()));
  for (Eigen::Index i = 0; i < X.rows(); ++i) {
    const Eigen::Vector3d x = X.row(i).transpose();
    const Eigen::Index k = pixel_of(x);
    pix[static_cast<size_t>(i)] = k;
    if (k >= 0 && footprint_[static_cast<size_t>(k)])
      zmin[static_cast<size_t>(k)] = std::min(zmin[static_cast<size_t>(k)], x.norm());
  }
  std::vector<Eigen::Index> seen;
  for (Eigen::Index i = 0; i < X.rows(); ++i) {
    const Eigen::Index k = pix[static_cast<size_t>(i)];
    if (k >= 0 && footprint_[static_cast<size_t>(k)] &&
        X.row(i).norm() <= zmin[static_cast<size_t>(k)] + depth_tolerance_ * Q.s)
      seen.push_back(i);
  }
  Eigen::MatrixXd V(static_cast<Eigen::Index>(seen.size()), 3);
  for (size_t k = 0; k < seen.size(); ++k) V.row(static_cast<Eigen::Index>(k)) = X.row(seen[k]);
  std::vector<Eigen::Index> index;
  Eigen::VectorXd d;
  double body_side = c;  // no visible body point in the footprint: the worst
  if (V.rows() > 0) {
    scan_tree_.nearest(V, &index, &d, threads_);
    body_side = d.cwiseMin(c).mean();
  }
  // d(y_j, Q(B)) = d(P y_j, B)·s_Q with P = Q⁻¹ (the body's tree is in its own frame).
  double scan_side = 0.0;
  if (surface_ != nullptr) {
    scan_side = mean_surface_distance(*surface_, scan_, Q.inverse(), c / Q.s, threads_) * Q.s;
  } else {
    body_tree_.nearest(apply_points(Q.inverse(), scan_), &index, &d, threads_);
    scan_side = (d * Q.s).cwiseMin(c).mean();
  }
  return 0.5 * (scan_side + body_side) / Lq;
}

size_t choose_candidate(const PointCloud& body, const PointCloud& scan, double size,
                        const AlignOptions& options, const FixtureConstraint* fixture,
                        const BodySurface* surface, std::vector<LocalResult>* refined) {
  std::vector<LocalResult>& r = *refined;
  if (r.size() < 2) return 0;
  std::vector<double> score(r.size());
  for (size_t k = 0; k < r.size(); ++k) score[k] = r[k].rho;
  const bool coverage = options.score == CandidateScore::coverage;
  if (coverage || surface != nullptr) {
    if (options.nearest_iterations > 0) {
      const NearestPoints nearest(body.points());
      AlignOptions serial = options;
      serial.threads = 1;
      std::vector<Pose> fitted(r.size());
#pragma omp parallel for schedule(dynamic) num_threads(resolve_threads(options.threads))
      for (size_t k = 0; k < r.size(); ++k) {
        int iterations = 0;
        fitted[k] = nearest_refinement(nearest, body.points(), surface, scan.points(),
                                       r[k].pose.inverse(), serial, fixture, size, &iterations);
      }
      for (size_t k = 0; k < r.size(); ++k) r[k].pose = fitted[k].inverse();
    }
  }
  if (coverage) {
    const CoverageScore S(body.points(), scan.points(), size, options.score_truncation,
                          options.threads, surface);
    for (size_t k = 0; k < r.size(); ++k)
      if (std::isfinite(score[k])) score[k] = S.value(r[k].pose);
  } else if (surface != nullptr) {  // rho with a surface: the scan's distance to it
    for (size_t k = 0; k < r.size(); ++k)
      if (std::isfinite(score[k]))
        score[k] = mean_surface_distance(*surface, scan.points(), r[k].pose.inverse(),
                                         options.score_truncation * size, options.threads);
  }
  if (fixture != nullptr)  // the clamp's side (all on the wrong side: the first)
    for (size_t k = 0; k < r.size(); ++k)
      if (!fixture->allows(r[k].pose)) score[k] = INFINITY;
  size_t best = 0;
  for (size_t k = 1; k < r.size(); ++k)
    if (score[k] < score[best]) best = k;
  return best;
}

}  // namespace softhd::scan::detail
