// The triangle surface's hierarchy (lib/src/common/surface_bvh.hpp, docs/formulation.md §2.8):
// closest points and radius queries against all triangles tried one by one (a closest-point
// routine written here, independently of the library's region test), the signed distance
// against the unit cube's and an L-shaped prism's analytic values and an icosphere's
// faceting bound, its derivatives against central differences (observed order printed),
// queries from a ball's candidates against the full search (bit for bit), and determinism over
// threads.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "common/surface_bvh.hpp"
#include "expect_error.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/boundary.hpp"
#include "softhd/fe/mesh.hpp"

using softhd::TriangleSurface;
using softhd::detail::Feature;
using softhd::detail::SignedDistance;
using softhd::detail::SurfaceDistance;

namespace {

// ---------------------------------------------------------------------------------------------
// Surfaces

// The boundary of the box [lo, hi] meshed by `cells` hexahedra per side (the FE's own surface:
// each square face cut by a diagonal).
TriangleSurface box_surface(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int cells) {
  const softhd::fe::Mesh m = softhd::fe::make_box_mesh(lo, hi, Eigen::Vector3i::Constant(cells), 1);
  return softhd::fe::boundary_surface(m, Eigen::VectorXd::Zero(m.num_nodes() * 3));
}

// The boundary of a union of unit voxels (integer corners): every voxel face without a
// neighbour, outward, cut into two triangles.
TriangleSurface voxel_surface(const std::vector<Eigen::Vector3i>& voxels) {
  auto occupied = [&](const Eigen::Vector3i& v) {
    return std::find(voxels.begin(), voxels.end(), v) != voxels.end();
  };
  std::map<std::array<int, 3>, int> id;
  std::vector<Eigen::Vector3d> pts;
  auto point = [&](const Eigen::Vector3i& p) {
    const std::array<int, 3> key = {p[0], p[1], p[2]};
    auto it = id.find(key);
    if (it != id.end()) return it->second;
    pts.push_back(p.cast<double>());
    return id[key] = static_cast<int>(pts.size()) - 1;
  };
  std::vector<Eigen::Vector3i> tri;
  for (const Eigen::Vector3i& v : voxels)
    for (int a = 0; a < 3; ++a)
      for (int s : {-1, 1}) {
        if (occupied(v + s * Eigen::Vector3i::Unit(a))) continue;
        const Eigen::Vector3i eu = Eigen::Vector3i::Unit((a + 1) % 3),
                              ev = Eigen::Vector3i::Unit((a + 2) % 3);
        const Eigen::Vector3i base =
            v + (s > 0 ? Eigen::Vector3i::Unit(a).eval() : Eigen::Vector3i::Zero().eval());
        // (e_u, e_v) turn about e_a: counter-clockwise seen from +e_a.
        std::array<int, 4> q = {point(base), point(base + eu), point(base + eu + ev),
                                point(base + ev)};
        if (s < 0) std::swap(q[1], q[3]);
        tri.emplace_back(q[0], q[1], q[2]);
        tri.emplace_back(q[0], q[2], q[3]);
      }
  TriangleSurface s;
  s.points.resize(static_cast<Eigen::Index>(pts.size()), 3);
  for (size_t i = 0; i < pts.size(); ++i) s.points.row(static_cast<Eigen::Index>(i)) = pts[i];
  s.triangles.resize(static_cast<Eigen::Index>(tri.size()), 3);
  for (size_t t = 0; t < tri.size(); ++t) s.triangles.row(static_cast<Eigen::Index>(t)) = tri[t];
  return s;
}

// The L-shaped prism [0,2]×[0,1]×[0,1] ∪ [0,1]×[0,2]×[0,1]: its re-entrant edge is x = y = 1.
const std::vector<Eigen::Vector3i> kL = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};

// The unit icosphere: the icosahedron, each triangle split in four `levels` times, every
// vertex projected onto the sphere |x| = 1; outward.
TriangleSurface icosphere(int levels) {
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> p = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0},
                                    {0, -1, g}, {0, 1, g}, {0, -1, -g}, {0, 1, -g},
                                    {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  std::vector<std::array<int, 3>> t = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                       {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (Eigen::Vector3d& x : p) x.normalize();
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const std::pair<int, int> key(std::min(a, b), std::max(a, b));
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      p.push_back((p[a] + p[b]).normalized());
      return mid[key] = static_cast<int>(p.size()) - 1;
    };
    std::vector<std::array<int, 3>> next;
    for (const std::array<int, 3>& f : t) {
      const int ab = midpoint(f[0], f[1]), bc = midpoint(f[1], f[2]), ca = midpoint(f[2], f[0]);
      next.push_back({f[0], ab, ca});
      next.push_back({f[1], bc, ab});
      next.push_back({f[2], ca, bc});
      next.push_back({ab, bc, ca});
    }
    t = next;
  }
  TriangleSurface s;
  s.points.resize(static_cast<Eigen::Index>(p.size()), 3);
  for (size_t i = 0; i < p.size(); ++i) s.points.row(static_cast<Eigen::Index>(i)) = p[i];
  s.triangles.resize(static_cast<Eigen::Index>(t.size()), 3);
  for (size_t i = 0; i < t.size(); ++i)
    s.triangles.row(static_cast<Eigen::Index>(i)) << t[i][0], t[i][1], t[i][2];
  return s;
}

Eigen::Vector3d vertex(const TriangleSurface& s, Eigen::Index t, int k) {
  return s.points.row(s.triangles(t, k)).transpose();
}

// Six times the enclosed volume, Σ a·(b × c): positive for an outward surface.
double six_volume(const TriangleSurface& s) {
  double v = 0.0;
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t)
    v += vertex(s, t, 0).dot(vertex(s, t, 1).cross(vertex(s, t, 2)));
  return v;
}

// ---------------------------------------------------------------------------------------------
// The reference: closest points by projection (not the library's region test)

// The closest point of the segment [p, q] to y: p + t (q − p), t = clamp((y − p)·(q − p)/|q − p|²).
Eigen::Vector3d ref_on_segment(const Eigen::Vector3d& y, const Eigen::Vector3d& p,
                               const Eigen::Vector3d& q) {
  const double t = std::clamp((y - p).dot(q - p) / (q - p).squaredNorm(), 0.0, 1.0);
  return p + t * (q - p);
}

// The closest point of the triangle (a, b, c) to y: the foot of y on its plane if the foot's
// barycentric coordinates (signed sub-areas) are all ≥ 0, else the nearest of the three
// edges' closest points.
Eigen::Vector3d ref_on_triangle(const Eigen::Vector3d& y, const Eigen::Vector3d& a,
                                const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d n = (b - a).cross(c - a);
  const Eigen::Vector3d f = y - n * (n.dot(y - a) / n.squaredNorm());
  const double la = (c - b).cross(f - b).dot(n), lb = (a - c).cross(f - c).dot(n),
               lc = (b - a).cross(f - a).dot(n);
  if (la >= 0.0 && lb >= 0.0 && lc >= 0.0) return f;
  Eigen::Vector3d best = ref_on_segment(y, a, b);
  for (const Eigen::Vector3d& e : {ref_on_segment(y, b, c), ref_on_segment(y, c, a)})
    if ((y - e).squaredNorm() < (y - best).squaredNorm()) best = e;
  return best;
}

// The unsigned distance from y to triangle t of s.
double ref_distance(const TriangleSurface& s, Eigen::Index t, const Eigen::Vector3d& y) {
  return (y - ref_on_triangle(y, vertex(s, t, 0), vertex(s, t, 1), vertex(s, t, 2))).norm();
}

// The closest point of the surface, all triangles tried.
Eigen::Vector3d ref_closest(const TriangleSurface& s, const Eigen::Vector3d& y) {
  Eigen::Vector3d best = Eigen::Vector3d::Constant(INFINITY);
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t) {
    const Eigen::Vector3d c = ref_on_triangle(y, vertex(s, t, 0), vertex(s, t, 1), vertex(s, t, 2));
    if ((y - c).squaredNorm() < (y - best).squaredNorm()) best = c;
  }
  return best;
}

Eigen::MatrixXd random_points(int n, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                              unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  Eigen::MatrixXd y(n, 3);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) y(i, k) = lo[k] + (hi[k] - lo[k]) * U(rng);
  return y;
}

// The unit cube's signed distance: q = |y − ½| − ½, sd = |max(q, 0)| + min(max_k q_k, 0).
double cube_sd(const Eigen::Vector3d& y) {
  const Eigen::Vector3d q = (y.array() - 0.5).abs() - 0.5;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

// ---------------------------------------------------------------------------------------------
// Closest points and radius queries against all triangles

// Every surface kind: the FE cube, an L prism, an icosphere, all against the reference.
std::vector<TriangleSurface> surfaces() {
  TriangleSurface shifted = icosphere(2);
  shifted.points.col(0).array() += 0.3;
  return {box_surface(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 3), voxel_surface(kL),
          shifted};
}

TEST(SurfaceBvh, ClosestPointEqualsBruteForce) {
  unsigned seed = 1;
  for (const TriangleSurface& s : surfaces()) {
    const SurfaceDistance sd(s);
    const Eigen::Vector3d lo = s.points.colwise().minCoeff(), hi = s.points.colwise().maxCoeff();
    const Eigen::Vector3d pad = 0.5 * (hi - lo);
    const Eigen::MatrixXd y = random_points(1000, lo - pad, hi + pad, seed++);
    const std::vector<SignedDistance> q = sd.at_rows(y);
    for (Eigen::Index i = 0; i < y.rows(); ++i) {
      const Eigen::Vector3d yi = y.row(i).transpose(), c = ref_closest(s, yi);
      const softhd::detail::SurfacePoint& p = q[static_cast<size_t>(i)].closest;
      // The same distance to rounding (|y − c| ≤ 3 in these boxes); the same point, the
      // closest point being unique at random y (ties lie on a set of measure zero).
      ASSERT_NEAR(std::sqrt(p.distance2), (yi - c).norm(), 1e-13) << "query " << i;
      ASSERT_LT((p.point - c).norm(), 1e-9) << "query " << i;
      // λ reproduces the point and fits the feature.
      const Eigen::Vector3d x = p.where.lambda[0] * vertex(s, p.triangle, 0) +
                                p.where.lambda[1] * vertex(s, p.triangle, 1) +
                                p.where.lambda[2] * vertex(s, p.triangle, 2);
      ASSERT_LT((x - p.point).norm(), 1e-15 * 8);
      const int zeros = static_cast<int>((p.where.lambda.array() == 0.0).count());
      ASSERT_EQ(zeros, static_cast<int>(p.where.feature)) << "query " << i;
      ASSERT_NEAR(p.where.lambda.sum(), 1.0, 1e-15 * 4);
    }
  }
}

TEST(SurfaceBvh, RadiusQueryEqualsBruteForce) {
  unsigned seed = 11;
  for (const TriangleSurface& s : surfaces()) {
    const SurfaceDistance sd(s);
    const Eigen::Vector3d lo = s.points.colwise().minCoeff(), hi = s.points.colwise().maxCoeff();
    const Eigen::MatrixXd y = random_points(200, lo.array() - 0.3, hi.array() + 0.3, seed++);
    for (double r : {0.0, 0.05, 0.2, 0.6}) {
      std::vector<int> start, tri;
      sd.within_rows(y, r, &start, &tri);
      for (Eigen::Index i = 0; i < y.rows(); ++i) {
        const std::vector<int> got(tri.begin() + start[i], tri.begin() + start[i + 1]);
        ASSERT_EQ(got, sd.within(Eigen::Vector3d(y.row(i)), r));
        for (Eigen::Index t = 0; t < s.triangles.rows(); ++t) {
          const double d = ref_distance(s, t, y.row(i).transpose());
          if (std::abs(d - r) < 1e-12) continue;  // on the sphere |d − r| = 0: either answer
          ASSERT_EQ(d <= r, std::binary_search(got.begin(), got.end(), static_cast<int>(t)))
              << "query " << i << ", triangle " << t << ", d " << d << ", r " << r;
        }
      }
    }
  }
}

// The same query, bit for bit: triangle, barycentric λ, feature, point, d², sd and ∂sd/∂y.
void expect_same(const SignedDistance& a, const SignedDistance& b, const std::string& where) {
  ASSERT_EQ(a.closest.triangle, b.closest.triangle) << where;
  ASSERT_EQ(a.closest.where.feature, b.closest.where.feature) << where;
  ASSERT_EQ(a.closest.where.corner, b.closest.where.corner) << where;
  ASSERT_TRUE((a.closest.where.lambda.array() == b.closest.where.lambda.array()).all()) << where;
  ASSERT_TRUE((a.closest.point.array() == b.closest.point.array()).all()) << where;
  ASSERT_EQ(a.closest.distance2, b.closest.distance2) << where;
  ASSERT_EQ(a.sd, b.sd) << where;
  ASSERT_TRUE((a.gradient.array() == b.gradient.array()).all()) << where;
}

// The points of segments (the outer rule's lines) from their candidates (the ball about the
// middle of radius max(|sd|) at the ends + length, as cell_rule::line_candidates builds it; a
// ball too small; a ball elsewhere) against the full search, bit for bit, and against all
// triangles. The FE cube's segments run along the grid through its vertices and edges, where
// several triangles tie.
TEST(SurfaceBvh, CandidateQueriesEqualTheFullSearch) {
  std::mt19937 rng(71);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  for (const TriangleSurface& s : surfaces()) {
    const SurfaceDistance sd(s);
    const Eigen::Vector3d lo = s.points.colwise().minCoeff(), hi = s.points.colwise().maxCoeff();
    for (int line = 0; line < 120; ++line) {
      Eigen::Vector3d a, b;
      if (line % 3 == 0) {  // along a grid axis through grid coordinates (k/6 of the box)
        const int axis = line % 9 / 3;
        for (int k = 0; k < 3; ++k) a[k] = lo[k] + (hi[k] - lo[k]) * std::floor(7 * U(rng)) / 6;
        b = a;
        a[axis] = lo[axis] - 0.1, b[axis] = hi[axis] + 0.1;
      } else {
        for (int k = 0; k < 3; ++k) a[k] = lo[k] - 0.2 + (hi[k] - lo[k] + 0.4) * U(rng);
        b = a + 0.3 * Eigen::Vector3d(U(rng) - 0.5, U(rng) - 0.5, U(rng) - 0.5);
      }
      const double s0 = sd.at(a).sd, s1 = sd.at(b).sd, length = (b - a).norm();
      const Eigen::Vector3d m = 0.5 * (a + b);
      const SurfaceDistance::Candidates balls[3] = {
          sd.candidates(m, std::max(std::abs(s0), std::abs(s1)) + length),
          sd.candidates(m, 0.1 * length), sd.candidates(m + Eigen::Vector3d(3, 0, 0), 0.5)};
      for (int k = 0; k <= 24; ++k) {
        const Eigen::Vector3d y = a + (b - a) * (k / 24.0);
        const SignedDistance full = sd.at(y);
        for (int c = 0; c < 3; ++c)
          expect_same(sd.at(y, balls[c]), full,
                      "line " + std::to_string(line) + ", point " + std::to_string(k) + ", ball " +
                          std::to_string(c));
        ASSERT_NEAR(std::abs(full.sd), (y - ref_closest(s, y)).norm(), 1e-13);
      }
    }
  }
  const SurfaceDistance cube(box_surface(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 1));
  softhd::test::expect_error<softhd::InvalidArgument>(
      [&] { cube.candidates(Eigen::Vector3d::Zero(), -1.0); }, "radius must be");
  softhd::test::expect_error<softhd::InvalidArgument>(
      [&] { cube.at(Eigen::Vector3d(NAN, 0, 0), cube.candidates(Eigen::Vector3d::Zero(), 1.0)); },
      "y is not finite");
}

// ---------------------------------------------------------------------------------------------
// The signed distance against analytic values

TEST(SurfaceBvh, CubeSignedDistanceIsAnalytic) {
  const SurfaceDistance sd(box_surface(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 2));
  std::vector<Eigen::Vector3d> y;
  const Eigen::MatrixXd r =
      random_points(2000, Eigen::Vector3d::Constant(-0.7), Eigen::Vector3d::Constant(1.7), 21);
  for (Eigen::Index i = 0; i < r.rows(); ++i) y.push_back(r.row(i).transpose());
  // Near every edge and corner, inside and outside, at offsets from 0.1 down to 1e-9.
  std::mt19937 rng(22);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::normal_distribution<double> G(0.0, 1.0);
  for (double off : {0.1, 1e-3, 1e-6, 1e-9})
    for (int i = 0; i < 200; ++i) {
      Eigen::Vector3d p;
      for (int k = 0; k < 3; ++k) p[k] = U(rng) < 0.5 ? 0.0 : 1.0;  // a corner
      const int along = static_cast<int>(3 * U(rng));               // an edge through it, or none
      if (i % 2 == 0) p[along] = U(rng);
      const Eigen::Vector3d d(G(rng), G(rng), G(rng));
      y.push_back(p + off * d.normalized());
    }
  for (const Eigen::Vector3d& yi : y) {
    const SignedDistance q = sd.at(yi);
    // Exact geometry (the cube's corners are representable): rounding only.
    ASSERT_NEAR(q.sd, cube_sd(yi), 4e-16 * 8) << yi.transpose();
  }
}

TEST(SurfaceBvh, LPrismSignFollowsMembership) {
  const SurfaceDistance sd(voxel_surface(kL));
  const Eigen::MatrixXd y =
      random_points(4000, Eigen::Vector3d(-0.5, -0.5, -0.5), Eigen::Vector3d(2.5, 2.5, 1.5), 31);
  int inside = 0, notch = 0;
  for (Eigen::Index i = 0; i < y.rows(); ++i) {
    const Eigen::Vector3d yi = y.row(i).transpose();
    const bool in_z = yi[2] > 0 && yi[2] < 1;
    const bool in =
        in_z && yi[0] > 0 && yi[1] > 0 && ((yi[0] < 2 && yi[1] < 1) || (yi[0] < 1 && yi[1] < 2));
    const double s = sd.at(yi).sd;
    ASSERT_EQ(s < 0.0, in) << yi.transpose() << " sd " << s;
    // Outside, the distance to a union is the least distance to its voxels.
    if (!in) {
      double d = INFINITY;
      for (const Eigen::Vector3i& v : kL) d = std::min(d, cube_sd(yi - v.cast<double>()));
      ASSERT_NEAR(s, d, 1e-15 * 8) << yi.transpose();
    }
    inside += in;
    notch += !in && in_z && yi[0] > 1 && yi[1] > 1 && yi[0] < 2 && yi[1] < 2;
  }
  EXPECT_GT(inside, 400);  // both sides and the notch sampled
  EXPECT_GT(notch, 200);
}

// A sharp tetrahedron (dihedral angles down to a few degrees at its spike, vertex 3) whose
// edge 0–1 is cut into m pieces: its two faces become fans of m triangles, so the spike's
// vertex has m triangles on one face and one on each other. Outside an edge or vertex there,
// y − c can make an obtuse angle with an incident face's normal (the sign needs the feature's
// pseudo-normal) and with a plain mean of the incident triangles' normals (it needs the
// angle weights).
TriangleSurface sharp_tetrahedron(int m) {
  const Eigen::Vector3d v[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.2, 0.25, 6}};
  TriangleSurface s;
  s.points.resize(m + 3, 3);  // p_0 = v0, ..., p_m = v1, then v2 (m + 1), v3 (m + 2)
  for (int i = 0; i <= m; ++i) s.points.row(i) = (v[0] + (v[1] - v[0]) * i / m).transpose();
  s.points.row(m + 1) = v[2].transpose();
  s.points.row(m + 2) = v[3].transpose();
  s.triangles.resize(2 * m + 2, 3);
  for (int i = 0; i < m; ++i) {
    s.triangles.row(2 * i) << i, m + 1, i + 1;      // the face (0, 2, 1)
    s.triangles.row(2 * i + 1) << i, i + 1, m + 2;  // the face (0, 1, 3)
  }
  s.triangles.row(2 * m) << m, m + 1, m + 2;      // (1, 2, 3)
  s.triangles.row(2 * m + 1) << m + 1, 0, m + 2;  // (2, 0, 3)
  return s;
}

// Convex: inside, sd = max over the four faces of n·(y − a); the sign is membership (every
// n·(y − a) < 0); outside, |sd| is the distance to all triangles.
TEST(SurfaceBvh, SharpTetrahedronSignAndDistance) {
  for (int m : {1, 12}) {
    const TriangleSurface s = sharp_tetrahedron(m);
    ASSERT_GT(six_volume(s), 0.0);
    const SurfaceDistance sd(s);
    const Eigen::MatrixXd y =
        random_points(3000, Eigen::Vector3d(-0.5, -0.5, -0.5), Eigen::Vector3d(1.5, 1.5, 6.8), 71);
    const Eigen::Index faces[4] = {0, 1, 2 * m, 2 * m + 1};  // a triangle of each face
    int inside = 0;
    for (Eigen::Index i = 0; i < y.rows(); ++i) {
      const Eigen::Vector3d yi = y.row(i).transpose();
      double plane = -INFINITY;
      for (Eigen::Index t : faces) {
        const Eigen::Vector3d n = (vertex(s, t, 1) - vertex(s, t, 0))
                                      .cross(vertex(s, t, 2) - vertex(s, t, 0))
                                      .normalized();
        plane = std::max(plane, n.dot(yi - vertex(s, t, 0)));
      }
      const double got = sd.at(yi).sd;
      ASSERT_EQ(got < 0.0, plane < 0.0) << "m " << m << ", y " << yi.transpose() << ", sd " << got;
      ASSERT_NEAR(got, plane < 0.0 ? plane : (yi - ref_closest(s, yi)).norm(), 1e-14)
          << "m " << m << ", y " << yi.transpose();
      inside += plane < 0.0;
    }
    EXPECT_GT(inside, 20);
  }
}

// An inscribed polyhedron P of the sphere |x| = R (vertices on it) holds the ball of radius
// r_in = min over faces of n·a (P is convex and holds the centre), so B(r_in) ⊂ P ⊂ B(R); the
// signed distance falls as the set grows, so |y| − R ≤ sd_P(y) ≤ |y| − r_in.
TEST(SurfaceBvh, IcosphereWithinItsFacetingBound) {
  const TriangleSurface s = icosphere(3);
  ASSERT_GT(six_volume(s), 0.0);
  double r_in = INFINITY;
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t) {
    const Eigen::Vector3d n =
        (vertex(s, t, 1) - vertex(s, t, 0)).cross(vertex(s, t, 2) - vertex(s, t, 0)).normalized();
    r_in = std::min(r_in, n.dot(vertex(s, t, 0)));
  }
  std::printf("icosphere, %d triangles: faceting bound 1 − r_in = %.3e\n",
              static_cast<int>(s.triangles.rows()), 1.0 - r_in);
  const SurfaceDistance sd(s);
  const Eigen::MatrixXd y =
      random_points(3000, Eigen::Vector3d::Constant(-1.8), Eigen::Vector3d::Constant(1.8), 41);
  double lo = INFINITY, hi = -INFINITY;
  for (Eigen::Index i = 0; i < y.rows(); ++i) {
    const double r = y.row(i).norm(), e = sd.at(Eigen::Vector3d(y.row(i))).sd - (r - 1.0);
    lo = std::min(lo, e);
    hi = std::max(hi, e);
    ASSERT_GE(e, -1e-15 * 8) << "at |y| = " << r;
    ASSERT_LE(e, 1.0 - r_in + 1e-15 * 8) << "at |y| = " << r;
  }
  std::printf("sd − (|y| − 1) in [%.3e, %.3e]\n", lo, hi);
}

// ---------------------------------------------------------------------------------------------
// Derivatives against central differences

// Central differences (f(h) − f(−h))/(2h) against `slope` at h = 1e-2 / 2^i: the errors and
// observed orders printed; the order must be 2 (1.8–2.2) while the error is above 1e-10, and
// an error below it from the first step means f is linear there (a face): exact slope.
void expect_second_order(const std::string& what, const std::function<double(double)>& f,
                         double slope) {
  std::vector<double> e;
  for (int i = 0; i < 5; ++i) {
    const double h = 1e-2 / std::pow(2.0, i);
    e.push_back(std::abs((f(h) - f(-h)) / (2 * h) - slope));
  }
  std::printf("%-34s errors", what.c_str());
  for (double v : e) std::printf(" %.2e", v);
  std::printf("  orders");
  for (size_t i = 1; i < e.size(); ++i) std::printf(" %.2f", std::log2(e[i - 1] / e[i]));
  std::printf("\n");
  const double floor = 1e-10;
  if (e[0] < floor) {
    for (double v : e) EXPECT_LT(v, floor) << what;
    return;
  }
  for (size_t i = 1; i < e.size() && e[i] > floor; ++i) {
    const double order = std::log2(e[i - 1] / e[i]);
    EXPECT_GT(order, 1.8) << what << " step " << i;
    EXPECT_LT(order, 2.2) << what << " step " << i;
  }
}

struct Probe {
  std::string name;
  TriangleSurface surface;
  Eigen::Vector3d y;
  Feature feature;
};

// Points with a unique closest feature, away from the medial axis by ≥ 0.1 (the
// perturbations below stay ≤ 1e-2 · √3).
std::vector<Probe> probes() {
  const TriangleSurface cube = box_surface(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 1);
  const TriangleSurface L = voxel_surface(kL), ball = icosphere(1);
  const Eigen::Vector3d v0 = ball.points.row(0).transpose();
  return {{"cube, face, outside", cube, {0.25, 0.5, 1.2}, Feature::kFace},
          {"cube, face, inside", cube, {0.5, 0.25, 0.85}, Feature::kFace},
          {"cube, edge, outside", cube, {0.4, 1.2, 1.3}, Feature::kEdge},
          {"cube, vertex, outside", cube, {1.2, 1.3, 1.1}, Feature::kVertex},
          {"L, re-entrant edge, inside", L, {0.9, 0.85, 0.45}, Feature::kEdge},
          {"L, face, outside in the notch", L, {1.2, 1.4, 0.75}, Feature::kFace},
          {"icosphere, vertex, outside", ball, 1.3 * v0 + Eigen::Vector3d(0.02, -0.01, 0.03),
           Feature::kVertex}};
}

TEST(SurfaceBvh, GradientInYIsSecondOrder) {
  const Eigen::Vector3d dir = Eigen::Vector3d(0.3, -0.7, 0.5).normalized();
  for (const Probe& p : probes()) {
    const SurfaceDistance sd(p.surface);
    const SignedDistance q = sd.at(p.y);
    ASSERT_EQ(q.closest.where.feature, p.feature) << p.name;
    for (double h : {-1e-2, 1e-2})
      ASSERT_EQ(sd.at(Eigen::Vector3d(p.y + h * dir)).closest.where.feature, p.feature) << p.name;
    expect_second_order(
        "d sd/dy, " + p.name, [&](double h) { return sd.at(Eigen::Vector3d(p.y + h * dir)).sd; },
        q.gradient.dot(dir));
  }
}

TEST(SurfaceBvh, PullbackToSurfacePointsIsSecondOrder) {
  for (const Probe& p : probes()) {
    const Eigen::Index N = p.surface.points.rows();
    std::mt19937 rng(51);
    std::normal_distribution<double> G(0.0, 1.0);
    Eigen::MatrixXd dx(N, 3);
    for (Eigen::Index i = 0; i < dx.size(); ++i) dx.data()[i] = G(rng);
    dx /= dx.rowwise().norm().maxCoeff();  // every point moves ≤ h
    const double w = 1.7;
    auto value = [&](double h) {
      TriangleSurface s = p.surface;
      s.points += h * dx;
      const SignedDistance q = SurfaceDistance(s).at(p.y);
      EXPECT_EQ(q.closest.where.feature, p.feature) << p.name << " at h " << h;
      return w * q.sd;
    };
    const SurfaceDistance sd(p.surface);
    const Eigen::MatrixXd g = sd.pullback({sd.at(p.y)}, Eigen::VectorXd::Constant(1, w));
    expect_second_order("d sd/dx, " + p.name, value, (g.array() * dx.array()).sum());
  }
}

// ---------------------------------------------------------------------------------------------
// Determinism and misuse

TEST(SurfaceBvh, ResultsDoNotDependOnRunsOrThreads) {
  const SurfaceDistance sd(icosphere(3));
  const Eigen::MatrixXd y =
      random_points(3000, Eigen::Vector3d::Constant(-1.5), Eigen::Vector3d::Constant(1.5), 61);
  const Eigen::VectorXd w = Eigen::VectorXd::LinSpaced(y.rows(), -1.0, 2.0);
  auto run = [&](int threads, Eigen::VectorXd* v, Eigen::MatrixXd* g, std::vector<int>* start,
                 std::vector<int>* tri) {
    const std::vector<SignedDistance> q = sd.at_rows(y, threads);
    v->resize(y.rows());
    for (size_t k = 0; k < q.size(); ++k) (*v)[static_cast<Eigen::Index>(k)] = q[k].sd;
    *g = sd.pullback(q, w);
    sd.within_rows(y, 0.1, start, tri, threads);
  };
  Eigen::VectorXd v1, v1b, v2;
  Eigen::MatrixXd g1, g1b, g2;
  std::vector<int> s1, s1b, s2, t1, t1b, t2;
  run(1, &v1, &g1, &s1, &t1);
  run(1, &v1b, &g1b, &s1b, &t1b);
  run(2, &v2, &g2, &s2, &t2);
  EXPECT_TRUE((v1.array() == v1b.array()).all() && (v1.array() == v2.array()).all());
  EXPECT_TRUE((g1.array() == g1b.array()).all() && (g1.array() == g2.array()).all());
  EXPECT_TRUE(s1 == s1b && s1 == s2 && t1 == t1b && t1 == t2);
  EXPECT_GT(t1.size(), 0u);
}

TEST(SurfaceBvh, RejectsSurfacesThatAreNotClosedOrOriented) {
  using softhd::InvalidArgument;
  using softhd::test::expect_error;
  const TriangleSurface cube = box_surface(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 1);
  TriangleSurface open = cube;
  open.triangles.conservativeResize(cube.triangles.rows() - 1, 3);
  expect_error<InvalidArgument>([&] { SurfaceDistance{open}; }, "not closed");
  TriangleSurface flipped = cube;
  std::swap(flipped.triangles(0, 1), flipped.triangles(0, 2));
  expect_error<InvalidArgument>([&] { SurfaceDistance{flipped}; }, "not consistently oriented");
  TriangleSurface flat = cube;
  flat.points.row(flat.triangles(0, 2)) = flat.points.row(flat.triangles(0, 1));
  expect_error<InvalidArgument>([&] { SurfaceDistance{flat}; }, "zero area");
  TriangleSurface outside = cube;
  outside.triangles(3, 1) = 99;
  expect_error<InvalidArgument>([&] { SurfaceDistance{outside}; }, "outside 0..7");
  const SurfaceDistance sd(cube);
  expect_error<InvalidArgument>([&] { sd.within(Eigen::Vector3d::Zero(), -1.0); }, "r must be");
  const Eigen::Vector3d nan(0.0, NAN, 0.0);
  expect_error<InvalidArgument>([&] { sd.at(nan); }, "y is not finite");
  expect_error<InvalidArgument>([&] { sd.at_rows(nan.transpose()); }, "a row of y is not finite");
  expect_error<InvalidArgument>([&] { sd.within(nan, 1.0); }, "y is not finite");
  SignedDistance foreign = sd.at(Eigen::Vector3d(0.2, 0.3, 0.4));
  foreign.closest.triangle = 12;
  expect_error<InvalidArgument>([&] { sd.pullback({foreign}, Eigen::VectorXd::Ones(1)); },
                                "query 0 names no triangle");
  expect_error<InvalidArgument>(
      [&] { sd.pullback({sd.at(Eigen::Vector3d(0.2, 0.3, 0.4))}, Eigen::VectorXd::Zero(2)); },
      "w has 2 entries for 1 queries");
}

}  // namespace
