#include "softhd/fe/dofs.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <numeric>
#include <set>
#include <sstream>

#include "softhd/error.hpp"

namespace softhd::fe {

namespace {

// 1 for every dof (node · dim + component) that a constraint fixes; throws InvalidArgument
// for an unknown face (Mesh::face) or an out-of-range component.
std::vector<char> fixed_dofs(const Mesh& mesh,
                             const std::vector<DirichletConstraint>& constraints) {
  std::vector<char> fixed(static_cast<size_t>(mesh.num_nodes() * mesh.dim), 0);
  for (const DirichletConstraint& c : constraints) {
    const std::vector<int>& nodes = mesh.face(c.face);
    std::vector<int> comps = c.components;
    if (comps.empty())
      for (int k = 0; k < mesh.dim; ++k) comps.push_back(k);
    for (int k : comps) {
      if (k < 0 || k >= mesh.dim) {
        throw InvalidArgument("constraint on face '" + c.face + "': component " +
                              std::to_string(k) + " is not in 0.." + std::to_string(mesh.dim - 1));
      }
      for (int n : nodes) fixed[static_cast<size_t>(n) * mesh.dim + k] = 1;
    }
  }
  return fixed;
}

}  // namespace

Eigen::VectorXd DofMap::expand(const Eigen::VectorXd& free_values) const {
  Eigen::VectorXd full = Eigen::VectorXd::Zero(num_dofs);
  for (Eigen::Index i = 0; i < num_free; ++i) full[free_dofs[i]] = free_values[i];
  return full;
}

Eigen::VectorXd DofMap::restrict(const Eigen::VectorXd& full_values) const {
  Eigen::VectorXd r(num_free);
  for (Eigen::Index i = 0; i < num_free; ++i) r[i] = full_values[free_dofs[i]];
  return r;
}

DofMap make_dof_map(const Mesh& mesh, const std::vector<DirichletConstraint>& constraints) {
  DofMap map;
  map.dim = mesh.dim;
  map.num_dofs = mesh.num_nodes() * mesh.dim;
  const std::vector<char> fixed = fixed_dofs(mesh, constraints);
  map.free_index = Eigen::VectorXi::Constant(map.num_dofs, -1);
  std::vector<int> free;
  for (Eigen::Index d = 0; d < map.num_dofs; ++d) {
    if (!fixed[d]) {
      map.free_index[d] = static_cast<int>(free.size());
      free.push_back(static_cast<int>(d));
    }
  }
  map.num_free = static_cast<Eigen::Index>(free.size());
  map.free_dofs = Eigen::Map<Eigen::VectorXi>(free.data(), map.num_free);
  return map;
}

namespace {

int root(std::vector<int>& parent, int n) {  // union-find, path halving
  while (parent[n] != n) n = parent[n] = parent[parent[n]];
  return n;
}

// The connected part of each node (elements joined by shared nodes), numbered 0..P−1 in the
// order of their first node; returns P.
int connected_parts(const Mesh& mesh, std::vector<int>* part) {
  const int N = static_cast<int>(mesh.num_nodes());
  std::vector<int> parent(N);
  std::iota(parent.begin(), parent.end(), 0);
  for (Eigen::Index e = 0; e < mesh.num_elements(); ++e) {
    const int a = root(parent, mesh.elements(e, 0));
    for (Eigen::Index k = 1; k < mesh.elements.cols(); ++k) {
      const int b = root(parent, mesh.elements(e, k));
      if (b != a) parent[b] = a;
    }
  }
  part->assign(N, -1);
  int P = 0;
  for (int n = 0; n < N; ++n) {
    const int r = root(parent, n);
    if ((*part)[r] < 0) (*part)[r] = P++;
    (*part)[n] = (*part)[r];
  }
  return P;
}

std::string vec(const Eigen::VectorXd& v) {  // "(x, y, z)", 3 significant digits
  std::ostringstream s;
  s.precision(3);
  for (Eigen::Index i = 0; i < v.size(); ++i)
    s << (i ? ", " : "(") << (std::abs(v[i]) < 1e-9 * v.norm() ? 0.0 : v[i]);
  return s.str() + ")";
}

// "region 'a'" or "regions 'a', 'b'" of part p; "a part of ..." near its centre when its
// regions have other parts too.
std::string part_name(const Mesh& mesh, const std::vector<int>& part, int p, int parts,
                      const Eigen::VectorXd& centre) {
  std::set<int> regions;
  for (Eigen::Index e = 0; e < mesh.num_elements(); ++e)
    if (part[mesh.elements(e, 0)] == p)
      regions.insert(mesh.element_region.size() ? mesh.element_region[e] : 0);
  std::string names;
  for (int r : regions)
    names += (names.empty() ? "'" : ", '") + mesh.region_names[static_cast<size_t>(r)] + "'";
  names = (regions.size() > 1 ? "regions " : "region ") + names;
  bool shared = false;  // does another part use these regions?
  for (Eigen::Index e = 0; e < mesh.num_elements() && !shared && parts > 1; ++e)
    shared = part[mesh.elements(e, 0)] != p &&
             regions.count(mesh.element_region.size() ? mesh.element_region[e] : 0);
  return shared ? "the part of " + names + " around " + vec(centre) + " (one of " +
                      std::to_string(parts) + " unconnected parts of the mesh)"
                : names;
}

// The rigid modes at node position r (relative to the part's centre, over its size) for
// component k: translations e_0.., then rotations ω × r about e_0.. (3D) or e_3 (2D).
Eigen::VectorXd rigid_row(int dim, const Eigen::VectorXd& r, int k) {
  Eigen::VectorXd a = Eigen::VectorXd::Zero(dim == 3 ? 6 : 3);
  a[k] = 1.0;
  if (dim == 2) {
    a[2] = k == 0 ? -r[1] : r[0];  // e_3 × r = (−r_1, r_0)
    return a;
  }
  for (int j = 0; j < 3; ++j) {  // (e_j × r)_k = ε_{kjl} r_l
    const int l = 3 - j - k;
    if (j != k) a[3 + j] = ((j - k + 3) % 3 == 1 ? 1.0 : -1.0) * r[l];
  }
  return a;
}

// A free rigid motion v (rigid_row's coordinates) in words: a rotation about an axis along ω
// (3D) or a translation along t, its largest entry made positive.
std::string free_motion(const Eigen::VectorXd& v, int dim) {
  const Eigen::VectorXd w = v.tail(v.size() - dim);
  const bool rotation = w.norm() >= 1e-6;
  if (rotation && dim == 2) return "a rotation";
  Eigen::VectorXd d = (rotation ? w : v.head(dim)).normalized();
  Eigen::Index big = 0;
  d.cwiseAbs().maxCoeff(&big);
  if (d[big] < 0.0) d = -d;
  return (rotation ? "a rotation about an axis along " : "a translation along ") + vec(d);
}

}  // namespace

void check_rigid_motions(const Mesh& mesh, const std::vector<DirichletConstraint>& constraints) {
  const std::vector<char> fixed = fixed_dofs(mesh, constraints);
  for (const DirichletConstraint& c : constraints)
    if (mesh.face(c.face).empty())
      throw InvalidArgument("group '" + c.face +
                            "' has no node of the body (no element of the body uses its nodes)");
  std::vector<int> part;
  const int P = connected_parts(mesh, &part), dim = mesh.dim, m = dim == 3 ? 6 : 3;
  std::vector<Eigen::VectorXd> centre(P, Eigen::VectorXd::Zero(dim));
  std::vector<double> count(P, 0.0), size(P, 0.0);
  for (Eigen::Index n = 0; n < mesh.num_nodes(); ++n) {
    centre[part[n]] += mesh.nodes.row(n).transpose();
    count[part[n]] += 1.0;
  }
  for (int p = 0; p < P; ++p) centre[p] /= count[p];
  for (Eigen::Index n = 0; n < mesh.num_nodes(); ++n)
    size[part[n]] =
        std::max(size[part[n]], (mesh.nodes.row(n).transpose() - centre[part[n]]).norm());
  // G_p = Σ a aᵀ over the fixed dofs of part p, a = the rigid modes there (rigid_row): its
  // eigenvalues are the squared singular values of the fixed rows on the rigid-mode space.
  std::vector<Eigen::MatrixXd> G(P, Eigen::MatrixXd::Zero(m, m));
  for (Eigen::Index n = 0; n < mesh.num_nodes(); ++n)
    for (int k = 0; k < dim; ++k)
      if (fixed[static_cast<size_t>(n) * dim + k]) {
        const int p = part[n];
        const Eigen::VectorXd r =
            (mesh.nodes.row(n).transpose() - centre[p]) / std::max(size[p], 1e-300);
        const Eigen::VectorXd a = rigid_row(dim, r, k);
        G[p].selfadjointView<Eigen::Lower>().rankUpdate(a);
      }
  for (int p = 0; p < P; ++p) {
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(G[p].selfadjointView<Eigen::Lower>());
    const Eigen::VectorXd& l = eig.eigenvalues();  // ascending
    // Rank test: σ_min/σ_max = sqrt(λ_min/λ_max) below 1e-5 is a free motion (a clamp face of
    // width w on a body of size L gives about w/L).
    int loose = 0;
    while (loose < m && !(l[loose] > 1e-10 * l[m - 1])) ++loose;
    if (loose == 0) continue;
    std::string held;
    for (const DirichletConstraint& c : constraints)
      for (int n : mesh.face(c.face))
        if (part[n] == p) {
          if (held.find("'" + c.face + "'") == std::string::npos)
            held += (held.empty() ? "'" : ", '") + c.face + "'";
          break;
        }
    const std::string name = part_name(mesh, part, p, P, centre[p]);
    if (held.empty())
      throw InvalidArgument("nothing holds " + name +
                            ": no clamp or constraint group has a node of it (clamp a group on "
                            "its boundary; parts hold each other only through shared nodes)");
    const std::string motion = free_motion(eig.eigenvectors().col(0), dim);
    throw InvalidArgument(held + " leave" + (held.find(',') == std::string::npos ? "s " : " ") +
                          name + " free to move rigidly (" + std::to_string(loose) + " of its " +
                          std::to_string(m) + " rigid motions, e.g. " + motion +
                          "): clamp a boundary group of it, or constrain more components");
  }
}

}  // namespace softhd::fe
