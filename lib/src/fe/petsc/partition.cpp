#include "partition.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <numeric>
#include <string>

#include "softhd/error.hpp"

namespace softhd::fe::petsc_detail {

namespace {

// Bounds and centroid (the mean of its nodes) of every element: E by dim each.
struct ElementBoxes {
  Eigen::MatrixXd lo, hi, centroid;
};

ElementBoxes element_boxes(const Mesh& mesh) {
  const Eigen::Index E = mesh.num_elements();
  const int dim = mesh.dim, nen = mesh.nodes_per_element();
  ElementBoxes b{Eigen::MatrixXd(E, dim), Eigen::MatrixXd(E, dim), Eigen::MatrixXd(E, dim)};
  for (Eigen::Index e = 0; e < E; ++e)
    for (int d = 0; d < dim; ++d) {
      double lo = INFINITY, hi = -INFINITY, sum = 0.0;
      for (int a = 0; a < nen; ++a) {
        const double x = mesh.nodes(mesh.elements(e, a), d);
        lo = std::min(lo, x);
        hi = std::max(hi, x);
        sum += x;
      }
      b.lo(e, d) = lo;
      b.hi(e, d) = hi;
      b.centroid(e, d) = sum / nen;
    }
  return b;
}

// The axis the elements [first, last) have the most elements across: n extent / Σ width
// along it (the extent over the mean element width); the lowest axis on ties (1e-9).
int most_across(const ElementBoxes& b, const int* first, const int* last) {
  int best = 0;
  double best_count = -1.0;
  for (int d = 0; d < b.lo.cols(); ++d) {
    double lo = INFINITY, hi = -INFINITY, width = 0.0;
    for (const int* e = first; e != last; ++e) {
      lo = std::min(lo, b.lo(*e, d));
      hi = std::max(hi, b.hi(*e, d));
      width += b.hi(*e, d) - b.lo(*e, d);
    }
    const double count = width > 0.0 ? (hi - lo) * static_cast<double>(last - first) / width : 0.0;
    if (count > best_count * (1.0 + 1e-9)) {
      best = d;
      best_count = count;
    }
  }
  return best;
}

// Where to cut n elements sorted by `key` (their centroid coordinates along the cut axis)
// so that kl of k ranks take the lower side: at ⌊n kl / k⌋, moved down to the start of the
// run of equal keys it falls in, else up to its end, if both sides keep at least one
// element per rank.
std::ptrdiff_t cut_position(const std::vector<double>& key, int kl, int k) {
  const auto n = static_cast<std::ptrdiff_t>(key.size());
  const auto raw = static_cast<std::ptrdiff_t>(static_cast<std::int64_t>(n) * kl / k);
  auto fits = [&](std::ptrdiff_t c) { return c >= kl && n - c >= k - kl; };
  std::ptrdiff_t down = raw, up = raw;
  while (down > 0 && key[down - 1] == key[raw]) --down;
  if (down == raw) return raw;  // already between two runs
  while (up < n && key[up] == key[raw]) ++up;
  return fits(down) ? down : fits(up) ? up : raw;
}

// Recursive coordinate bisection of the elements [first, last) among ranks rank0 ..
// rank0 + k - 1 (each side has at least one element per rank: n >= k on entry).
void bisect(const ElementBoxes& b, int* first, int* last, int rank0, int k, std::vector<int>* owner,
            int* axis) {
  if (k == 1) {
    for (int* e = first; e != last; ++e) (*owner)[*e] = rank0;
    return;
  }
  const int a = most_across(b, first, last);
  if (axis) *axis = a;
  std::sort(first, last, [&](int i, int j) {
    const double ci = b.centroid(i, a), cj = b.centroid(j, a);
    return ci < cj || (ci == cj && i < j);
  });
  std::vector<double> key(static_cast<size_t>(last - first));
  for (size_t i = 0; i < key.size(); ++i) key[i] = b.centroid(first[i], a);
  const int kl = k / 2;
  const std::ptrdiff_t cut = cut_position(key, kl, k);
  bisect(b, first, first + cut, rank0, kl, owner, nullptr);
  bisect(b, first + cut, last, rank0 + kl, k - kl, owner, nullptr);
}

// Local ids of the marked global ids (-1 for the others) in increasing global order;
// `ids` gets the global id of each local one.
std::vector<int> compact(const std::vector<char>& used, std::vector<int>* ids) {
  std::vector<int> local(used.size(), -1);
  for (size_t i = 0; i < used.size(); ++i)
    if (used[i]) {
      local[i] = static_cast<int>(ids->size());
      ids->push_back(static_cast<int>(i));
    }
  return local;
}

// The mesh of the global elements `elements` (increasing ids); `node_ids` and `vertex_ids`
// get the global ids of its nodes and vertices.
Mesh submesh(const Mesh& g, const std::vector<int>& elements, std::vector<int>* node_ids,
             std::vector<int>* vertex_ids) {
  const int nen = g.nodes_per_element(), nv = static_cast<int>(g.element_vertices.cols());
  std::vector<char> node_used(g.num_nodes(), 0), vertex_used(g.num_vertices(), 0);
  for (int e : elements) {
    for (int a = 0; a < nen; ++a) node_used[g.elements(e, a)] = 1;
    for (int a = 0; a < nv; ++a) vertex_used[g.element_vertices(e, a)] = 1;
  }
  const std::vector<int> ln = compact(node_used, node_ids), lv = compact(vertex_used, vertex_ids);
  Mesh m;
  m.dim = g.dim;
  m.order = g.order;
  m.cell = g.cell;
  m.region_names = g.region_names;
  m.nodes.resize(static_cast<Eigen::Index>(node_ids->size()), g.dim);
  for (size_t i = 0; i < node_ids->size(); ++i) m.nodes.row(i) = g.nodes.row((*node_ids)[i]);
  const auto E = static_cast<Eigen::Index>(elements.size());
  m.elements.resize(E, nen);
  m.element_vertices.resize(E, nv);
  const bool regions = g.element_region.size() == g.num_elements();
  m.element_region = Eigen::VectorXi::Zero(E);
  for (Eigen::Index k = 0; k < E; ++k) {
    const int e = elements[k];
    for (int a = 0; a < nen; ++a) m.elements(k, a) = ln[g.elements(e, a)];
    for (int a = 0; a < nv; ++a) m.element_vertices(k, a) = lv[g.element_vertices(e, a)];
    if (regions) m.element_region[k] = g.element_region[e];
    if (!g.element_tags.empty()) m.element_tags.push_back(g.element_tags[e]);
  }
  m.vertex_nodes.resize(static_cast<Eigen::Index>(vertex_ids->size()));
  for (size_t v = 0; v < vertex_ids->size(); ++v)
    m.vertex_nodes[v] = ln[g.vertex_nodes[(*vertex_ids)[v]]];
  for (const auto& [name, nodes] : g.boundary_nodes) {
    std::vector<int>& out = m.boundary_nodes[name];
    for (int n : nodes)
      if (ln[n] >= 0) out.push_back(ln[n]);
  }
  return m;
}

FiberField restrict_fibers(const FiberField& f, const Partition& p) {
  if (f.kind == FiberField::Kind::kUniform) return f;
  const std::vector<int>& ids =
      f.kind == FiberField::Kind::kElement ? p.global_element : p.global_node;
  FiberField out;
  out.kind = f.kind;
  out.values.resize(3, static_cast<Eigen::Index>(ids.size()));
  for (size_t i = 0; i < ids.size(); ++i) out.values.col(i) = f.values.col(ids[i]);
  return out;
}

// The owner of every node: the lowest rank whose elements touch it.
std::vector<int> node_owners(const Mesh& g, const std::vector<int>& element_owner) {
  std::vector<int> owner(g.num_nodes(), INT_MAX);
  for (Eigen::Index e = 0; e < g.num_elements(); ++e)
    for (int a = 0; a < g.nodes_per_element(); ++a) {
      int& o = owner[g.elements(e, a)];
      o = std::min(o, element_owner[e]);
    }
  for (size_t n = 0; n < owner.size(); ++n)
    if (owner[n] == INT_MAX)
      throw InvalidArgument("PETSc state: node " + std::to_string(n) +
                            " of the mesh is in no element");
  return owner;
}

// The global nodes in row order: by owner, then by their coordinates (X_a, X_c, X_b).
std::vector<int> row_order(const Mesh& g, const std::vector<int>& owner, int a) {
  int axes[3] = {a, -1, -1}, k = 1;
  for (int d = g.dim - 1; d >= 0; --d)  // the others, the higher first
    if (d != a) axes[k++] = d;
  std::vector<int> order(g.num_nodes());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int i, int j) {
    if (owner[i] != owner[j]) return owner[i] < owner[j];
    for (int l = 0; l < g.dim; ++l) {
      const double xi = g.nodes(i, axes[l]), xj = g.nodes(j, axes[l]);
      if (xi != xj) return xi < xj;
    }
    return i < j;
  });
  return order;
}

// The nonzero counts of the owned rows (FreeNumbering): for each owned node, in row order,
// the free components of the nodes it shares an element with, through a node-to-element
// incidence of the whole mesh.
void count_nonzeros(const Mesh& g, const DofMap& global, const std::vector<int>& owner,
                    const std::vector<int>& owned_nodes, int rank, FreeNumbering* f) {
  const int dim = g.dim, nen = g.nodes_per_element();
  const Eigen::Index nn = g.num_nodes(), E = g.num_elements();
  std::vector<Eigen::Index> first(nn + 1, 0);
  for (Eigen::Index e = 0; e < E; ++e)
    for (int a = 0; a < nen; ++a) ++first[g.elements(e, a) + 1];
  for (Eigen::Index n = 0; n < nn; ++n) first[n + 1] += first[n];
  std::vector<Eigen::Index> incident(first[nn]), next(first.begin(), first.end() - 1);
  for (Eigen::Index e = 0; e < E; ++e)
    for (int a = 0; a < nen; ++a) incident[next[g.elements(e, a)]++] = e;
  std::vector<int> seen(nn, -1);
  for (int n : owned_nodes) {
    int diagonal = 0, off = 0;
    for (Eigen::Index k = first[n]; k < first[n + 1]; ++k)
      for (int a = 0; a < nen; ++a) {
        const int m = g.elements(incident[k], a);
        if (seen[m] == n) continue;
        seen[m] = n;
        for (int c = 0; c < dim; ++c)
          if (global.free_index[static_cast<Eigen::Index>(m) * dim + c] >= 0)
            ++(owner[m] == rank ? diagonal : off);
      }
    for (int c = 0; c < dim; ++c)
      if (global.free_index[static_cast<Eigen::Index>(n) * dim + c] >= 0) {
        f->diagonal_nonzeros.push_back(diagonal);
        f->off_diagonal_nonzeros.push_back(off);
      }
  }
}

// The rows (see the header) as seen by p.rank; `local` is the DofMap of p.mesh.
FreeNumbering number_rows(const Mesh& g, const std::vector<DirichletConstraint>& constraints,
                          const std::vector<int>& owner, const Partition& p, const DofMap& local) {
  const int dim = g.dim;
  const DofMap global = make_dof_map(g, constraints);
  std::vector<std::int64_t> row(static_cast<size_t>(global.num_dofs), -1);
  std::vector<int> local_node(g.num_nodes(), -1);
  for (size_t l = 0; l < p.global_node.size(); ++l)
    local_node[p.global_node[l]] = static_cast<int>(l);
  FreeNumbering f;
  std::vector<int> owned_nodes;
  for (int n : row_order(g, owner, p.axis)) {
    if (owner[n] == p.rank) owned_nodes.push_back(n);
    for (int k = 0; k < dim; ++k) {
      const Eigen::Index dof = static_cast<Eigen::Index>(n) * dim + k;
      if (global.free_index[dof] < 0) continue;
      if (owner[n] == p.rank) {
        f.owned_local.push_back(
            local.free_index[static_cast<Eigen::Index>(local_node[n]) * dim + k]);
        f.owned_global_dof.push_back(dof);
      }
      row[dof] = f.num_global++;
    }
    if (owner[n] < p.rank) f.owned_begin = f.num_global;  // rows of the lower ranks
  }
  f.owned_end = f.owned_begin + static_cast<std::int64_t>(f.owned_local.size());
  f.local_to_global.assign(static_cast<size_t>(local.num_free), -1);
  for (size_t l = 0; l < p.global_node.size(); ++l) {
    int free_components = 0;
    for (int k = 0; k < dim; ++k) {
      const int fi = local.free_index[static_cast<Eigen::Index>(l) * dim + k];
      const std::int64_t r = row[static_cast<size_t>(p.global_node[l]) * dim + k];
      SOFTHD_ASSERT((fi < 0) == (r < 0),
                    "PETSc state: the part's constraints differ from the mesh's");
      if (fi < 0) continue;
      ++free_components;
      f.local_to_global[fi] = r;
    }
    if (free_components != 0 && free_components != dim) f.whole_nodes = false;
  }
  count_nonzeros(g, global, owner, owned_nodes, p.rank, &f);
  return f;
}

}  // namespace

std::vector<int> bisect_elements(const Mesh& mesh, int size, int* first_axis) {
  if (size < 1) throw InvalidArgument("PETSc state: the number of ranks must be >= 1");
  const Eigen::Index E = mesh.num_elements();
  if (E < size)
    throw InvalidArgument("PETSc state: the mesh has " + std::to_string(E) +
                          " elements, fewer than the " + std::to_string(size) + " ranks");
  std::vector<int> order(E), owner(E, 0);
  std::iota(order.begin(), order.end(), 0);
  *first_axis = 0;
  bisect(element_boxes(mesh), order.data(), order.data() + E, 0, size, &owner, first_axis);
  return owner;
}

Partition make_partition(const Body& body, int rank, int size) {
  if (rank < 0 || rank >= size) throw InvalidArgument("PETSc state: rank out of range");
  const Mesh global = body.make_mesh();
  Partition p;
  p.rank = rank;
  p.size = size;
  const std::vector<int> element_owner = bisect_elements(global, size, &p.axis);
  for (Eigen::Index e = 0; e < global.num_elements(); ++e)
    if (element_owner[e] == rank) p.global_element.push_back(static_cast<int>(e));
  p.mesh = submesh(global, p.global_element, &p.global_node, &p.global_vertex);
  p.fibers = restrict_fibers(body.fiber_field, p);
  p.num_global_nodes = global.num_nodes();
  p.num_global_elements = global.num_elements();
  p.num_global_vertices = global.num_vertices();
  p.numbering = number_rows(global, body.constraints, node_owners(global, element_owner), p,
                            make_dof_map(p.mesh, body.constraints));
  return p;
}

}  // namespace softhd::fe::petsc_detail
