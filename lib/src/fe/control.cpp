#include "softhd/fe/control.hpp"

#include <Eigen/LU>
#include <sstream>

#include "softhd/enum_names.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/interpolation.hpp"
#include "softhd/fe/locator.hpp"

namespace softhd::fe {

constexpr auto kControlKinds = enum_sequence<ControlKind::kElement>({"vertex", "element"});

ControlKind parse_control_kind(const std::string& name) {
  return enum_from_name(kControlKinds, name, "control space");
}

bool in_regions(const Mesh& mesh, const std::vector<int>& regions, Eigen::Index e) {
  if (regions.empty()) return true;
  const int r = mesh.element_region.size() > e ? mesh.element_region[e] : 0;
  for (int k : regions)
    if (k == r) return true;
  return false;
}

std::vector<char> acting_controls(const Mesh& mesh, ControlKind kind,
                                  const std::vector<int>& regions) {
  const Eigen::Index E = mesh.num_elements();
  if (kind == ControlKind::kElement) {
    std::vector<char> acts(E);
    for (Eigen::Index e = 0; e < E; ++e) acts[e] = in_regions(mesh, regions, e);
    return acts;
  }
  std::vector<char> acts(mesh.num_vertices(), regions.empty() ? 1 : 0);
  if (regions.empty()) return acts;
  for (Eigen::Index e = 0; e < E; ++e)
    if (in_regions(mesh, regions, e))
      for (Eigen::Index a = 0; a < mesh.element_vertices.cols(); ++a)
        acts[mesh.element_vertices(e, a)] = 1;
  return acts;
}

namespace {
Eigen::VectorXd constant_where(const std::vector<char>& acts, double value) {
  Eigen::VectorXd m(static_cast<Eigen::Index>(acts.size()));
  for (Eigen::Index k = 0; k < m.size(); ++k) m[k] = acts[k] ? value : 0.0;
  return m;
}
}  // namespace

Eigen::VectorXd constant_control(const Mesh& mesh, ControlKind kind,
                                 const std::vector<int>& regions, double value) {
  return constant_where(acting_controls(mesh, kind, regions), value);
}

ControlSpace::ControlSpace(const Mesh& mesh, const ReferenceGeometry& g, ControlKind kind,
                           std::vector<int> regions)
    : kind_(kind), regions_(std::move(regions)), weights_(g.weights()) {
  const int nq = g.points_per_element(), dim = mesh.dim;
  const Eigen::Index E = mesh.num_elements();
  for (int r : regions_)
    if (r < 0 || r >= static_cast<int>(mesh.region_names.size()))
      throw InvalidArgument("control space: region id " + std::to_string(r) + " is not a region");
  acts_in_.resize(E);
  for (Eigen::Index e = 0; e < E; ++e) acts_in_[e] = in_regions(mesh, regions_, e);
  active_ = acting_controls(mesh, kind, regions_);
  if (kind == ControlKind::kElement) {
    size_ = E;
    support_.resize(E, 1);
    for (Eigen::Index e = 0; e < E; ++e) support_(e, 0) = static_cast<int>(e);
    M_ = Eigen::MatrixXd::Ones(nq, 1);
    dM_.assign(E, Eigen::MatrixXd::Zero(dim, nq));
    return;
  }
  size_ = mesh.num_vertices();
  support_ = mesh.element_vertices;
  const int nv = static_cast<int>(support_.cols());
  M_.resize(nq, nv);
  // The P1/Q1 functions of the linear cell on the element's vertices, at the points.
  const CellType linear = reference_element(mesh.cell).linear;
  const int nen = mesh.nodes_per_element();
  std::vector<Eigen::MatrixXd> dref(nq), dgeo(nq);
  Eigen::VectorXd N(nv), Ng(nen);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> dN(nv, dim), dG(nen, dim);
  for (int q = 0; q < nq; ++q) {
    const Eigen::VectorXd xi = g.reference_points().row(q).transpose();
    shape_functions(linear, xi.data(), N.data(), dN.data());
    M_.row(q) = N.transpose();
    dref[q] = dN;
    shape_functions(mesh.cell, xi.data(), Ng.data(), dG.data());
    dgeo[q] = dG;
  }
  // Gradients of the P1/Q1 functions in X: dM/dX = dM/dξ (dX/dξ)^{-1}, with dX/dξ the
  // element's own (isoparametric) map, Σ_a X_a ⊗ dN_a/dξ over all its nodes, so that ∇m is
  // exact on curved P2/Q2 elements too, where the map is not the vertices' one.
  dM_.resize(E);
  Eigen::MatrixXd Xe(nen, dim);
  for (Eigen::Index e = 0; e < E; ++e) {
    for (int a = 0; a < nen; ++a) Xe.row(a) = mesh.nodes.row(mesh.elements(e, a));
    dM_[e].resize(dim, nq * nv);
    for (int q = 0; q < nq; ++q) {
      const Eigen::MatrixXd J0 = Xe.transpose() * dgeo[q];
      dM_[e].middleCols(q * nv, nv) = (dref[q] * J0.inverse()).transpose();
    }
  }
}

Eigen::MatrixXd ControlSpace::to_quadrature(const Eigen::VectorXd& m) const {
  if (m.size() != size_) {
    throw InvalidArgument("control: expected " + std::to_string(size_) + " values, got " +
                          std::to_string(m.size()));
  }
  const Eigen::Index E = support_.rows();
  Eigen::MatrixXd mq(E, M_.rows());
  Eigen::VectorXd me(support_.cols());
  for (Eigen::Index e = 0; e < E; ++e) {
    if (!acts_in_[e]) {  // m = 0 outside the control's regions
      mq.row(e).setZero();
      continue;
    }
    for (Eigen::Index a = 0; a < support_.cols(); ++a) me[a] = m[support_(e, a)];
    mq.row(e) = (M_ * me).transpose();
  }
  return mq;
}

Eigen::VectorXd ControlSpace::from_quadrature(const Eigen::MatrixXd& v) const {
  Eigen::VectorXd g = Eigen::VectorXd::Zero(size_);
  for (Eigen::Index e = 0; e < support_.rows(); ++e) {
    if (!acts_in_[e]) continue;
    const Eigen::VectorXd ge = M_.transpose() * v.row(e).transpose();
    for (Eigen::Index a = 0; a < support_.cols(); ++a) g[support_(e, a)] += ge[a];
  }
  return g;
}

Eigen::VectorXd ControlSpace::constant(double value) const {
  return constant_where(active_, value);
}

Eigen::MatrixXd control_positions(const Mesh& mesh, ControlKind kind) {
  if (kind == ControlKind::kVertex) {
    Eigen::MatrixXd P(mesh.num_vertices(), mesh.dim);
    for (Eigen::Index k = 0; k < P.rows(); ++k) P.row(k) = mesh.nodes.row(mesh.vertex_nodes[k]);
    return P;
  }
  Eigen::MatrixXd P = Eigen::MatrixXd::Zero(mesh.num_elements(), mesh.dim);
  for (Eigen::Index e = 0; e < P.rows(); ++e) {
    for (int a = 0; a < mesh.nodes_per_element(); ++a)
      P.row(e) += mesh.nodes.row(mesh.elements(e, a));
    P.row(e) /= mesh.nodes_per_element();
  }
  return P;
}

double ControlSpace::regularisation(const Eigen::VectorXd& m, double Mreg, double eps,
                                    Eigen::VectorXd* gradient) const {
  // (M/2) ∫ m² + (ε/2) ∫ |∇m|² by quadrature; ∇m = 0 inside elements for element controls.
  const Eigen::Index E = support_.rows();
  const int nq = static_cast<int>(M_.rows()), nc = static_cast<int>(support_.cols());
  if (gradient) gradient->setZero(size_);
  double value = 0.0;
  Eigen::VectorXd me(nc);
  for (Eigen::Index e = 0; e < E; ++e) {
    if (!acts_in_[e]) continue;  // m = 0 there: no contribution
    for (int a = 0; a < nc; ++a) me[a] = m[support_(e, a)];
    for (int q = 0; q < nq; ++q) {
      const double w = weights_(e, q);
      const double mq = M_.row(q).dot(me);
      const Eigen::MatrixXd dM = dM_[e].middleCols(q * nc, kind_ == ControlKind::kVertex ? nc : 0);
      Eigen::VectorXd grad = Eigen::VectorXd::Zero(dM_[e].rows());
      if (kind_ == ControlKind::kVertex) grad = dM * me;
      value += w * (0.5 * Mreg * mq * mq + 0.5 * eps * grad.squaredNorm());
      if (gradient) {
        for (int a = 0; a < nc; ++a) {
          double ga = Mreg * mq * M_(q, a);
          if (kind_ == ControlKind::kVertex) ga += eps * grad.dot(dM.col(a));
          (*gradient)[support_(e, a)] += w * ga;
        }
      }
    }
  }
  return value;
}

Eigen::VectorXd control_at_nodes(const Mesh& mesh, const ControlSpace& space,
                                 const Eigen::VectorXd& m) {
  if (space.kind() != ControlKind::kVertex) return Eigen::VectorXd::Zero(mesh.num_nodes());
  if (space.regions().empty()) return control_at(mesh, ControlKind::kVertex, m, mesh.nodes);
  // With regions, a node on a region's boundary takes the value of the region side:
  // m(X_a) = Σ_b M_b(ξ_a) m_b over the vertices b of an element of the regions.
  const CellType linear = reference_element(mesh.cell).linear;
  const ReferenceElement& ref = reference_element(mesh.cell);
  const int nv = static_cast<int>(mesh.element_vertices.cols());
  Eigen::VectorXd values = Eigen::VectorXd::Zero(mesh.num_nodes()), N(nv), dN(nv * mesh.dim);
  for (Eigen::Index e = 0; e < mesh.num_elements(); ++e) {
    if (!in_regions(mesh, space.regions(), e)) continue;
    for (int a = 0; a < mesh.nodes_per_element(); ++a) {
      const Eigen::VectorXd xi = ref.node_coordinates.row(a).transpose();
      shape_functions(linear, xi.data(), N.data(), dN.data());
      double v = 0.0;
      for (int b = 0; b < nv; ++b) v += N[b] * m[mesh.element_vertices(e, b)];
      values[mesh.elements(e, a)] = v;
    }
  }
  return values;
}

Eigen::VectorXd control_at(const Mesh& mesh, ControlKind kind, const Eigen::VectorXd& m,
                           const Eigen::MatrixXd& X, const std::vector<int>& regions) {
  const PointLocator locator(mesh);
  std::vector<int> outside;
  Eigen::VectorXd values(X.rows());
  if (kind == ControlKind::kElement) {
    const Eigen::VectorXi e = locate_points(locator, X);
    for (Eigen::Index p = 0; p < X.rows(); ++p) {
      if (e[p] < 0) {
        outside.push_back(static_cast<int>(p));
        break;
      }
      values[p] = m[e[p]];
    }
  } else {  // m(X) = Σ_a M_a(ξ) m_a over the element's vertices (P1/Q1 shape functions)
    values = interpolate_vertex(mesh, locator, m, X, &outside);
  }
  if (!outside.empty()) {
    std::ostringstream os;
    os << "control_at: the point (" << X.row(outside[0]) << ") is outside the body";
    throw InvalidArgument(os.str());
  }
  if (!regions.empty()) {  // m = 0 outside the control's regions
    const Eigen::VectorXi e = locate_points(locator, X);
    for (Eigen::Index p = 0; p < X.rows(); ++p)
      if (!in_regions(mesh, regions, e[p])) values[p] = 0.0;
  }
  return values;
}

}  // namespace softhd::fe
