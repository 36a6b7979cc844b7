// Visibility of a surface's points from a camera (scan/visibility.hpp, docs/formulation.md §8.7):
// a cube seen along its axes, a box hiding part of another (the hidden set derived by hand),
// and the hierarchy's answer against all triangles tried one by one on random closed surfaces.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>
#include <random>

#include "softhd/error.hpp"
#include "softhd/fe/boundary.hpp"
#include "softhd/parallel.hpp"
#include "softhd/scan/visibility.hpp"

using softhd::TriangleSurface;
using softhd::scan::visible_points;
using Mask = Eigen::Array<bool, Eigen::Dynamic, 1>;

namespace {

TriangleSurface box_surface(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int cells) {
  const softhd::fe::Mesh m = softhd::fe::make_box_mesh(lo, hi, Eigen::Vector3i::Constant(cells), 1);
  return softhd::fe::boundary_surface(m, Eigen::VectorXd::Zero(m.num_nodes() * 3));
}

TriangleSurface join(const TriangleSurface& a, const TriangleSurface& b) {
  TriangleSurface s;
  s.points.resize(a.points.rows() + b.points.rows(), 3);
  s.points << a.points, b.points;
  s.triangles.resize(a.triangles.rows() + b.triangles.rows(), 3);
  s.triangles << a.triangles, (b.triangles.array() + static_cast<int>(a.points.rows())).matrix();
  return s;
}

// A star-shaped closed surface: a latitude-longitude sphere around `centre` whose radius
// varies randomly from vertex to vertex (bumps hide parts of their neighbours), outward.
TriangleSurface bumpy_sphere(const Eigen::Vector3d& centre, int rings, int sectors, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0.7, 1.3);
  TriangleSurface s;
  const int N = 2 + (rings - 1) * sectors;
  s.points.resize(N, 3);
  s.points.row(0) = (centre + U(rng) * Eigen::Vector3d::UnitZ()).transpose();
  s.points.row(1) = (centre - U(rng) * Eigen::Vector3d::UnitZ()).transpose();
  auto id = [&](int r, int k) { return 2 + (r - 1) * sectors + (k % sectors); };
  for (int r = 1; r < rings; ++r)
    for (int k = 0; k < sectors; ++k) {
      const double th = M_PI * r / rings, ph = 2 * M_PI * k / sectors;
      const Eigen::Vector3d d(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph),
                              std::cos(th));
      s.points.row(id(r, k)) = (centre + U(rng) * d).transpose();
    }
  std::vector<Eigen::Vector3i> t;
  for (int k = 0; k < sectors; ++k) {
    t.emplace_back(0, id(1, k), id(1, k + 1));
    t.emplace_back(1, id(rings - 1, k + 1), id(rings - 1, k));
    for (int r = 1; r + 1 < rings; ++r) {
      t.emplace_back(id(r, k), id(r + 1, k), id(r + 1, k + 1));
      t.emplace_back(id(r, k), id(r + 1, k + 1), id(r, k + 1));
    }
  }
  s.triangles.resize(static_cast<Eigen::Index>(t.size()), 3);
  for (size_t i = 0; i < t.size(); ++i) s.triangles.row(static_cast<Eigen::Index>(i)) = t[i];
  return s;
}

// The rule of visible_points with every triangle tried: facing (an incident triangle with
// n·(camera − x) > 0), and no non-incident triangle met by camera + t (x − camera) for
// t in [0, 1 − slack/|x − camera|], the meeting solved as a 3 by 3 system (LU).
// `occluded` counts the points that face the camera but are hidden.
Mask brute_force(const TriangleSurface& s, const Eigen::Vector3d& camera, double tolerance,
                 int* occluded) {
  *occluded = 0;
  const double slack =
      tolerance * (s.points.colwise().maxCoeff() - s.points.colwise().minCoeff()).norm();
  Mask seen(s.points.rows());
  for (Eigen::Index i = 0; i < s.points.rows(); ++i) {
    const Eigen::Vector3d x = s.points.row(i).transpose(), d = x - camera;
    bool facing = false, hidden = false;
    for (Eigen::Index t = 0; t < s.triangles.rows(); ++t) {
      const Eigen::Vector3d a = s.points.row(s.triangles(t, 0)),
                            b = s.points.row(s.triangles(t, 1)),
                            c = s.points.row(s.triangles(t, 2));
      if ((s.triangles.row(t).array() == i).any()) {
        facing = facing || (b - a).cross(c - a).dot(camera - x) > 0.0;
        continue;
      }
      Eigen::Matrix3d M;  // camera + t d = a + v (b − a) + w (c − a)
      M << d, a - b, a - c;
      const Eigen::Vector3d tvw = M.partialPivLu().solve(a - camera);
      const double t_max = 1.0 - slack / d.norm();
      hidden = hidden || (tvw[1] >= 0 && tvw[2] >= 0 && tvw[1] + tvw[2] <= 1 && tvw[0] >= 0 &&
                          tvw[0] <= t_max);
    }
    seen[i] = facing && !hidden;
    *occluded += facing && hidden;
  }
  return seen;
}

}  // namespace

// A cube seen along each axis from outside sees exactly the points of the face towards the
// camera, its edges and corners included (they belong to a facing triangle and the segment
// to them runs outside the cube); the side faces are edge-on or turned away.
TEST(Visibility, CubeSeesItsFacingFace) {
  const TriangleSurface s = box_surface(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 4);
  for (int axis = 0; axis < 3; ++axis)
    for (double side : {-1.0, 1.0}) {
      Eigen::Vector3d camera = Eigen::Vector3d::Constant(0.5);
      camera[axis] += side * 5.0;
      const Mask seen = visible_points(s, camera);
      const double face = side > 0 ? 1.0 : 0.0;
      for (Eigen::Index i = 0; i < s.points.rows(); ++i)
        EXPECT_EQ(seen[i], s.points(i, axis) == face) << "axis " << axis << " point " << i;
    }
}

// A small box B = [0.28, 0.72]² × [2, 2.5] floats above the cube A = [0, 1]³, camera at
// (0.5, 0.5, 10). The segment to a point of A's top (z = 1) meets B iff its offset from the
// axis, scaled by (10 − z)/9 ≥ 7.5/9 over B's height, falls inside B's half-width 0.22: a top
// point is hidden iff max(|x − ½|, |y − ½|) < 0.22 · 9/7.5 = 0.264 (grid offsets 0, 0.1, 0.2
// hidden; 0.3, 0.4, 0.5 seen). B shows its top only.
TEST(Visibility, ABoxHidesPartOfAnother) {
  const TriangleSurface a = box_surface(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 10);
  const TriangleSurface b = box_surface({0.28, 0.28, 2.0}, {0.72, 0.72, 2.5}, 2);
  const TriangleSurface s = join(a, b);
  const Eigen::Vector3d camera(0.5, 0.5, 10.0);
  const Mask seen = visible_points(s, camera);
  int hidden_top = 0;
  for (Eigen::Index i = 0; i < s.points.rows(); ++i) {
    const Eigen::Vector3d x = s.points.row(i);
    bool expect;
    if (i < a.points.rows()) {
      const double offset = std::max(std::abs(x[0] - 0.5), std::abs(x[1] - 0.5));
      expect = x[2] == 1.0 && offset > 0.264;
      hidden_top += x[2] == 1.0 && !expect;
    } else {
      expect = x[2] == 2.5;
    }
    EXPECT_EQ(seen[i], expect) << "point " << i << " at " << x.transpose();
  }
  EXPECT_EQ(hidden_top, 25);  // the 5 × 5 top points at offsets 0, 0.1, 0.2
}

// Random bumpy closed surfaces (two, one partly in front of the other) from random cameras:
// the hierarchy gives the brute-force answer for every point, with a non-trivial split and
// points that face the camera but are hidden.
TEST(Visibility, MatchesBruteForceOnRandomSurfaces) {
  std::mt19937 rng(11);
  std::normal_distribution<double> G(0.0, 1.0);
  for (unsigned seed = 1; seed <= 4; ++seed) {
    const TriangleSurface s = join(bumpy_sphere(Eigen::Vector3d::Zero(), 12, 20, seed),
                                   bumpy_sphere(Eigen::Vector3d(1.2, 0.9, 0.3), 8, 14, seed + 10));
    const Eigen::Vector3d camera = 5.0 * Eigen::Vector3d(G(rng), G(rng), G(rng)).normalized();
    int occluded = 0;
    const Mask seen = visible_points(s, camera), expect = brute_force(s, camera, 1e-6, &occluded);
    EXPECT_GT(occluded, 5) << "seed " << seed;  // facing but hidden: the cast decides them
    EXPECT_EQ(seen.count(), expect.count()) << "seed " << seed;
    for (Eigen::Index i = 0; i < s.points.rows(); ++i) EXPECT_EQ(seen[i], expect[i]) << i;
    EXPECT_GT(seen.count(), 0);
    EXPECT_LT(seen.count(), s.points.rows() / 2);
    softhd::set_threads(1);  // one thread and two: the same answer (no shared state)
    const Mask one = visible_points(s, camera);
    softhd::set_threads(2);
    EXPECT_TRUE((visible_points(s, camera) == one).all());
    EXPECT_TRUE((one == seen).all());
    softhd::set_threads(0);
  }
}

// Misuse: a triangle outside the points, a camera or point not finite, a bad tolerance.
TEST(Visibility, RefusesBadInput) {
  TriangleSurface s = box_surface(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 1);
  const Eigen::Vector3d camera(0.5, 0.5, 3.0);
  EXPECT_THROW(visible_points(s, camera, -1.0), softhd::InvalidArgument);
  EXPECT_THROW(visible_points(s, Eigen::Vector3d::Constant(NAN)), softhd::InvalidArgument);
  TriangleSurface bad = s;
  bad.triangles(0, 0) = static_cast<int>(s.points.rows());
  EXPECT_THROW(visible_points(bad, camera), softhd::InvalidArgument);
  bad = s;
  bad.points(0, 0) = NAN;
  EXPECT_THROW(visible_points(bad, camera), softhd::InvalidArgument);
}
