#include "softhd/fe/mesh.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <sstream>

#include "softhd/error.hpp"

namespace softhd::fe {

std::string Mesh::element_name(Eigen::Index e) const {
  return "element " + std::to_string(element_tags.empty()
                                         ? static_cast<std::int64_t>(e)
                                         : element_tags[static_cast<std::size_t>(e)]);
}

const std::vector<int>& Mesh::face(const std::string& name) const {
  auto it = boundary_nodes.find(name);
  if (it == boundary_nodes.end()) {
    for (const std::string& r : region_names)  // a Gmsh file's region (a box lists its faces)
      if (r == name && !structured())
        throw InvalidArgument("mesh: '" + name + "' is a region of the body (a physical " +
                              (dim == 3 ? "volume" : "surface") + "), not a boundary group: " +
                              "a clamp needs a " + (dim == 3 ? "surface" : "curve") + " group");
    std::string names;
    for (const auto& [n, nodes] : boundary_nodes) names += (names.empty() ? "" : ", ") + n;
    throw InvalidArgument("mesh: unknown boundary face '" + name + "' (expected one of " +
                          (names.empty() ? "none: the mesh has no named boundary" : names) + ")");
  }
  return it->second;
}

int Mesh::region(const std::string& name) const {
  for (std::size_t r = 0; r < region_names.size(); ++r)
    if (region_names[r] == name) return static_cast<int>(r);
  std::string names;
  for (const auto& n : region_names) names += (names.empty() ? "" : ", ") + n;
  throw InvalidArgument("mesh: unknown region '" + name + "' (expected one of " + names + ")");
}

MeshSize mesh_size(int dim, double nodes, double elements, int nodes_per_element, int vertices,
                   int quadrature_points, double pairs) {
  const double nen = nodes_per_element;
  const double dofs = nodes * dim;
  const double quadrature = elements * quadrature_points;
  const double tangent_nonzeros = pairs * dim * dim;  // a dim x dim block per node pair
  MeshSize s;
  constexpr double kInt64 = 9.2e18;  // the counts are exact below this
  s.nodes = static_cast<std::int64_t>(std::min(nodes, kInt64));
  s.elements = static_cast<std::int64_t>(std::min(elements, kInt64));
  s.dofs = static_cast<std::int64_t>(std::min(dofs, kInt64));
  s.quadrature_points = static_cast<std::int64_t>(std::min(quadrature, kInt64));
  s.bytes = nodes * dim * 8.0 + elements * (nen + vertices) * 4.0 +
            quadrature * (dim * nen * 8.0 + 24.0) + 3.0 * tangent_nonzeros * 12.0 +
            10.0 * dofs * 8.0;
  return s;
}

MeshSize box_mesh_size(const Eigen::VectorXd& cells, int order) {
  const int dim = static_cast<int>(cells.size());
  double nodes = 1.0, elements = 1.0;
  for (int d = 0; d < dim; ++d) {
    nodes *= order * cells[d] + 1.0;
    elements *= cells[d];
  }
  const int nen = static_cast<int>(std::pow(order + 1, dim));
  // The tangent couples a node with the (2p+1)^dim nodes of the elements around it.
  return mesh_size(dim, nodes, elements, nen, 1 << dim, nen,
                   nodes * std::pow(2.0 * order + 1.0, dim));
}

void check_mesh_size(const MeshSize& size, double memory_limit, const std::string& what) {
  std::ostringstream msg;
  msg.precision(3);
  msg << what << " has " << size.nodes << " nodes and " << size.elements << " elements";
  if (size.bytes > memory_limit) {
    msg << ": it needs about " << size.bytes / (1u << 30) << " GiB, above the memory limit of "
        << memory_limit / (1u << 30) << " GiB (raise the limit: --max-memory GIB)";
    throw ResourceError(msg.str());
  }
  if (size.dofs > INT_MAX || size.quadrature_points > INT_MAX) {
    msg << " (" << size.dofs << " dofs, " << size.quadrature_points
        << " quadrature points): more than the 2147483647 one run can index";
    throw ResourceError(msg.str());
  }
}

Mesh make_box_mesh(const Eigen::VectorXd& lo, const Eigen::VectorXd& hi,
                   const Eigen::VectorXi& cells, int order) {
  const int dim = static_cast<int>(lo.size());
  if (dim != 2 && dim != 3) throw InvalidArgument("box mesh: dimension must be 2 or 3");
  if (hi.size() != dim || cells.size() != dim) {
    throw InvalidArgument("box mesh: lo, hi and cells must have the same size");
  }
  if (order != 1 && order != 2) {
    throw InvalidArgument("box mesh: order must be 1 or 2, got " + std::to_string(order));
  }
  for (int d = 0; d < dim; ++d) {
    if (!(hi[d] > lo[d]) || !std::isfinite(lo[d]) || !std::isfinite(hi[d])) {
      throw InvalidArgument("box mesh: need lo < hi (finite) along axis " + std::to_string(d));
    }
    if (cells[d] < 1) throw InvalidArgument("box mesh: cells must be >= 1 along every axis");
  }
  check_mesh_size(box_mesh_size(cells.cast<double>(), order), INFINITY, "box mesh");
  Mesh m;
  m.dim = dim;
  m.order = order;
  m.cell = cell_type(dim, order, false);
  m.box_lo = lo;
  m.box_hi = hi;
  m.cells = cells;
  int nn[3] = {1, 1, 1}, nc[3] = {1, 1, 1};
  for (int d = 0; d < dim; ++d) {
    nc[d] = cells[d];
    nn[d] = order * cells[d] + 1;
  }
  const int num_nodes = nn[0] * nn[1] * nn[2];
  auto node_id = [&](int i, int j, int k) { return i + nn[0] * (j + nn[1] * k); };
  m.nodes.resize(num_nodes, dim);
  for (int k = 0; k < nn[2]; ++k)
    for (int j = 0; j < nn[1]; ++j)
      for (int i = 0; i < nn[0]; ++i) {
        const int ijk[3] = {i, j, k};
        for (int d = 0; d < dim; ++d) {
          m.nodes(node_id(i, j, k), d) =
              lo[d] + (hi[d] - lo[d]) * static_cast<double>(ijk[d]) / (nn[d] - 1);
        }
      }
  // Vertices: the nodes whose grid indices are multiples of the order.
  const int nv[3] = {nc[0] + 1, dim >= 2 ? nc[1] + 1 : 1, dim == 3 ? nc[2] + 1 : 1};
  auto vertex_id = [&](int i, int j, int k) { return i + nv[0] * (j + nv[1] * k); };
  m.vertex_nodes.resize(nv[0] * nv[1] * nv[2]);
  for (int k = 0; k < nv[2]; ++k)
    for (int j = 0; j < nv[1]; ++j)
      for (int i = 0; i < nv[0]; ++i)
        m.vertex_nodes[vertex_id(i, j, k)] = node_id(order * i, order * j, order * k);
  const int n1 = order + 1;
  const int nen = dim == 2 ? n1 * n1 : n1 * n1 * n1;
  const int nve = dim == 2 ? 4 : 8;
  const int num_el = nc[0] * nc[1] * nc[2];
  m.elements.resize(num_el, nen);
  m.element_vertices.resize(num_el, nve);
  for (int ek = 0; ek < nc[2]; ++ek)
    for (int ej = 0; ej < nc[1]; ++ej)
      for (int ei = 0; ei < nc[0]; ++ei) {
        const int e = ei + nc[0] * (ej + nc[1] * ek);
        for (int a = 0; a < nen; ++a) {
          const int i = a % n1, j = (a / n1) % n1, k = a / (n1 * n1);
          m.elements(e, a) = node_id(order * ei + i, order * ej + j, order * ek + k);
        }
        for (int a = 0; a < nve; ++a) {
          const int i = a % 2, j = (a / 2) % 2, k = a / 4;
          m.element_vertices(e, a) = vertex_id(ei + i, ej + j, ek + k);
        }
      }
  const char* axes = "xyz";
  for (int d = 0; d < dim; ++d) {
    std::vector<int> f0, f1;
    for (int n = 0; n < num_nodes; ++n) {
      const int ijk[3] = {n % nn[0], (n / nn[0]) % nn[1], n / (nn[0] * nn[1])};
      if (ijk[d] == 0) f0.push_back(n);
      if (ijk[d] == nn[d] - 1) f1.push_back(n);
    }
    m.boundary_nodes[std::string(1, axes[d]) + "0"] = f0;
    m.boundary_nodes[std::string(1, axes[d]) + "1"] = f1;
  }
  m.element_region = Eigen::VectorXi::Zero(num_el);
  return m;
}

Mesh linear_mesh(const Mesh& mesh) {
  if (mesh.order == 1) return mesh;
  Mesh m;
  m.dim = mesh.dim;
  m.order = 1;
  m.cell = reference_element(mesh.cell).linear;
  const Eigen::Index nv = mesh.num_vertices();
  m.nodes.resize(nv, mesh.dim);
  std::vector<int> vertex_of(static_cast<std::size_t>(mesh.num_nodes()), -1);
  for (Eigen::Index k = 0; k < nv; ++k) {
    m.nodes.row(k) = mesh.nodes.row(mesh.vertex_nodes[k]);
    vertex_of[static_cast<std::size_t>(mesh.vertex_nodes[k])] = static_cast<int>(k);
  }
  m.elements = mesh.element_vertices;  // in the linear cell's local order
  m.element_vertices = mesh.element_vertices;
  m.vertex_nodes = Eigen::VectorXi::LinSpaced(nv, 0, static_cast<int>(nv) - 1);
  for (const auto& [name, nodes] : mesh.boundary_nodes) {
    std::vector<int>& set = m.boundary_nodes[name];
    for (int n : nodes)
      if (vertex_of[static_cast<std::size_t>(n)] >= 0)
        set.push_back(vertex_of[static_cast<std::size_t>(n)]);
    std::sort(set.begin(), set.end());
  }
  m.element_region = mesh.element_region;
  m.region_names = mesh.region_names;
  m.element_tags = mesh.element_tags;
  m.box_lo = mesh.box_lo;
  m.box_hi = mesh.box_hi;
  m.cells = mesh.cells;
  return m;
}

int locate(const Mesh& mesh, const Eigen::VectorXd& X, Eigen::VectorXd* xi) {
  const int dim = mesh.dim;
  if (X.size() != dim) return -1;
  int cell[3] = {0, 0, 0};
  xi->resize(dim);
  for (int d = 0; d < dim; ++d) {
    const double len = mesh.box_hi[d] - mesh.box_lo[d];
    const double s = (X[d] - mesh.box_lo[d]) / len;  // in [0, 1] inside the box
    if (!(s >= -1e-10 && s <= 1.0 + 1e-10)) return -1;
    const double c = std::clamp(s, 0.0, 1.0) * mesh.cells[d];
    cell[d] = std::min(static_cast<int>(std::floor(c)), mesh.cells[d] - 1);
    (*xi)[d] = std::clamp(2.0 * (c - cell[d]) - 1.0, -1.0, 1.0);
  }
  const int ny = dim >= 2 ? mesh.cells[1] : 1;
  return cell[0] + mesh.cells[0] * (cell[1] + ny * cell[2]);
}

}  // namespace softhd::fe
