#include "softhd/fe/locator.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <nanoflann.hpp>
#include <vector>

#include "../common/matrix_rows.hpp"

namespace softhd::fe {

namespace {

// nanoflann's dataset adaptor over the element centres (E by dim, read in place).
using Centres = softhd::detail::MatrixRows;
using CentreTree = softhd::detail::MatrixRowsTree<>;

using CellsWithinRadius = softhd::detail::WithinRadius<int>;

constexpr double kTol = 1e-10;  // relative to the mesh's size (X) or the cell (ξ)

}  // namespace

// Element bounding boxes (inflated: a curved quadratic edge may leave its nodes' box) and a
// k-d tree over their centres; a point can only lie in elements whose centre is within the
// largest half-diagonal.
struct PointLocator::Tree {
  explicit Tree(const Mesh& mesh);
  Eigen::MatrixXd centres, lo, hi;  // E by dim
  double radius = 0.0, tol = 0.0;
  Centres adaptor;
  CentreTree index;
};

PointLocator::Tree::Tree(const Mesh& mesh)
    : centres(mesh.num_elements(), mesh.dim),
      lo(mesh.num_elements(), mesh.dim),
      hi(mesh.num_elements(), mesh.dim),
      adaptor{&centres},
      index(mesh.dim, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16)) {
  const Eigen::RowVectorXd size = mesh.nodes.colwise().maxCoeff() - mesh.nodes.colwise().minCoeff();
  tol = kTol * size.maxCoeff();
  for (Eigen::Index e = 0; e < mesh.num_elements(); ++e) {
    Eigen::RowVectorXd a = mesh.nodes.row(mesh.elements(e, 0)), b = a;
    for (int k = 1; k < mesh.nodes_per_element(); ++k) {
      a = a.cwiseMin(mesh.nodes.row(mesh.elements(e, k)));
      b = b.cwiseMax(mesh.nodes.row(mesh.elements(e, k)));
    }
    const Eigen::RowVectorXd pad = Eigen::RowVectorXd::Constant(
        mesh.dim, (mesh.order > 1 ? 0.25 * (b - a).maxCoeff() : 0.0) + tol);
    lo.row(e) = a - pad;
    hi.row(e) = b + pad;
    centres.row(e) = 0.5 * (lo.row(e) + hi.row(e));
    radius = std::max(radius, 0.5 * (hi.row(e) - lo.row(e)).norm());
  }
  index.buildIndex();
}

namespace {

// Newton on X(ξ) = Σ_a X_a N_a(ξ) = X from the cell's centroid: ξ ← ξ − (dX/dξ)⁻¹ (X(ξ) − X).
// True if it converged (|Δξ| < 1e-14) to a point of the reference cell within kTol.
bool invert(const Mesh& mesh, Eigen::Index e, const Eigen::VectorXd& X, double* xi) {
  const ReferenceElement& r = reference_element(mesh.cell);
  const int dim = mesh.dim;
  double N[27], dN[81];
  for (int k = 0; k < dim; ++k) xi[k] = r.simplex ? 1.0 / (dim + 1) : 0.0;
  for (int it = 0; it < 50; ++it) {
    shape_functions(mesh.cell, xi, N, dN);
    Eigen::Vector3d f = Eigen::Vector3d::Zero();
    Eigen::Matrix3d J = Eigen::Matrix3d::Identity();  // identity beyond dim
    J.topLeftCorner(dim, dim).setZero();
    for (int k = 0; k < dim; ++k) f[k] = -X[k];
    for (int a = 0; a < r.nodes; ++a) {
      const auto Xa = mesh.nodes.row(mesh.elements(e, a));
      for (int i = 0; i < dim; ++i) {
        f[i] += N[a] * Xa[i];
        for (int K = 0; K < dim; ++K) J(i, K) += Xa[i] * dN[a * dim + K];
      }
    }
    const Eigen::Vector3d step = J.partialPivLu().solve(f);
    double len = 0.0;
    for (int k = 0; k < dim; ++k) {
      xi[k] -= step[k];
      len = std::max(len, std::abs(step[k]));
    }
    if (!std::isfinite(len) || len > 1e3) return false;  // far outside: not this element
    if (len < 1e-14) break;
  }
  return inside_reference_cell(mesh.cell, xi, kTol);
}

}  // namespace

PointLocator::PointLocator(const Mesh& mesh) : mesh_(&mesh) {
  if (!mesh.structured()) tree_ = std::make_unique<Tree>(mesh);
}
PointLocator::~PointLocator() = default;
PointLocator::PointLocator(PointLocator&&) noexcept = default;
PointLocator& PointLocator::operator=(PointLocator&&) noexcept = default;

int PointLocator::locate(const Eigen::VectorXd& X, Eigen::VectorXd* xi) const {
  const Mesh& mesh = *mesh_;
  if (!tree_) return fe::locate(mesh, X, xi);
  if (X.size() != mesh.dim || !X.allFinite()) return -1;
  std::vector<int> candidates;
  CellsWithinRadius within{tree_->radius * tree_->radius, &candidates};
  tree_->index.radiusSearchCustomCallback(X.data(), within);
  std::sort(candidates.begin(), candidates.end());  // the lowest element wins on shared faces
  xi->resize(mesh.dim);
  for (int e : candidates) {
    if ((X.transpose().array() < tree_->lo.row(e).array()).any() ||
        (X.transpose().array() > tree_->hi.row(e).array()).any())
      continue;
    if (invert(mesh, e, X, xi->data())) return e;
  }
  return -1;
}

}  // namespace softhd::fe
