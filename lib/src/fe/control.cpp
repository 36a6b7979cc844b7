#include "softhd/fe/control.hpp"

#include <Eigen/LU>

#include "softhd/enum_names.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/grid_sequencing.hpp"

namespace softhd::fe {

namespace {
constexpr EnumNames<ControlKind, 2> kControlKinds{
    {{ControlKind::kVertex, "vertex"}, {ControlKind::kElement, "element"}}};
}  // namespace

ControlKind parse_control_kind(const std::string& name) {
  return enum_from_name(kControlKinds, name, "control space");
}

ControlSpace::ControlSpace(const Mesh& mesh, const ReferenceGeometry& g, ControlKind kind)
    : kind_(kind), weights_(g.weights()) {
  const int nq = g.points_per_element(), dim = mesh.dim;
  const Eigen::Index E = mesh.num_elements();
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
  std::vector<Eigen::MatrixXd> dref(nq);
  Eigen::VectorXd N(nv);
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> dN(nv, dim);
  for (int q = 0; q < nq; ++q) {
    const Eigen::VectorXd xi = g.reference_points().row(q).transpose();
    shape_functions(linear, xi.data(), N.data(), dN.data());
    M_.row(q) = N.transpose();
    dref[q] = dN;
  }
  // Gradients of the P1/Q1 functions in X: dM/dX = dM/dξ (dX/dξ)^{-1}, the geometry being
  // interpolated by the element's vertices (exact for affine cells).
  dM_.resize(E);
  Eigen::MatrixXd Xv(nv, dim);
  for (Eigen::Index e = 0; e < E; ++e) {
    for (int a = 0; a < nv; ++a) Xv.row(a) = mesh.nodes.row(mesh.vertex_nodes[support_(e, a)]);
    dM_[e].resize(dim, nq * nv);
    for (int q = 0; q < nq; ++q) {
      const Eigen::MatrixXd J0 = Xv.transpose() * dref[q];
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
    for (Eigen::Index a = 0; a < support_.cols(); ++a) me[a] = m[support_(e, a)];
    mq.row(e) = (M_ * me).transpose();
  }
  return mq;
}

Eigen::VectorXd ControlSpace::from_quadrature(const Eigen::MatrixXd& v) const {
  Eigen::VectorXd g = Eigen::VectorXd::Zero(size_);
  for (Eigen::Index e = 0; e < support_.rows(); ++e) {
    const Eigen::VectorXd ge = M_.transpose() * v.row(e).transpose();
    for (Eigen::Index a = 0; a < support_.cols(); ++a) g[support_(e, a)] += ge[a];
  }
  return g;
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
  return control_at(mesh, ControlKind::kVertex, m, mesh.nodes);
}

}  // namespace softhd::fe
