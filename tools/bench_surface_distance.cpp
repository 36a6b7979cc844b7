// Signed-distance queries to a body's boundary surface (lib/src/common/surface_bvh.hpp,
// docs/formulation.md §2.8) against all triangles tried one by one, in one process.
//
//   bench_surface_distance [--scene PATH] [--points N] [--brute N] [--radius R] [--threads T]
//                          [--repeats R]
//
// The scene's mesh (undeformed) and its fe::boundary_surface; queries at the mesh's nodes and
// at N random points in the scene's box (default 1e5). Prints the hierarchy's build time,
// queries per second of SurfaceDistance::at_rows (1 thread and T threads), of the brute force
// (1 thread, on the first --brute queries of each set, default 2000) with the largest
// difference of the distances, and of the radius query (triangles within R, default 1.5 × the
// mean edge length). Medians of R repeats (default 5), the methods interleaved.

#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "common/surface_bvh.hpp"
#include "softhd/control/scene.hpp"
#include "softhd/fe/boundary.hpp"

namespace {

using softhd::detail::SurfaceDistance;

template <class F>
double seconds(F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The closest distance from y to every triangle, tried one by one (the library's
// per-triangle routine: the comparison times the search alone).
double brute_distance(const softhd::TriangleSurface& s, const Eigen::Vector3d& y) {
  double best = INFINITY;
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t) {
    const Eigen::Vector3d a = softhd::detail::corner(s, t, 0), b = softhd::detail::corner(s, t, 1),
                          c = softhd::detail::corner(s, t, 2);
    const Eigen::Vector3d l = softhd::detail::closest_on_triangle(y, a, b, c).lambda;
    best = std::min(best, (y - (l[0] * a + l[1] * b + l[2] * c)).squaredNorm());
  }
  return std::sqrt(best);
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Each timing repeated `repeats` times, the methods interleaved; medians.
void run(const char* name, const SurfaceDistance& sd, const Eigen::MatrixXd& y, int brute_n,
         double radius, int threads, int repeats) {
  std::vector<softhd::detail::SignedDistance> q1, qt;
  const int nb = std::min<int>(brute_n, static_cast<int>(y.rows()));
  std::vector<double> brute(static_cast<size_t>(nb)), t1, tt, tb, tr;
  std::vector<int> start, tri;
  for (int r = 0; r < repeats; ++r) {
    t1.push_back(seconds([&] { q1 = sd.at_rows(y, 1); }));
    tt.push_back(seconds([&] { qt = sd.at_rows(y, threads); }));
    tb.push_back(seconds([&] {
      for (int i = 0; i < nb; ++i) brute[i] = brute_distance(sd.surface(), y.row(i).transpose());
    }));
    tr.push_back(seconds([&] { sd.within_rows(y, radius, &start, &tri, 1); }));
  }
  double diff = 0.0;
  for (int i = 0; i < nb; ++i) diff = std::max(diff, std::abs(std::abs(q1[i].sd) - brute[i]));
  const double Q = static_cast<double>(y.rows());
  const double r1 = Q / median(t1), rt = Q / median(tt), rb = nb / median(tb);
  std::printf(
      "%-22s %8d queries: sd %9.0f /s (1 thread), %9.0f /s (%d threads); brute force %7.0f /s "
      "(1 thread, %d queries; max |Δd| %.1e): %.0fx; within r: %9.0f /s (1 thread), %.1f "
      "triangles per query\n",
      name, static_cast<int>(Q), r1, rt, threads, rb, nb, diff, r1 / rb, Q / median(tr),
      tri.size() / Q);
}

}  // namespace

int main(int argc, char** argv) {
  std::string scene = std::string(SOFTHD_SOURCE_DIR) + "/data/scenes/bending.json";
  int points = 100000, brute_n = 2000, threads = 2, repeats = 5;
  double radius = -1.0;
  for (int i = 1; i < argc; i += 2) {
    const std::string a = argv[i];
    if (i + 1 >= argc) {
      std::fprintf(stderr, "%s needs a value\n", a.c_str());
      return 2;
    }
    if (a == "--scene")
      scene = argv[i + 1];
    else if (a == "--points")
      points = std::stoi(argv[i + 1]);
    else if (a == "--brute")
      brute_n = std::stoi(argv[i + 1]);
    else if (a == "--radius")
      radius = std::stod(argv[i + 1]);
    else if (a == "--threads")
      threads = std::stoi(argv[i + 1]);
    else if (a == "--repeats")
      repeats = std::stoi(argv[i + 1]);
    else {
      std::fprintf(stderr, "unknown option %s\n", a.c_str());
      return 2;
    }
  }
  if (points < 1 || brute_n < 1 || threads < 1 || repeats < 1) {
    std::fprintf(stderr, "--points, --brute, --threads and --repeats must be >= 1\n");
    return 2;
  }
  const softhd::Scene sc = softhd::load_scene(scene);
  const softhd::fe::Mesh mesh = sc.body.make_mesh();
  const softhd::TriangleSurface s =
      softhd::fe::boundary_surface(mesh, Eigen::VectorXd::Zero(mesh.num_nodes() * 3));
  double edges = 0.0;
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t)
    for (int k = 0; k < 3; ++k)
      edges += (softhd::detail::corner(s, t, k) - softhd::detail::corner(s, t, (k + 1) % 3)).norm();
  if (radius < 0.0) radius = 1.5 * edges / (3.0 * s.triangles.rows());
  std::printf("%s: %d mesh nodes, surface %d points, %d triangles; radius %.4g\n", scene.c_str(),
              static_cast<int>(mesh.num_nodes()), static_cast<int>(s.points.rows()),
              static_cast<int>(s.triangles.rows()), radius);
  const auto t0 = std::chrono::steady_clock::now();
  const SurfaceDistance sd(s);
  const double tb = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("build (closedness, pseudo-normals, hierarchy): %.2f ms\n", 1e3 * tb);
  run("mesh nodes", sd, mesh.nodes, brute_n, radius, threads, repeats);
  std::mt19937_64 rng(1);
  const Eigen::Vector3d lo = s.points.colwise().minCoeff(), hi = s.points.colwise().maxCoeff();
  std::uniform_real_distribution<double> U(0.0, 1.0);
  Eigen::MatrixXd y(points, 3);
  for (int i = 0; i < points; ++i)
    for (int k = 0; k < 3; ++k) y(i, k) = lo[k] + (hi[k] - lo[k]) * U(rng);
  run("random points in box", sd, y, brute_n, radius, threads, repeats);
  return 0;
}
