#include "softhd/fe/gmsh_mesh.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>

#include "../common/matrix_rows.hpp"
#include "softhd/error.hpp"

namespace softhd::fe {

namespace {

[[noreturn]] void fail(const std::string& what) { throw InvalidArgument("mesh: " + what); }

// A number for messages: %g (6 significant digits, an exponent when large or small).
std::string shown(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", x);
  return text;
}

// The cell type whose Gmsh code is `gmsh_type`, or false.
bool cell_of_gmsh(int gmsh_type, CellType* cell) {
  for (CellType c : {CellType::kQuad4, CellType::kQuad9, CellType::kTri3, CellType::kTri6,
                     CellType::kHex8, CellType::kHex27, CellType::kTet4, CellType::kTet10})
    if (reference_element(c).gmsh_type == gmsh_type) {
      *cell = c;
      return true;
    }
  return false;
}

std::string group_name(const io::MshFile& f, int dim, int tag) {
  for (const io::MshPhysicalGroup& g : f.physical_groups)
    if (g.dim == dim && g.tag == tag && !g.name.empty()) return g.name;
  return std::to_string(tag);  // an unnamed group is named by its tag
}

// True if every node lies in one plane z = const (a planar mesh of triangles or quads).
bool planar(const Eigen::MatrixXd& nodes) {
  if (nodes.rows() == 0) return true;
  const double z0 = nodes(0, 2);
  double extent = 0.0;
  for (Eigen::Index i = 0; i < nodes.rows(); ++i)
    extent = std::max(extent, (nodes.row(i) - nodes.row(0)).cwiseAbs().maxCoeff());
  for (Eigen::Index i = 0; i < nodes.rows(); ++i)
    if (std::abs(nodes(i, 2) - z0) > 1e-12 * std::max(extent, 1e-300)) return false;
  return true;
}

// The unit normal of the plane all nodes lie in (the covariance's null direction), or zero if
// they do not lie in one plane.
Eigen::Vector3d plane_normal(const Eigen::MatrixXd& nodes) {
  const Eigen::RowVector3d c = nodes.colwise().mean();
  const Eigen::MatrixXd d = nodes.rowwise() - c;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(d.transpose() * d);
  const double spread = es.eigenvalues()[2];  // ascending: the smallest is off the plane
  if (!(es.eigenvalues()[0] <= 1e-24 * spread)) return Eigen::Vector3d::Zero();
  return es.eigenvectors().col(0);
}

// Why a file of surface elements only cannot be a 2D body (whose nodes must lie in z = const).
[[noreturn]] void fail_not_in_xy(const Eigen::MatrixXd& nodes) {
  const Eigen::Vector3d n = plane_normal(nodes);
  if (n.isZero())
    fail(
        "the file has surface elements only, and they are not planar: Gmsh writes only the "
        "elements of physical groups, so add a Physical Volume for the body");
  std::ostringstream os;
  os.precision(3);
  os << "the file has surface elements only, in a plane with normal (" << n[0] << ", " << n[1]
     << ", " << n[2]
     << ") rather than z = const: a 2D body must lie in the xy-plane (rotate it there), and a 3D "
        "body needs a Physical Volume";
  fail(os.str());
}

// The body's cell type (from the file's top-dimension blocks, which must agree) and dim.
CellType body_cell(const io::MshFile& f, int* dim) {
  *dim = f.max_element_dim();
  if (*dim < 2) fail("the file has no volume or surface elements");
  if (*dim == 2 && !planar(f.nodes)) fail_not_in_xy(f.nodes);
  int gmsh_type = -1;
  for (const io::MshElementBlock& b : f.blocks) {
    if (b.dim != *dim) continue;
    if (gmsh_type >= 0 && b.gmsh_type != gmsh_type)
      fail("mixed element types of dimension " + std::to_string(*dim) + " (Gmsh types " +
           std::to_string(gmsh_type) + " and " + std::to_string(b.gmsh_type) +
           "): softhd solves on one cell type and order per mesh");
    gmsh_type = b.gmsh_type;
  }
  CellType cell;
  if (!cell_of_gmsh(gmsh_type, &cell))
    fail("Gmsh element type " + std::to_string(gmsh_type) +
         " is not one softhd solves on (tet4, tet10, hex8, hex27, tri3, tri6, quad4, quad9)");
  return cell;
}

// The physical tags of the body's dimension, sorted, and their names (the regions; "body"
// if there are none). Refuses an entity in two of them; an entity in none beside entities
// in one (Gmsh's -save_all writes it: its elements would join a region silently; it is
// refused rather than made a region of its own, as the file does not say what it is); and
// two groups of one name (a scene names regions).
std::vector<int> body_regions(const io::MshFile& f, int dim, std::vector<std::string>* names) {
  const char* group = dim == 3 ? "Physical Volume" : "Physical Surface";
  std::vector<int> tags;
  const io::MshElementBlock* untagged = nullptr;
  for (const io::MshElementBlock& b : f.blocks) {
    if (b.dim != dim) continue;
    if (b.physical_tags.size() > 1)
      fail("entity " + std::to_string(b.entity) + " belongs to " +
           std::to_string(b.physical_tags.size()) +
           " physical groups of the body's dimension: give each part of the body one");
    if (b.physical_tags.empty()) {
      if (!untagged) untagged = &b;
    } else if (std::find(tags.begin(), tags.end(), b.physical_tags[0]) == tags.end()) {
      tags.push_back(b.physical_tags[0]);
    }
  }
  if (untagged && !tags.empty())
    fail("entity " + std::to_string(untagged->entity) + " of dimension " + std::to_string(dim) +
         " is in no physical group while other parts of the body are (a file saved with "
         "-save_all?): add it to a " +
         group + ", or remove it");
  std::sort(tags.begin(), tags.end());
  names->clear();
  for (std::size_t k = 0; k < tags.size(); ++k) {
    names->push_back(group_name(f, dim, tags[k]));
    for (std::size_t j = 0; j < k; ++j)
      if ((*names)[j] == names->back())
        fail("physical groups " + std::to_string(tags[j]) + " and " + std::to_string(tags[k]) +
             " of dimension " + std::to_string(dim) + " are both named '" + names->back() +
             "': region names must differ (rename one, or make them one " + group + ")");
  }
  if (names->empty()) names->push_back("body");
  return tags;
}

// Elements of the body in the internal local order, node ids of the file, and the region
// of each (its block's physical group); fills region names.
void body_elements(const io::MshFile& f, int dim, CellType cell, Connectivity* elements,
                   Eigen::VectorXi* region, std::vector<std::string>* names,
                   std::vector<std::int64_t>* tags_out) {
  const ReferenceElement& ref = reference_element(cell);
  Eigen::Index count = 0;
  for (const io::MshElementBlock& b : f.blocks)
    if (b.dim == dim) count += b.nodes.rows();
  const std::vector<int> tags = body_regions(f, dim, names);
  elements->resize(count, ref.nodes);
  region->resize(count);
  Eigen::Index e = 0;
  for (const io::MshElementBlock& b : f.blocks) {
    if (b.dim != dim) continue;
    const int r = b.physical_tags.empty()
                      ? 0
                      : static_cast<int>(std::find(tags.begin(), tags.end(), b.physical_tags[0]) -
                                         tags.begin());
    for (Eigen::Index i = 0; i < b.nodes.rows(); ++i, ++e) {
      for (int a = 0; a < ref.nodes; ++a) (*elements)(e, a) = b.nodes(i, ref.gmsh_order[a]);
      (*region)[e] = r;
      tags_out->push_back(b.element_tags[static_cast<std::size_t>(i)]);
    }
  }
}

// Refuses two elements on the same nodes (one element listed twice under two tags: its
// volume would count twice), naming their Gmsh tags. Sorts the rows' node sets: O(E log E).
void check_repeated(const Connectivity& elements, const std::vector<std::int64_t>& tags) {
  Connectivity sets = elements;
  for (Eigen::Index e = 0; e < sets.rows(); ++e) std::sort(sets.row(e).begin(), sets.row(e).end());
  std::vector<Eigen::Index> order(static_cast<std::size_t>(sets.rows()));
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = static_cast<Eigen::Index>(k);
  const auto less = [&](Eigen::Index a, Eigen::Index b) {
    return std::lexicographical_compare(sets.row(a).begin(), sets.row(a).end(), sets.row(b).begin(),
                                        sets.row(b).end());
  };
  std::sort(order.begin(), order.end(), less);
  for (std::size_t k = 1; k < order.size(); ++k) {
    if (less(order[k - 1], order[k])) continue;
    std::int64_t a = tags[static_cast<std::size_t>(order[k - 1])];
    std::int64_t b = tags[static_cast<std::size_t>(order[k])];
    if (a > b) std::swap(a, b);
    fail("elements " + std::to_string(a) + " and " + std::to_string(b) +
         " have the same nodes (an element listed twice): remove one");
  }
}

// 2D elements whose outline runs clockwise (det dX/dξ < 0 at the centroid of the corners),
// e.g. from a Gmsh surface whose curve loop is clockwise, are reoriented: node a takes the
// node at the mirror image (ξ₁, ξ₂) -> (ξ₂, ξ₁) of its reference position, a symmetry of the
// reference triangle and square that reverses the orientation, X'(ξ) = X(ξ₂, ξ₁).
void orient_counter_clockwise(const Eigen::MatrixXd& X, CellType cell, Connectivity* elements) {
  const ReferenceElement& ref = reference_element(cell);
  const ReferenceElement& lin = reference_element(ref.linear);
  std::vector<int> mirror(ref.nodes);  // the node at the mirror image of node a
  for (int a = 0; a < ref.nodes; ++a)
    for (int b = 0; b < ref.nodes; ++b)
      if ((ref.node_coordinates.row(b) - ref.node_coordinates.row(a).reverse()).norm() < 1e-12)
        mirror[a] = b;
  const Eigen::VectorXd centre = lin.node_coordinates.colwise().mean().transpose();
  std::vector<double> N(lin.nodes), dN(lin.nodes * 2);
  shape_functions(ref.linear, centre.data(), N.data(), dN.data());
  std::vector<int> row(ref.nodes);
  for (Eigen::Index e = 0; e < elements->rows(); ++e) {
    Eigen::Matrix2d J = Eigen::Matrix2d::Zero();  // J_iK = Σ_v X_v,i dN_v/dξ_K
    for (int v = 0; v < lin.nodes; ++v)
      for (int i = 0; i < 2; ++i)
        for (int K = 0; K < 2; ++K)
          J(i, K) += X((*elements)(e, ref.vertex_nodes[v]), i) * dN[v * 2 + K];
    if (!(J.determinant() < 0.0)) continue;
    for (int a = 0; a < ref.nodes; ++a) row[a] = (*elements)(e, mirror[a]);
    for (int a = 0; a < ref.nodes; ++a) (*elements)(e, a) = row[a];
  }
}

// A mesh under construction: node ids of the file (or -1 for new midside nodes) and the
// positions of the new ones.
struct NodeTable {
  std::vector<int> new_id;                     // file node -> mesh node, -1 if unused
  std::vector<int> file_of;                    // mesh node -> file node (-1: new)
  std::vector<Eigen::VectorXd> new_position;   // of the new nodes, in order
  std::map<std::vector<int>, int> by_support;  // sorted vertex mesh ids -> new node id
  std::vector<std::vector<int>> support_of;    // per new node, its support (vertex mesh ids)
};

// Numbers the file nodes that `elements` use, in file order, and renumbers `elements`.
void number_used(Connectivity* elements, Eigen::Index file_nodes, NodeTable* t) {
  t->new_id.assign(file_nodes, -1);
  std::vector<char> used(file_nodes, 0);
  for (Eigen::Index e = 0; e < elements->rows(); ++e)
    for (Eigen::Index a = 0; a < elements->cols(); ++a) used[(*elements)(e, a)] = 1;
  for (Eigen::Index n = 0; n < file_nodes; ++n)
    if (used[n]) {
      t->new_id[n] = static_cast<int>(t->file_of.size());
      t->file_of.push_back(static_cast<int>(n));
    }
  for (Eigen::Index e = 0; e < elements->rows(); ++e)
    for (Eigen::Index a = 0; a < elements->cols(); ++a)
      (*elements)(e, a) = t->new_id[(*elements)(e, a)];
}

// Second-order elements on first-order ones (`corners`: mesh node ids in the linear cell's
// order): a node per sub-entity (edge, face, cell) shared by the elements that share its
// vertices, at X(ξ_a) = Σ_b N^lin_b(ξ_a) X_b (straight-sided).
Connectivity elevate(const Connectivity& corners, CellType quadratic, const Eigen::MatrixXd& X,
                     NodeTable* t) {
  const ReferenceElement& q = reference_element(quadratic);
  const ReferenceElement& lin = reference_element(q.linear);
  const int nv = lin.nodes, dim = q.dim;
  Connectivity out(corners.rows(), q.nodes);
  std::vector<double> N(nv), dN(nv * dim);
  const Eigen::Index base = static_cast<Eigen::Index>(t->file_of.size());
  for (Eigen::Index e = 0; e < corners.rows(); ++e)
    for (int a = 0; a < q.nodes; ++a) {
      const std::vector<int>& local = q.node_support[a];
      if (local.size() == 1) {
        out(e, a) = corners(e, local[0]);
        continue;
      }
      std::vector<int> key;
      for (int k : local) key.push_back(corners(e, k));
      std::sort(key.begin(), key.end());
      auto [it, fresh] =
          t->by_support.emplace(key, static_cast<int>(base + t->new_position.size()));
      if (fresh) {
        const Eigen::VectorXd xi = q.node_coordinates.row(a).transpose();
        shape_functions(q.linear, xi.data(), N.data(), dN.data());
        Eigen::VectorXd x = Eigen::VectorXd::Zero(dim);
        for (int b = 0; b < nv; ++b) x += N[b] * X.row(corners(e, b)).transpose();
        t->new_position.push_back(x);
        t->support_of.push_back(key);
      }
      out(e, a) = it->second;
    }
  return out;
}

}  // namespace

void GmshMeshOptions::validate() const {
  if (order != 0 && order != 1 && order != 2)
    throw InvalidArgument("mesh options: order must be 0 (the file's), 1 or 2");
  if (!(scale >= kMinScale && scale <= kMaxScale))
    throw InvalidArgument("mesh options: scale must be in [1e-12, 1e12], got " + shown(scale));
}

namespace {

// Named boundary node sets: every physical group below the body's dimension, as the mesh
// nodes of its elements; with elevated elements also the new nodes whose support lies in
// one of the group's facets.
std::map<std::string, std::vector<int>> boundary_sets(const io::MshFile& f, int dim,
                                                      const NodeTable& t, Eigen::Index new_base) {
  std::map<std::string, std::set<int>> sets;
  std::map<std::string, std::vector<std::vector<int>>> facets;  // vertex mesh ids, sorted
  for (const io::MshElementBlock& b : f.blocks) {
    if (b.dim >= dim || b.physical_tags.empty()) continue;
    for (int tag : b.physical_tags) {
      const std::string name = group_name(f, b.dim, tag);
      std::set<int>& nodes = sets[name];
      for (Eigen::Index i = 0; i < b.nodes.rows(); ++i) {
        std::vector<int> facet;
        for (Eigen::Index a = 0; a < b.nodes.cols(); ++a) {
          const int n = t.new_id[b.nodes(i, a)];
          if (n >= 0) nodes.insert(n), facet.push_back(n);
        }
        std::sort(facet.begin(), facet.end());
        if (!t.support_of.empty()) facets[name].push_back(facet);
      }
    }
  }
  std::map<std::string, std::vector<int>> out;
  for (auto& [name, nodes] : sets) {
    for (std::size_t k = 0; k < t.support_of.size(); ++k) {
      const std::vector<int>& sup = t.support_of[k];
      for (const std::vector<int>& facet : facets[name])
        if (std::includes(facet.begin(), facet.end(), sup.begin(), sup.end())) {
          nodes.insert(static_cast<int>(new_base + static_cast<Eigen::Index>(k)));
          break;
        }
    }
    out[name] = std::vector<int>(nodes.begin(), nodes.end());
  }
  for (const io::MshPhysicalGroup& g : f.physical_groups)  // named groups without elements
    if (g.dim < dim) out.emplace(group_name(f, g.dim, g.tag), std::vector<int>());
  return out;
}

using NodesWithinRadius = softhd::detail::WithinRadius<size_t>;

std::string point(const Eigen::VectorXd& x) {  // "(x, y, z)", 6 significant digits
  std::ostringstream s;
  s.precision(6);
  for (Eigen::Index i = 0; i < x.size(); ++i) s << (i ? ", " : "(") << x[i];
  return s.str() + ")";
}

// Refuses nodes of the file that lie within 1e-9 of the bounding-box diagonal of one another
// (docs/formulation.md §7): elements that touch there do not share nodes, so nothing joins
// them. A k-d tree over the nodes, O(n log n). Names the regions of the first pair's nodes.
void check_conforming(const io::MshFile& f, const NodeTable& t, const Mesh& m) {
  const Eigen::Index N = static_cast<Eigen::Index>(t.file_of.size());
  if (N < 2) return;
  const Eigen::MatrixXd X = m.nodes.topRows(N);  // the file's nodes (new ones come after)
  const double tol = 1e-9 * (X.colwise().maxCoeff() - X.colwise().minCoeff()).norm();
  const softhd::detail::MatrixRows rows{&X};
  const softhd::detail::MatrixRowsTree<> tree(static_cast<int>(X.cols()), rows,
                                              nanoflann::KDTreeSingleIndexAdaptorParams(16));
  std::vector<size_t> found;
  NodesWithinRadius within{tol * tol, &found};
  std::map<std::pair<int, int>, Eigen::Index> pairs;  // regions (a ≤ b) -> coincident pairs
  std::pair<Eigen::Index, Eigen::Index> first{-1, -1};
  std::vector<int> region(static_cast<size_t>(N), 0);  // of an element using the node
  for (Eigen::Index e = 0; e < m.num_elements(); ++e)
    for (Eigen::Index a = 0; a < m.elements.cols(); ++a)
      if (m.elements(e, a) < N) region[m.elements(e, a)] = m.element_region[e];
  for (Eigen::Index i = 0; i < N; ++i) {
    const Eigen::VectorXd x = X.row(i).transpose();
    found.clear();
    tree.radiusSearchCustomCallback(x.data(), within);
    for (size_t j : found) {
      if (static_cast<Eigen::Index>(j) <= i) continue;
      const int a = region[i], b = region[j];
      if (first.first < 0) first = {i, static_cast<Eigen::Index>(j)};
      ++pairs[{std::min(a, b), std::max(a, b)}];
    }
  }
  if (first.first < 0) return;
  const int a = region[first.first], b = region[first.second];
  const Eigen::Index n = pairs[{std::min(a, b), std::max(a, b)}];
  auto tag = [&](Eigen::Index i) {
    return std::to_string(f.node_tags[static_cast<size_t>(t.file_of[static_cast<size_t>(i)])]);
  };
  const std::string where = std::to_string(n) + " coincident nodes that they do not share (e.g. " +
                            "nodes " + tag(first.first) + " and " + tag(first.second) + " at " +
                            point(X.row(first.first).transpose()) + ")";
  if (a == b)
    fail("region '" + m.region_names[a] + "' has " + where +
         ": its elements are not joined there; remove the duplicate nodes (Coherence Mesh in "
         "Gmsh, or BooleanFragments on its parts before meshing)");
  fail("regions '" + m.region_names[std::min(a, b)] + "' and '" + m.region_names[std::max(a, b)] +
       "' touch at " + where +
       ": nothing joins them; mesh them with BooleanFragments (Coherence in a .geo file) so "
       "that they share their interface nodes");
}

// The vertices of the mesh (element corners, in node order) and each element's corners.
void number_vertices(Mesh* m) {
  const ReferenceElement& ref = reference_element(m->cell);
  const int nv = static_cast<int>(ref.vertex_nodes.size());
  std::vector<int> vertex_of(m->num_nodes(), -1);
  for (Eigen::Index e = 0; e < m->num_elements(); ++e)
    for (int k = 0; k < nv; ++k) vertex_of[m->elements(e, ref.vertex_nodes[k])] = 0;
  std::vector<int> nodes;
  for (Eigen::Index n = 0; n < m->num_nodes(); ++n)
    if (vertex_of[n] == 0) {
      vertex_of[n] = static_cast<int>(nodes.size());
      nodes.push_back(static_cast<int>(n));
    }
  m->vertex_nodes =
      Eigen::Map<Eigen::VectorXi>(nodes.data(), static_cast<Eigen::Index>(nodes.size()));
  m->element_vertices.resize(m->num_elements(), nv);
  for (Eigen::Index e = 0; e < m->num_elements(); ++e)
    for (int k = 0; k < nv; ++k)
      m->element_vertices(e, k) = vertex_of[m->elements(e, ref.vertex_nodes[k])];
}

// mesh_from_gmsh, with the node table and the Gmsh tag of each element.
Mesh build_mesh(const io::MshFile& f, const GmshMeshOptions& o, NodeTable* table,
                std::vector<std::int64_t>* element_tags) {
  o.validate();
  NodeTable& t = *table;
  int dim = 0;
  const CellType file_cell = body_cell(f, &dim);
  const ReferenceElement& fref = reference_element(file_cell);
  Mesh m;
  Connectivity el;
  body_elements(f, dim, file_cell, &el, &m.element_region, &m.region_names, element_tags);
  check_repeated(el, *element_tags);
  if (dim == 2) orient_counter_clockwise(f.nodes, file_cell, &el);
  const int order = o.order == 0 ? fref.order : o.order;
  m.cell = order == fref.order ? file_cell : order == 1 ? fref.linear : fref.quadratic;
  m.dim = dim;
  m.order = order;
  if (order < fref.order) {  // the vertices only
    Connectivity corners(el.rows(), static_cast<Eigen::Index>(fref.vertex_nodes.size()));
    for (Eigen::Index k = 0; k < corners.cols(); ++k) corners.col(k) = el.col(fref.vertex_nodes[k]);
    el = corners;
  }
  number_used(&el, f.nodes.rows(), &t);
  Eigen::MatrixXd X(static_cast<Eigen::Index>(t.file_of.size()), dim);
  for (Eigen::Index n = 0; n < X.rows(); ++n)
    X.row(n) = o.scale * f.nodes.row(t.file_of[n]).head(dim);
  const double extent = (X.colwise().maxCoeff() - X.colwise().minCoeff()).maxCoeff();
  if (extent != 0.0 && !std::isnormal(std::pow(extent, dim)))  // 0: degenerate, said later
    fail("the mesh spans " + shown(extent) + " (scale " + shown(o.scale) +
         "): its lengths and volumes must be normal doubles (change the scale or units)");
  const Eigen::Index new_base = X.rows();
  if (order > fref.order) el = elevate(el, m.cell, X, &t);
  m.nodes.resize(new_base + static_cast<Eigen::Index>(t.new_position.size()), dim);
  m.nodes.topRows(new_base) = X;
  for (std::size_t k = 0; k < t.new_position.size(); ++k)
    m.nodes.row(new_base + static_cast<Eigen::Index>(k)) = t.new_position[k].transpose();
  m.elements = std::move(el);
  m.element_tags = *element_tags;
  m.boundary_nodes = boundary_sets(f, dim, t, new_base);
  number_vertices(&m);
  for (std::size_t r = 0; r < m.region_names.size(); ++r)
    if ((m.element_region.array() == static_cast<int>(r)).count() == 0)
      fail("region '" + m.region_names[r] + "' has no elements");
  return m;
}

// A fibre value must be a finite non-zero vector (its sign is free: an axis).
void check_fiber(const Eigen::Vector3d& a, const std::string& block, const char* what,
                 std::int64_t tag) {
  if (!(a.norm() > 0.0) || !a.allFinite())
    fail("data block '" + block + "' gives " + what + " " + std::to_string(tag) +
         " a zero or non-finite fibre vector");
}

}  // namespace

Mesh mesh_from_gmsh(const io::MshFile& f, const GmshMeshOptions& o) {
  NodeTable t;
  std::vector<std::int64_t> tags;
  Mesh m = build_mesh(f, o, &t, &tags);
  check_conforming(f, t, m);
  return m;
}

FiberField gmsh_fiber_field(const io::MshFile& f, const std::string& name,
                            const GmshMeshOptions& o) {
  const io::MshDataBlock* block = nullptr;
  for (const io::MshDataBlock& d : f.data)
    if (d.name == name) block = &d;
  if (!block) fail("no $NodeData or $ElementData block named '" + name + "'");
  if (block->components != 3)
    fail("data block '" + name + "' has " + std::to_string(block->components) +
         " components, a fibre needs 3");
  NodeTable t;
  std::vector<std::int64_t> tags;
  const Mesh m = build_mesh(f, o, &t, &tags);
  FiberField field;
  if (block->per_element) {
    std::map<std::int64_t, Eigen::Index> row;  // element tag -> row of the block
    for (std::size_t k = 0; k < block->tags.size(); ++k)
      row[block->tags[k]] = static_cast<Eigen::Index>(k);
    field.kind = FiberField::Kind::kElement;
    field.values.resize(3, m.num_elements());
    for (Eigen::Index e = 0; e < m.num_elements(); ++e) {
      auto it = row.find(tags[static_cast<std::size_t>(e)]);
      if (it == row.end())
        fail("data block '" + name + "' has no value for element " +
             std::to_string(tags[static_cast<std::size_t>(e)]));
      field.values.col(e) = block->values.row(it->second).transpose();
      check_fiber(field.values.col(e), name, "element", tags[static_cast<std::size_t>(e)]);
    }
    return field;
  }
  std::vector<Eigen::Index> row(static_cast<std::size_t>(f.nodes.rows()), -1);
  for (std::size_t k = 0; k < block->tags.size(); ++k)
    row[static_cast<std::size_t>(block->tags[k])] = static_cast<Eigen::Index>(k);
  field.kind = FiberField::Kind::kNode;
  field.values.resize(3, m.num_nodes());
  const Eigen::Index base = static_cast<Eigen::Index>(t.file_of.size());
  for (Eigen::Index n = 0; n < base; ++n) {
    const Eigen::Index r = row[static_cast<std::size_t>(t.file_of[n])];
    if (r < 0)
      fail("data block '" + name + "' has no value for node " +
           std::to_string(f.node_tags[static_cast<std::size_t>(t.file_of[n])]));
    field.values.col(n) = block->values.row(r).transpose();
    check_fiber(field.values.col(n), name, "node",
                f.node_tags[static_cast<std::size_t>(t.file_of[n])]);
  }
  for (std::size_t k = 0; k < t.support_of.size(); ++k) {  // new nodes: the mean axis
    Eigen::Matrix3Xd a(3, static_cast<Eigen::Index>(t.support_of[k].size()));
    for (Eigen::Index j = 0; j < a.cols(); ++j)
      a.col(j) = field.values.col(t.support_of[k][static_cast<std::size_t>(j)]);
    field.values.col(base + static_cast<Eigen::Index>(k)) = aligned_fibers(a).rowwise().mean();
  }
  return field;
}

MeshSize gmsh_mesh_size(const io::MshCounts& counts, const GmshMeshOptions& o) {
  int dim = 0;  // the body: the solved-on type of the top dimension with the most elements
  double E = 0.0;
  CellType cell = CellType::kTet4;
  for (const auto& [type, n] : counts.elements) {
    CellType c;
    if (!cell_of_gmsh(type, &c)) continue;
    const int d = reference_element(c).dim;
    if (d > dim || (d == dim && static_cast<double>(n) > E))
      dim = d, E = static_cast<double>(n), cell = c;
  }
  if (dim == 0) return {};
  const ReferenceElement& file = reference_element(cell);
  const int order = o.order == 0 ? file.order : o.order;
  const ReferenceElement& ref = reference_element(order == 1 ? file.linear : file.quadratic);
  // Euler's formula V - edges + faces (- cells) ~ 0, each facet shared by two cells: edges
  // ~ V + E (triangles, tetrahedra, quadrilaterals), V + 2E (hexahedra); second-order
  // nodes: the vertices and one per edge, and for Q2 one per face and cell.
  const double k = ref.simplex ? 1.0 : dim == 2 ? 2.0 : 6.0;
  const double file_nodes = static_cast<double>(counts.nodes);
  const double V = file.order == 1 ? file_nodes : std::max(1.0, (file_nodes - k * E) / 2.0);
  const double N = order == 1 ? V : file.order == 2 ? file_nodes : 2.0 * V + k * E;
  // Ordered node pairs sharing a cell: P1 V + 2 edges = 3V + 2E; P2 adds the edge nodes'
  // pairs, counted per face and cell: 8V + 19E (triangles), 8V + 37E (tetrahedra); Q
  // cells as the box, (2p+1)^dim per node.
  const double pairs = !ref.simplex ? N * std::pow(2.0 * order + 1.0, dim)
                       : order == 1 ? 3.0 * V + 2.0 * E
                                    : 8.0 * V + (dim == 2 ? 19.0 : 37.0) * E;
  Eigen::MatrixXd points;
  Eigen::VectorXd weights;
  cell_quadrature(ref.type, ref.default_quadrature_degree, &points, &weights);
  return mesh_size(dim, N, E, ref.nodes, static_cast<int>(ref.vertex_nodes.size()),
                   static_cast<int>(points.rows()), pairs);
}

Mesh read_gmsh_mesh(const std::string& path, const GmshMeshOptions& options, double* volume,
                    double memory_limit) {
  options.validate();
  const auto check = [&](const io::MshCounts& counts) {
    check_mesh_size(gmsh_mesh_size(counts, options), memory_limit, path + ": the mesh");
  };
  const io::MshFile file = io::read_msh(path, check);  // FileError names the file
  try {
    Mesh m = mesh_from_gmsh(file, options);
    const ReferenceGeometry g(m, GradientStorage::kOnDemand);  // checks det dX/dξ > 0
    if (volume) *volume = g.weights().sum();
    return m;
  } catch (const InvalidArgument& e) {
    throw FileError(path + ": " + e.what());
  }
}

}  // namespace softhd::fe
