// A scan's surface against the body (docs/formulation.md §2.8, "A scan's surface against the
// body's cells"): ρ̃ of the one-sided form scan_to_body at the true shape, the scan an exact,
// noise-free sampling of the deformed body's surface at several densities, with the body
// integrated over its cells (quadrature cells) and collocated at its boundary nodes (the scan
// runs' moving cloud, deformed volumes). The true shape is the scene target's known map (the
// finger: the 2× finer solve of m* = −1.5 X₃ at the body's nodes); the surface sampled is the
// one the cell form integrates (its hexahedra's boundary at X + u). Points are uniform in area
// (seeded), each weighted area / count; density f gives f² × the body's boundary nodes per area of
// its whole boundary (the body's boundary spacing / f).
//
//   bench_scan_surface [--top] [--pose-bias SIGMA | --pose-fit SIGMA] SCENE [THREADS [TOL [SEED
//                      [F...]]]]
//
// --pose-bias SIGMA: instead, the pose's bias of each quadrature: the scan at the first density
// (default 1) with Gaussian noise of SIGMA × L on every coordinate (L the body's bounding-box
// diagonal; 0: none), rotated about the body's centroid by θ = −0.8°, −0.6°, …, 0.8° about each
// axis; per axis ρ̃ at each θ and the minimiser of the parabola through the three lowest (the
// true pose is θ = 0: the minimiser is the data term's bias along that rotation).
//
// --pose-fit SIGMA: instead, the data term's pose accuracy in all 6 degrees of freedom: the same
// noisy scan (first density, default 1), the body started from the true pose turned by 3° about a
// random axis through its centroid and moved by 0.02 L in a random direction (both seeded by
// SEED), and the pose refined by the projection's inner minimisation (scan::minimise_pose, first
// step 1e-3 L, 20 halvings, step tolerance 1e-10 L, 200 iterations) with cells (the body moved by
// the pose against the scan's surface, CellForm::posed_rho) and with collocation (β = 4, align's,
// and β = 2, the tracking run's default for scan_to_body); per quadrature the final pose's
// rotation error in degrees and its error at the scan's centroid in % of L, ρ̃ there and at the
// true pose, the iterations, the seconds, and where the scan's centroid moved (x, y, z in % L).
//
// --top: a one-sided view, the triangles whose outward normal has a positive z component only
// (seen from above, without occlusion). TOL (default 1e-4): the tree's tolerance for both
// quadratures (cells: J's, with the loop's rules when ≥ 3.7e-5). F default 0.5 1 2 4. Prints one
// line per density.

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <random>
#include <string>
#include <vector>

#include "control/cell_form.hpp"
#include "fe/hex_decomposition.hpp"
#include "hausdorff/cell_distance.hpp"
#include "softhd/control/moving_cloud.hpp"
#include "softhd/control/scene.hpp"
#include "softhd/control/scene_target.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/boundary.hpp"
#include "softhd/hausdorff.hpp"
#include "softhd/scan/align.hpp"
#include "softhd/scan/pose_map.hpp"

using namespace softhd;

namespace {

double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// The triangles of `s` whose outward normal has a positive z component (a view from above).
TriangleSurface top_view(const TriangleSurface& s) {
  std::vector<Eigen::Index> keep;
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t) {
    const Eigen::RowVector3d a = s.points.row(s.triangles(t, 0));
    const Eigen::RowVector3d b = s.points.row(s.triangles(t, 1));
    const Eigen::RowVector3d c = s.points.row(s.triangles(t, 2));
    if ((b - a).cross(c - a)[2] > 0.0) keep.push_back(t);
  }
  TriangleSurface v = s;
  v.triangles.resize(static_cast<Eigen::Index>(keep.size()), 3);
  for (std::size_t k = 0; k < keep.size(); ++k)
    v.triangles.row(static_cast<Eigen::Index>(k)) = s.triangles.row(keep[k]);
  return v;
}

// The area of every triangle of `s`.
std::vector<double> triangle_areas(const TriangleSurface& s) {
  std::vector<double> area(static_cast<std::size_t>(s.triangles.rows()));
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t) {
    const Eigen::RowVector3d a = s.points.row(s.triangles(t, 0));
    const Eigen::RowVector3d b = s.points.row(s.triangles(t, 1));
    const Eigen::RowVector3d c = s.points.row(s.triangles(t, 2));
    area[static_cast<std::size_t>(t)] = 0.5 * (b - a).cross(c - a).norm();
  }
  return area;
}

// `count` points uniform in area on `s` (triangle by its area, then uniform barycentric).
Eigen::MatrixXd sample_surface(const TriangleSurface& s, long count, unsigned seed) {
  const std::vector<double> area = triangle_areas(s);
  std::mt19937_64 rng(seed);
  std::discrete_distribution<long> pick(area.begin(), area.end());
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  Eigen::MatrixXd y(count, 3);
  for (long k = 0; k < count; ++k) {
    const long t = pick(rng);
    double r1 = u01(rng), r2 = u01(rng);
    if (r1 + r2 > 1.0) r1 = 1.0 - r1, r2 = 1.0 - r2;
    y.row(k) = (1 - r1 - r2) * s.points.row(s.triangles(t, 0)) +
               r1 * s.points.row(s.triangles(t, 1)) + r2 * s.points.row(s.triangles(t, 2));
  }
  return y;
}

double total_area(const TriangleSurface& s) {
  const std::vector<double> area = triangle_areas(s);
  return std::accumulate(area.begin(), area.end(), 0.0);
}

}  // namespace

// The minimiser of the parabola through the lowest value of `f` (at `t`) and its neighbours.
double parabola_minimum(const std::vector<double>& t, const std::vector<double>& f) {
  std::size_t k = 0;
  for (std::size_t i = 1; i < f.size(); ++i)
    if (f[i] < f[k]) k = i;
  if (k == 0 || k + 1 == f.size()) return t[k];  // at an end: no bracket
  const double a = f[k - 1], b = f[k], c = f[k + 1], h = t[k + 1] - t[k];
  return t[k] + 0.5 * h * (a - c) / (a - 2 * b + c);
}

// Per axis, ρ̃ (cells, collocation) of the scan rotated by θ about `centre`, and the minimisers.
void pose_bias(const fe::Mesh& mesh, const Eigen::VectorXd& u, const PointCloud& body,
               const Eigen::MatrixXd& y, const Eigen::VectorXd& w, const Eigen::Vector3d& centre,
               const detail::CellDistanceOptions& c, const HausdorffOptions& h,
               const HausdorffRequest& req) {
  const double deg = std::acos(-1.0) / 180.0;
  std::vector<double> theta;
  for (int k = -4; k <= 4; ++k) theta.push_back(0.2 * k);
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<double> cells, coll;
    for (double t : theta) {
      const Eigen::Matrix3d R = Eigen::AngleAxisd(t * deg, Eigen::Vector3d::Unit(axis)).matrix();
      const Eigen::MatrixXd yr =
          ((y.rowwise() - centre.transpose()) * R.transpose()).rowwise() + centre.transpose();
      cells.push_back(detail::CellForm(mesh, yr, w, c).evaluate(u).rho);
      coll.push_back(hausdorff(body, PointCloud(yr, w), h, req).rho);
      std::printf("axis %d theta %+.1f deg: cells %.8f collocation %.8f\n", axis, t, cells.back(),
                  coll.back());
    }
    std::printf("axis %d: minimiser cells %+.4f deg, collocation %+.4f deg\n", axis,
                parabola_minimum(theta, cells), parabola_minimum(theta, coll));
  }
}

// The start pose (body → scan frame): θ = 3° about a random axis through `centre`, then 0.02 L
// along a random direction (seeded).
scan::Pose perturbed_start(const Eigen::Vector3d& centre, double L, unsigned seed) {
  std::mt19937_64 rng(seed + 2000u);
  std::normal_distribution<double> n01(0.0, 1.0);
  const Eigen::Vector3d axis = Eigen::Vector3d(n01(rng), n01(rng), n01(rng)).normalized();
  const Eigen::Vector3d dir = Eigen::Vector3d(n01(rng), n01(rng), n01(rng)).normalized();
  scan::Pose Q;
  Q.R = Eigen::AngleAxisd(3.0 * std::acos(-1.0) / 180.0, axis).matrix();
  Q.t = centre - Q.R * centre + 0.02 * L * dir;
  return Q;
}

// One fit from `start`: the pose found, its errors against the identity (the true pose) and time.
void report_fit(const char* name, const scan::PoseFunction& f, const scan::Pose& start,
                const Eigen::Vector3d& scan_centre, double L) {
  scan::LocalPoseSettings st;
  st.size = L;
  st.max_iterations = 200;
  st.step_tolerance = 1e-10;
  st.first_step = 1e-3;
  st.max_backtracks = 20;
  const double t0 = now();
  const scan::LocalPoseResult r = scan::minimise_pose(f, start, st);
  const double seconds = now() - t0;
  const auto error = [&](const scan::Pose& Q, double* deg, double* shift) {
    *deg = scan::rotation_angle_between(Q.R, Eigen::Matrix3d::Identity()) * 180.0 / std::acos(-1.0);
    *shift =
        100.0 *
        (scan::apply_points(Q.inverse(), scan_centre.transpose()).row(0).transpose() - scan_centre)
            .norm() /
        L;
  };
  double d0, s0, d1, s1;
  error(start, &d0, &s0);
  error(r.pose, &d1, &s1);
  // Where the scan's centroid lands in the body's frame, relative to its true place (% L).
  const Eigen::Vector3d moved =
      100.0 / L *
      (scan::apply_points(r.pose.inverse(), scan_centre.transpose()).row(0).transpose() -
       scan_centre);
  const double at_truth = f(scan::Pose(), nullptr, nullptr);
  std::printf(
      "%-22s start %.3f deg %.3f %%L -> %.4f deg %.4f %%L  rho %.8g (true pose %.8g)  %d it %d ev "
      "%s  %.2f s; the scan's centroid moved by (%+.3f, %+.3f, %+.3f) %% L\n",
      name, d0, s0, d1, s1, r.rho, at_truth, r.iterations, r.evaluations,
      r.converged ? "converged" : "limit", seconds, moved[0], moved[1], moved[2]);
}

// The 6-DOF fit with cells and collocation (β = 4 and 2) from the perturbed start.
void pose_fit(const fe::Mesh& mesh, const Eigen::VectorXd& u, const PointCloud& body,
              const Eigen::MatrixXd& y, const Eigen::VectorXd& w, double L, unsigned seed,
              const detail::CellDistanceOptions& c, const HausdorffOptions& h) {
  const Eigen::RowVector3d mean = body.points().colwise().mean();
  const scan::Pose start = perturbed_start(mean.transpose(), L, seed);
  const Eigen::Vector3d scan_centre = y.colwise().mean().transpose();
  double t0 = now();
  const detail::CellForm form(mesh, y, w, c);
  const auto deformed = form.deform(u);
  std::printf("cells: the body's J built in %.2f s\n", now() - t0);
  const scan::PoseFunction cells = [&](const scan::Pose& Q, Eigen::VectorXd* g,
                                       Eigen::Vector3d* centre) {
    const Eigen::Vector3d cq = scan::apply_points(Q, mean).row(0).transpose();
    if (g) *centre = cq;
    return form.posed_rho(*deformed, Q, cq, g);
  };
  report_fit("cells (beta 4)", cells, start, scan_centre, L);
  DistanceForm one_sided;
  one_sided.sides = Sides::scan_to_body;
  for (double beta : {4.0, 2.0}) {
    HausdorffOptions hb = h;
    hb.params.beta = beta;
    const HausdorffTarget target(PointCloud(y, w), hb);
    const scan::PoseFunction coll = [&](const scan::Pose& Q, Eigen::VectorXd* g,
                                        Eigen::Vector3d* centre) {
      return scan::pose_distance(target, body, one_sided, Q, g, centre);
    };
    report_fit(beta == 4.0 ? "collocation (beta 4)" : "collocation (beta 2)", coll, start,
               scan_centre, L);
  }
}

int main(int argc, char** argv) {
  const bool top = argc > 1 && std::string(argv[1]) == "--top";
  if (top) --argc, ++argv;
  double bias_sigma = -1.0;  // < 0: the density table
  bool fit = false;          // --pose-fit: the 6-DOF fit instead of the 1-D scans
  if (argc > 2 && (std::string(argv[1]) == "--pose-bias" || std::string(argv[1]) == "--pose-fit")) {
    fit = std::string(argv[1]) == "--pose-fit";
    bias_sigma = std::atof(argv[2]);
    argc -= 2, argv += 2;
  }
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: bench_scan_surface [--top] [--pose-bias|--pose-fit SIGMA] SCENE [THREADS "
                 "[TOL [SEED [F...]]]]\n");
    return 2;
  }
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  try {
    const Scene scene = load_scene(argv[1]);
    const fe::Assembler A = scene.body.make_assembler();
    const fe::Mesh& mesh = A.mesh();
    const SceneTarget target = scene_target(scene, mesh);
    if (!target.map_displacement || mesh.dim != 3) {
      std::fprintf(stderr, "%s: needs a 3D scene whose target has a known map\n", argv[1]);
      return 2;
    }
    const int threads = argc > 2 ? std::atoi(argv[2]) : 0;
    const double tol = argc > 3 ? std::atof(argv[3]) : 1e-4;
    const unsigned seed = argc > 4 ? static_cast<unsigned>(std::atoi(argv[4])) : 1u;
    std::vector<double> densities;
    for (int k = 5; k < argc; ++k) densities.push_back(std::atof(argv[k]));
    if (densities.empty()) densities = {0.5, 1.0, 2.0, 4.0};

    const Eigen::VectorXd& u = *target.map_displacement;  // node-major
    const Eigen::Index n = mesh.num_nodes();
    const fe::HexDecomposition d = fe::hex_decomposition(mesh);
    const detail::HexCells cells{d.map * (mesh.nodes + u.reshaped(3, n).transpose()), d.cells};
    const TriangleSurface whole = detail::hex_boundary(cells);
    const TriangleSurface surface = top ? top_view(whole) : whole;
    const MovingCloud moving(A, Particles::boundary, ParticleVolumes::deformed, true);
    const PointCloud body = moving.at(u);
    const double area = total_area(surface);

    HausdorffOptions h;
    h.method = Method::tree;
    h.tolerance = tol;
    h.threads = threads;
    detail::CellDistanceOptions c;
    c.epsilon = h.params.epsilon;
    c.threads = threads;
    c.tolerance = tol;
    if (tol >= 3.7e-5) c.j_near_ratio = 2.0, c.j_angle_points = 8;
    HausdorffRequest req;
    req.form.sides = Sides::scan_to_body;
    std::printf("scene %s: %ld boundary nodes, %s surface area %.6g, tree tolerance %g, seed %u\n",
                argv[1], static_cast<long>(body.size()), top ? "top view's" : "whole", area, tol,
                seed);
    if (bias_sigma >= 0.0) {
      const double per_area = static_cast<double>(body.size()) / total_area(whole);
      const double f = argc > 5 ? densities[0] : 1.0;  // the first F given, else 1
      const long count = std::max(1L, static_cast<long>(f * f * per_area * area));
      Eigen::MatrixXd y = sample_surface(surface, count, seed);
      const Eigen::RowVector3d lo = body.points().colwise().minCoeff();
      const double L = (body.points().colwise().maxCoeff() - lo).norm();
      std::mt19937_64 rng(seed + 1000u);
      std::normal_distribution<double> noise(0.0, bias_sigma * L);
      for (Eigen::Index k = 0; k < y.size(); ++k) y.data()[k] += noise(rng);
      const Eigen::VectorXd w = Eigen::VectorXd::Constant(count, area / static_cast<double>(count));
      std::printf("pose bias: %ld points (density %g), noise %g L (L = %g)\n", count, f, bias_sigma,
                  L);
      if (fit)
        pose_fit(mesh, u, body, y, w, L, seed, c, h);
      else
        pose_bias(mesh, u, body, y, w, body.points().colwise().mean().transpose(), c, h, req);
      return 0;
    }
    std::printf("density points  rho_cells  s_cells  rho_collocation  s_collocation\n");
    for (double f : densities) {
      // f² × the boundary nodes per area of the whole boundary: spacing / f
      const double per_area = static_cast<double>(body.size()) / total_area(whole);
      const long count = std::max(1L, static_cast<long>(f * f * per_area * area));
      const Eigen::MatrixXd y = sample_surface(surface, count, seed);
      const Eigen::VectorXd w = Eigen::VectorXd::Constant(count, area / static_cast<double>(count));
      double t0 = now();
      const detail::CellForm form(mesh, y, w, c);
      const double rho_cells = form.evaluate(u).rho;
      const double s_cells = now() - t0;
      t0 = now();
      const double rho_coll = hausdorff(body, PointCloud(y, w), h, req).rho;
      const double s_coll = now() - t0;
      std::printf("%7.3g %7ld  %.7f  %7.2f  %.7f  %7.3f\n", f, count, rho_cells, s_cells, rho_coll,
                  s_coll);
    }
  } catch (const Error& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  return 0;
}
