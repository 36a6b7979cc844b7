// The boundary form's inner integral J(y) (hausdorff/body_integral.hpp) measured
// (docs/formulation.md §2.8):
//   bench_body_integral accuracy FILE   largest relative error around the unit cube against the
//                                       box code's values in FILE (x y z J per line, made by
//                                       studies/cell_reference_points.py), per near ratio
//   bench_body_integral plate           the near ratio's error and time at a fifth of the
//                                       bending plate's nodes
//   bench_body_integral cost [THREADS]  J, its gradient and the surface product at the bending
//                                       plate's nodes against the collocated rho~ (exact); J, its
//                                       gradient and the surface product by the tree (tolerance
//                                       1e-2, also with near_ratio 2 and angle_points 8; 1e-6)
//                                       against all pairs and collocation's tree at that tolerance
//   bench_body_integral cells [THREADS [REPS [OUT [TOL]]]]  J, J and its gradient, and the surface
//                                       product (weights 1) at the 2×2×2 Gauss points of the
//                                       10 × 2 × 0.1 plate's 100 × 10 × 4 hexahedra (the cell
//                                       distance's samples) against the plate's own boundary, by
//                                       the tree at TOL, 1e-2 (0: all pairs, the first only;
//                                       near_ratio 2, angle_points 8; then the defaults): seconds,
//                                       REPS repeats; OUT: J (value only), J, the gradient and the
//                                       product's rows at near_ratio 2 written there (raw doubles)
#include <Eigen/Core>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "hausdorff/body_integral.hpp"
#include "hausdorff/cell_distance.hpp"
#include "hausdorff/cell_rule.hpp"
#include "softhd/control/scene.hpp"
#include "softhd/fe/boundary.hpp"
#include "softhd/fe/geometry.hpp"
#include "softhd/hausdorff.hpp"

using namespace softhd;

using detail::BodyIntegral;
using detail::BodyIntegralOptions;

static double now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// The unit cube, each face n × n squares of two triangles (the cell distance's hexahedral
// cube's boundary).
TriangleSurface box_surface(int n) {
  return detail::hex_boundary(detail::hex_cube(Eigen::Vector3d::Zero(), 1.0, n));
}

void accuracy(const char* file) {
  std::ifstream in(file);
  std::vector<double> v;
  double x;
  while (in >> x) v.push_back(x);
  const int m = v.size() / 4;
  Eigen::MatrixXd y(m, 3);
  Eigen::VectorXd ref(m);
  for (int k = 0; k < m; ++k) {
    y.row(k) << v[4 * k], v[4 * k + 1], v[4 * k + 2];
    ref[k] = v[4 * k + 3];
  }
  std::printf("# accuracy vs J_box (%d points: 150 in [-0.3,1.3]^3, 100 within 3 eps of a face)\n",
              m);
  std::printf("mesh n  near_ratio  angle_pts  max_rel_err  near_pairs_frac  seconds\n");
  for (int n : {4, 8, 16}) {
    const TriangleSurface s = box_surface(n);
    for (double ratio : {2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0})
      for (int ap : {16}) {
        BodyIntegralOptions o;
        o.near_ratio = ratio;
        o.angle_points = ap;
        o.threads = 1;
        BodyIntegral b(s, o);
        Eigen::VectorXd J;
        double t0 = now();
        b.evaluate(y, &J);
        double t1 = now();
        double err = ((J - ref).array() / ref.array()).abs().maxCoeff();
        // fraction of near pairs
        long near = 0;
        for (int k = 0; k < m; ++k)
          for (int t = 0; t < s.triangles.rows(); ++t) {
            Eigen::Vector3d c = Eigen::Vector3d::Zero();
            double R2 = 0;
            for (int a = 0; a < 3; ++a) c += s.points.row(s.triangles(t, a)).transpose() / 3.0;
            for (int a = 0; a < 3; ++a)
              R2 = std::max(R2, (s.points.row(s.triangles(t, a)).transpose() - c).squaredNorm());
            if ((y.row(k).transpose() - c).squaredNorm() < ratio * ratio * R2) ++near;
          }
        std::printf("%2d  %5.1f  %3d  %.3e  %.4f  %.3f\n", n, ratio, ap, err,
                    double(near) / (double(m) * s.triangles.rows()), t1 - t0);
      }
  }
  std::printf(
      "# angle points, polar rule only (mesh n = 4, near_ratio = 16: all pairs near but the outer "
      "corner ones)\n");
  for (int ap : {4, 6, 8, 10, 12, 16, 20}) {
    BodyIntegralOptions o;
    o.angle_points = ap;
    o.near_ratio = 30;
    o.threads = 1;
    BodyIntegral b(box_surface(4), o);
    Eigen::VectorXd J;
    b.evaluate(y, &J);
    std::printf("angle_points %2d  max_rel_err %.3e\n", ap,
                ((J - ref).array() / ref.array()).abs().maxCoeff());
  }
  std::printf("# angle points (mesh n = 8, near_ratio = 8)\n");
  for (int ap : {4, 6, 8, 10, 12, 16, 20, 24, 32}) {
    BodyIntegralOptions o;
    o.angle_points = ap;
    o.near_ratio = 8;
    o.threads = 1;
    BodyIntegral b(box_surface(8), o);
    Eigen::VectorXd J;
    double t0 = now();
    b.evaluate(y, &J);
    double t1 = now();
    std::printf("angle_points %2d  max_rel_err %.3e  %.3f s\n", ap,
                ((J - ref).array() / ref.array()).abs().maxCoeff(), t1 - t0);
  }
}

void cost(const char* scene_path, int threads) {
  Scene sc = load_scene(scene_path);
  fe::Mesh mesh = sc.body.make_mesh();
  fe::ReferenceGeometry geo(mesh);
  Eigen::VectorXd vol = fe::lumped_volumes(mesh, geo);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(mesh.num_nodes() * 3);
  TriangleSurface surf = fe::boundary_surface(mesh, u);
  const Eigen::MatrixXd& X = mesh.nodes;
  std::printf("# cost: %s, %ld nodes, %ld boundary points, %ld boundary triangles, threads %d\n",
              scene_path, (long)X.rows(), (long)surf.points.rows(), (long)surf.triangles.rows(),
              threads);
  PointCloud cloud(X, vol);
  HausdorffOptions ho;
  ho.method = Method::exact;
  ho.threads = threads;
  BodyIntegralOptions o;
  o.threads = threads;
  BodyIntegral b(surf, o);
  Eigen::VectorXd J, w = Eigen::VectorXd::Ones(X.rows());
  Eigen::MatrixXd G;
  HausdorffRequest req;
  req.gradient_points = true;
  for (int rep = 0; rep < 2; ++rep) {
    double t0 = now();
    HausdorffResult r = hausdorff(cloud, cloud, ho, {});
    double t1 = now();
    hausdorff(cloud, cloud, ho, req);
    double t2 = now();
    b.evaluate(X, &J);
    double t3 = now();
    b.evaluate(X, &J, &G);
    double t4 = now();
    Eigen::MatrixXd V = b.surface_vjp(X, w);
    double t5 = now();
    std::printf(
        "rep %d: collocation exact (%ld^2 pairs, both directions): value %.3f s, value+grad %.3f s "
        "| "
        "J at the nodes %.3f s (%.0f evals/s), J+grad_y %.3f s, surface vjp %.3f s | rho %.6f, "
        "mean J %.3f\n",
        rep, (long)X.rows(), t1 - t0, t2 - t1, t3 - t2, X.rows() / (t3 - t2), t4 - t3, t5 - t4,
        r.rho, J.mean());
  }
  // The tree (tolerance τ; with near_ratio and angle_points) against all pairs (the defaults),
  // interleaved, with collocation's tree at the same τ.
  struct Config {
    double tau, near_ratio;
    int angle_points;
  };
  for (int rep = 0; rep < 2; ++rep)
    for (const Config& cf : {Config{1e-2, 4.0, 12}, Config{1e-2, 2.0, 8}, Config{1e-6, 4.0, 12}}) {
      BodyIntegralOptions ot = o;
      ot.tolerance = cf.tau;
      ot.near_ratio = cf.near_ratio;
      ot.angle_points = cf.angle_points;
      const BodyIntegral bt(surf, ot);
      HausdorffOptions hot = ho;
      hot.method = Method::tree;
      hot.tolerance = cf.tau;
      Eigen::VectorXd J0, J1;
      Eigen::MatrixXd G0, G1;
      double t0 = now();
      b.evaluate(X, &J0, &G0);
      double t1 = now();
      const Eigen::MatrixXd V0 = b.surface_vjp(X, w);
      double t2 = now();
      bt.evaluate(X, &J1);
      double t3 = now();
      bt.evaluate(X, &J1, &G1);
      double t4 = now();
      const Eigen::MatrixXd V1 = bt.surface_vjp(X, w);
      double t5 = now();
      hausdorff(cloud, cloud, hot, {});
      double t6 = now();
      hausdorff(cloud, cloud, hot, req);
      double t7 = now();
      double ej = 0.0;
      for (Eigen::Index k = 0; k < X.rows(); ++k)
        ej = std::max(ej, std::abs(J1[k] - J0[k]) / J0[k]);
      std::printf(
          "rep %d, tau %.0e, near_ratio %.0f, angle_points %d: all pairs J+grad %.3f s, vjp %.3f "
          "s | tree: J %.3f s, J+grad %.3f s, vjp %.3f s (max |dJ|/J %.1e, |dG|/|G| %.1e, |dV|/|V| "
          "%.1e, Frobenius) | collocation tree: value %.3f s, value+grad %.3f s\n",
          rep, cf.tau, cf.near_ratio, cf.angle_points, t1 - t0, t2 - t1, t3 - t2, t4 - t3, t5 - t4,
          ej, (G1 - G0).norm() / G0.norm(), (V1 - V0).norm() / V0.norm(), t6 - t5, t7 - t6);
      std::fflush(stdout);
    }
  // near fraction
  long near = 0;
  for (int k = 0; k < X.rows(); ++k)
    for (int t = 0; t < surf.triangles.rows(); ++t) {
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      double R2 = 0;
      for (int a = 0; a < 3; ++a) c += surf.points.row(surf.triangles(t, a)).transpose() / 3.0;
      for (int a = 0; a < 3; ++a)
        R2 = std::max(R2, (surf.points.row(surf.triangles(t, a)).transpose() - c).squaredNorm());
      if ((X.row(k).transpose() - c).squaredNorm() < 16 * R2) ++near;
    }
  {
    BodyIntegralOptions of;
    of.threads = threads;
    of.near_ratio = 1.0;
    BodyIntegral bf(surf, of);
    double t0 = now();
    bf.evaluate(X, &J);
    std::printf("near_ratio 1 (almost all far): J at the nodes %.3f s\n", now() - t0);
  }
  std::printf("near pairs: %ld of %ld (%.4f)\n", near, (long)(X.rows() * surf.triangles.rows()),
              double(near) / (X.rows() * surf.triangles.rows()));
}

// The box [0, 10] × [0, 2] × [0, 0.1] meshed by nx · ny · nz hexahedra (Gmsh's corner order).
detail::HexCells plate_cells(int nx, int ny, int nz) {
  return detail::hex_box(Eigen::Vector3d::Zero(), Eigen::Vector3d(10, 2, 0.1),
                         Eigen::Vector3i(nx, ny, nz));
}

void cells(int threads, int reps, const char* out, double tol) {
  const detail::HexCells plate = plate_cells(100, 10, 4);
  const TriangleSurface surf = detail::hex_boundary(plate);
  std::vector<detail::cell_rule::Cell> cs;
  for (Eigen::Index c = 0; c < plate.cells.rows(); ++c)
    cs.push_back(detail::cell_rule::cell_of(plate, c));
  Eigen::MatrixXd y;
  Eigen::VectorXd weight;
  detail::cell_rule::cell_samples(cs, &y, &weight);
  const Eigen::VectorXd w = Eigen::VectorXd::Ones(y.rows());
  std::printf(
      "# cells: %ld Gauss points of the plate's %ld cells, %ld boundary triangles, "
      "threads %d\n",
      (long)y.rows(), (long)plate.cells.rows(), (long)surf.triangles.rows(), threads);
  struct Config {
    double near_ratio;
    int angle_points;
  };
  Eigen::VectorXd J;
  Eigen::MatrixXd G, V;
  for (int rep = 0; rep < reps; ++rep)
    for (const Config& cf : {Config{2.0, 8}, Config{4.0, 12}}) {
      if (tol == 0.0 && cf.near_ratio != 2.0) continue;  // all pairs: the reference of OUT only
      BodyIntegralOptions o;
      o.threads = threads;
      o.tolerance = tol;
      o.near_ratio = cf.near_ratio;
      o.angle_points = cf.angle_points;
      const BodyIntegral b(surf, o);
      Eigen::VectorXd J1;
      const double t0 = now();
      b.evaluate(y, &J1);
      const double t1 = now();
      b.evaluate(y, &J, &G);
      const double t2 = now();
      V = b.surface_vjp(y, w);
      const double t3 = now();
      std::printf(
          "rep %d, tau %.0e, near_ratio %.0f, angle_points %d: J %.3f s, J+grad %.3f s, vjp %.3f s "
          "| mean J %.9g, max |J(value) - J(value+grad)|/J %.1e\n",
          rep, tol, cf.near_ratio, cf.angle_points, t1 - t0, t2 - t1, t3 - t2, J.mean(),
          ((J1 - J).array() / J.array()).abs().maxCoeff());
      std::fflush(stdout);
      if (out && rep == 0 && cf.near_ratio == 2.0) {
        std::FILE* f = std::fopen(out, "wb");
        const Eigen::MatrixXd gt = G.transpose(), vt = V.transpose();
        std::fwrite(J1.data(), sizeof(double), J1.size(), f);
        std::fwrite(J.data(), sizeof(double), J.size(), f);
        std::fwrite(gt.data(), sizeof(double), gt.size(), f);
        std::fwrite(vt.data(), sizeof(double), vt.size(), f);
        std::fclose(f);
      }
    }
}

int main(int argc, char** argv) {
  std::string what = argc > 1 ? argv[1] : "";
  if (what != "accuracy" && what != "plate" && what != "cost" && what != "cells") {
    std::fprintf(stderr,
                 "usage: bench_body_integral accuracy FILE | plate | cost [THREADS] | cells "
                 "[THREADS [REPS [OUT [TOL]]]]\n");
    return 2;
  }
  if (what == "accuracy") {
    if (argc < 3) {
      std::fprintf(stderr, "bench_body_integral accuracy FILE: FILE is missing\n");
      return 2;
    }
    accuracy(argv[2]);
  }
  if (what == "plate") {
    Scene sc = load_scene(SOFTHD_SOURCE_DIR "/data/scenes/bending.json");
    fe::Mesh mesh = sc.body.make_mesh();
    TriangleSurface surf = fe::boundary_surface(mesh, Eigen::VectorXd::Zero(mesh.num_nodes() * 3));
    Eigen::MatrixXd X(mesh.nodes.rows() / 5, 3);
    for (int i = 0; i < X.rows(); ++i) X.row(i) = mesh.nodes.row(5 * i);
    Eigen::VectorXd Jref;
    {
      BodyIntegralOptions o;
      o.near_ratio = 24;
      o.angle_points = 20;
      o.threads = 1;
      BodyIntegral(surf, o).evaluate(X, &Jref);
    }
    for (int rep = 0; rep < 3; ++rep)
      for (double ratio : {3.0, 4.0, 6.0, 8.0})
        for (int ap : {12}) {
          BodyIntegralOptions o;
          o.near_ratio = ratio;
          o.angle_points = ap;
          o.threads = 1;
          BodyIntegral b(surf, o);
          Eigen::VectorXd J;
          double t0 = now();
          b.evaluate(X, &J);
          double t1 = now();
          std::printf(
              "plate, %ld of the nodes: near_ratio %4.1f angle_points %2d: %.3f s (%.0f evals/s), "
              "max rel err vs (24, 20) %.2e\n",
              (long)X.rows(), ratio, ap, t1 - t0, X.rows() / (t1 - t0),
              ((J - Jref).array() / Jref.array()).abs().maxCoeff());
        }
  }
  if (what == "cells")
    cells(argc > 2 ? std::atoi(argv[2]) : 1, argc > 3 ? std::atoi(argv[3]) : 1,
          argc > 4 ? argv[4] : nullptr, argc > 5 ? std::atof(argv[5]) : 1e-2);
  if (what == "cost") {
    const int threads = argc > 2 ? std::atoi(argv[2]) : 1;
    cost(SOFTHD_SOURCE_DIR "/data/scenes/bending.json", threads);
  }
}
