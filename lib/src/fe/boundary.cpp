#include "softhd/fe/boundary.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <climits>
#include <numeric>

#include "softhd/error.hpp"

namespace softhd::fe {

namespace {

// One face of the reference cell: its corners (local node ids, for the key that finds the
// face's twin in a neighbour) and its flat sub-triangles (local node ids, outward).
struct FaceTemplate {
  std::vector<int> corners;
  std::vector<std::array<int, 3>> triangles;
};

// The local node at reference coordinates xi (every face node is a node of the cell).
int node_at(const ReferenceElement& r, const Eigen::Vector3d& xi) {
  for (int a = 0; a < r.nodes; ++a)
    if ((r.node_coordinates.row(a).transpose() - xi).norm() < 1e-12) return a;
  SOFTHD_ASSERT(false, "boundary: no node of " + to_string(r.type) + " at a face point");
  return -1;
}

// The sub-triangles of a face whose corners c (local ids) run around it: the corner
// triangles and the midside one (triangles), the quarters cut through the centre node
// (quadrilaterals of order 2), or the fan from c0 (order 1).
std::vector<std::array<int, 3>> cut_face(const ReferenceElement& r, const std::vector<int>& c) {
  const int n = static_cast<int>(c.size());
  auto X = [&](int a) { return Eigen::Vector3d(r.node_coordinates.row(a).transpose()); };
  std::vector<std::array<int, 3>> t;
  if (r.order == 1) {
    for (int i = 1; i + 1 < n; ++i) t.push_back({c[0], c[i], c[i + 1]});
    return t;
  }
  std::vector<int> m(n);  // m[i]: the midside node between c[i] and c[i+1]
  for (int i = 0; i < n; ++i) m[i] = node_at(r, 0.5 * (X(c[i]) + X(c[(i + 1) % n])));
  if (n == 3)
    return {{c[0], m[0], m[2]}, {m[0], c[1], m[1]}, {m[2], m[1], c[2]}, {m[0], m[1], m[2]}};
  const int f = node_at(r, 0.25 * (X(c[0]) + X(c[1]) + X(c[2]) + X(c[3])));
  for (int i = 0; i < 4; ++i) {  // quarter (c_i, m_i, f, m_{i−1})
    t.push_back({c[i], m[i], f});
    t.push_back({c[i], f, m[(i + 3) % 4]});
  }
  return t;
}

// The faces of a 3D reference cell, corners ordered so that (ξ1 − ξ0) × (ξ2 − ξ0) points away
// from the cell's centroid (outward: the cells are convex in ξ).
std::vector<FaceTemplate> face_templates(const ReferenceElement& r) {
  std::vector<std::vector<int>> faces;  // corner local ids, cyclic
  const std::vector<int>& v = r.vertex_nodes;
  if (r.simplex) {
    faces = {{v[1], v[2], v[3]}, {v[0], v[2], v[3]}, {v[0], v[1], v[3]}, {v[0], v[1], v[2]}};
  } else {  // corner k has ξ = (±1, ±1, ±1), tensor order: bit d of k is the sign of ξ_d
    for (int d = 0; d < 3; ++d)
      for (int s = 0; s < 2; ++s) {
        const int d1 = (d + 1) % 3, d2 = (d + 2) % 3;
        std::vector<int> f;
        for (int q : {0, 1, 3, 2}) {  // (−,−), (+,−), (+,+), (−,+) in (ξ_d1, ξ_d2)
          const int k = (s << d) | ((q & 1) << d1) | ((q >> 1) << d2);
          f.push_back(v[k]);
        }
        faces.push_back(f);
      }
  }
  const Eigen::Vector3d centre = r.node_coordinates.colwise().mean().transpose();
  std::vector<FaceTemplate> out;
  for (std::vector<int>& f : faces) {
    auto X = [&](int a) { return Eigen::Vector3d(r.node_coordinates.row(a).transpose()); };
    Eigen::Vector3d mid = Eigen::Vector3d::Zero();
    for (int a : f) mid += X(a) / static_cast<double>(f.size());
    const Eigen::Vector3d n = (X(f[1]) - X(f[0])).cross(X(f[2]) - X(f[0]));
    if (n.dot(mid - centre) < 0.0) std::reverse(f.begin(), f.end());
    out.push_back({f, cut_face(r, f)});
  }
  return out;
}

}  // namespace

BoundaryFacets boundary_facets(const Mesh& mesh) {
  if (mesh.dim != 3) throw InvalidArgument("boundary_facets: the body is 2D (3D meshes only)");
  const std::vector<FaceTemplate> faces = face_templates(reference_element(mesh.cell));
  const int F = static_cast<int>(faces.size());
  // Every element face keyed by its sorted global corners (a triangle's padded with INT_MAX);
  // a key met once is a boundary facet.
  using Key = std::array<int, 4>;
  const Eigen::Index E = mesh.num_elements();
  std::vector<Key> keys(static_cast<size_t>(E) * F);
  for (Eigen::Index e = 0; e < E; ++e)
    for (int f = 0; f < F; ++f) {
      Key& k = keys[static_cast<size_t>(e) * F + f];
      k.fill(INT_MAX);
      for (size_t i = 0; i < faces[f].corners.size(); ++i)
        k[i] = mesh.elements(e, faces[f].corners[i]);
      std::sort(k.begin(), k.end());
    }
  // Faces bucketed by their smallest corner (a counting sort), each bucket sorted by key and
  // face index: equal keys become neighbours, in an order that does not depend on threads.
  std::vector<size_t> start(static_cast<size_t>(mesh.num_nodes()) + 1, 0), order(keys.size());
  for (const Key& k : keys) ++start[static_cast<size_t>(k[0]) + 1];
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<size_t> fill(start.begin(), start.end() - 1);
  for (size_t i = 0; i < keys.size(); ++i) order[fill[static_cast<size_t>(keys[i][0])]++] = i;
  for (size_t n = 0; n + 1 < start.size(); ++n)
    std::sort(order.begin() + start[n], order.begin() + start[n + 1],
              [&](size_t a, size_t b) { return keys[a] != keys[b] ? keys[a] < keys[b] : a < b; });
  std::vector<std::array<int, 3>> tri;  // global node ids
  for (size_t i = 0; i < order.size();) {
    size_t j = i + 1;
    while (j < order.size() && keys[order[j]] == keys[order[i]]) ++j;
    if (j == i + 1) {
      const Eigen::Index e = static_cast<Eigen::Index>(order[i] / F);
      for (const std::array<int, 3>& t : faces[order[i] % F].triangles)
        tri.push_back({mesh.elements(e, t[0]), mesh.elements(e, t[1]), mesh.elements(e, t[2])});
    }
    i = j;
  }
  BoundaryFacets b;
  for (const std::array<int, 3>& t : tri) b.nodes.insert(b.nodes.end(), t.begin(), t.end());
  std::sort(b.nodes.begin(), b.nodes.end());
  b.nodes.erase(std::unique(b.nodes.begin(), b.nodes.end()), b.nodes.end());
  std::vector<int> index(mesh.num_nodes(), -1);
  for (size_t k = 0; k < b.nodes.size(); ++k) index[b.nodes[k]] = static_cast<int>(k);
  b.triangles.resize(static_cast<Eigen::Index>(tri.size()), 3);
  for (size_t t = 0; t < tri.size(); ++t)
    for (int c = 0; c < 3; ++c) b.triangles(static_cast<Eigen::Index>(t), c) = index[tri[t][c]];
  return b;
}

TriangleSurface boundary_surface(const Mesh& mesh, const BoundaryFacets& facets,
                                 const Eigen::VectorXd& u) {
  if (mesh.dim != 3) throw InvalidArgument("boundary_surface: the body is 2D (3D meshes only)");
  if (u.size() != mesh.num_nodes() * 3)
    throw InvalidArgument("boundary_surface: u has " + std::to_string(u.size()) +
                          " entries, expected 3 per node");
  TriangleSurface s;
  s.points.resize(static_cast<Eigen::Index>(facets.nodes.size()), 3);
  for (size_t k = 0; k < facets.nodes.size(); ++k) {
    const int n = facets.nodes[k];
    s.points.row(static_cast<Eigen::Index>(k)) =
        mesh.nodes.row(n) + u.segment<3>(3 * n).transpose();
  }
  s.triangles = facets.triangles;
  return s;
}

TriangleSurface boundary_surface(const Mesh& mesh, const Eigen::VectorXd& u) {
  return boundary_surface(mesh, boundary_facets(mesh), u);
}

Eigen::VectorXd lumped_areas(const TriangleSurface& s) {
  Eigen::VectorXd V = Eigen::VectorXd::Zero(s.points.rows());
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t) {
    const Eigen::Vector3d a = s.points.row(s.triangles(t, 0)), b = s.points.row(s.triangles(t, 1)),
                          c = s.points.row(s.triangles(t, 2));
    const double third = 0.5 * (b - a).cross(c - a).norm() / 3.0;  // |T|/3
    for (int i = 0; i < 3; ++i) V[s.triangles(t, i)] += third;
  }
  return V;
}

Eigen::MatrixXd lumped_areas_pullback(const TriangleSurface& s, const Eigen::VectorXd& w) {
  if (w.size() != s.points.rows())
    throw InvalidArgument("lumped_areas_pullback: w has the wrong size");
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(s.points.rows(), 3);
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t) {
    const int i[3] = {s.triangles(t, 0), s.triangles(t, 1), s.triangles(t, 2)};
    const Eigen::Vector3d x[3] = {s.points.row(i[0]), s.points.row(i[1]), s.points.row(i[2])};
    const Eigen::Vector3d m = (x[1] - x[0]).cross(x[2] - x[0]);
    const double norm = m.norm();
    if (norm == 0.0) continue;  // a collapsed triangle: |T| is not differentiable there
    const Eigen::Vector3d n = m / norm;
    const double wt = (w[i[0]] + w[i[1]] + w[i[2]]) / 3.0;  // Σ_k w_k ∂V_k/∂|T|
    for (int k = 0; k < 3; ++k)  // ∂|T|/∂x_k = ½ (x_{k+1} − x_{k+2}) × n̂
      g.row(i[k]) += wt * 0.5 * (x[(k + 1) % 3] - x[(k + 2) % 3]).cross(n).transpose();
  }
  return g;
}

}  // namespace softhd::fe
