#pragma once
/// \file assembly.hpp
/// Energy Π(u; m) = ∫ W(F) + W_m(F) dX, residual R = ∫ P ∇N dX and tangent
/// K = ∫ ∇N C ∇N dX on the free dofs (docs/formulation.md §3.5), assembled in parallel with OpenMP.
///
/// Determinism: elements are coloured so that no two elements of one colour share a
/// node; colours are processed in a fixed order and each nonzero receives its element
/// contributions in the same order whatever the number of threads, so the results are
/// bitwise identical for 1 and N threads. The sparsity pattern of K (lower triangle,
/// free dofs) and the element-to-nonzero maps are built once in the constructor.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <vector>

#include "softhd/fe/dofs.hpp"
#include "softhd/fe/geometry.hpp"
#include "softhd/fe/materials.hpp"
#include "softhd/fe/mesh.hpp"

namespace softhd::fe {

/// Column-major sparse matrix; tangents store only the lower triangle.
using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

/// Everything that defines the discrete state problem except the control.
class Assembler {
 public:
  /// `a0` is the fiber direction (normalised here; in 2D its third component must be 0).
  /// Throws InvalidArgument on inconsistent input.
  Assembler(Mesh mesh, std::shared_ptr<const Material> material, const Eigen::Vector3d& a0,
            const std::vector<DirichletConstraint>& constraints);

  /// The mesh.
  const Mesh& mesh() const { return mesh_; }
  /// Its quadrature data.
  const ReferenceGeometry& geometry() const { return geometry_; }
  /// The numbering of the free dofs.
  const DofMap& dofs() const { return dofs_; }
  /// The stored energy.
  const Material& material() const { return *material_; }
  /// The unit fiber direction a₀.
  const Eigen::Vector3d& fiber() const { return a0_; }
  /// Number of element colours (for reports).
  int num_colours() const { return static_cast<int>(colours_.size()); }

  /// An all-zero tangent with the fixed sparsity pattern (free by free, lower triangle).
  SparseMatrix tangent_pattern() const;

  /// Evaluates at the full displacement `u` (num_dofs; fixed entries ignored) and the
  /// control at the quadrature points `m_qp` (E by nq). Any output may be null (skipped).
  /// `residual` gets num_free entries; `tangent` must come from tangent_pattern().
  /// Returns false, with *energy = +inf and other outputs unspecified, if det F <= 0 at
  /// some quadrature point.
  bool evaluate(const Eigen::VectorXd& u, const Eigen::MatrixXd& m_qp, double* energy,
                Eigen::VectorXd* residual, SparseMatrix* tangent) const;

  /// Smallest det F over all quadrature points.
  double min_jacobian(const Eigen::VectorXd& u) const;
  /// ∫ J dX: the deformed volume (area per unit thickness in 2D).
  double deformed_volume(const Eigen::VectorXd& u) const;
  /// det F at every quadrature point, E by nq.
  Eigen::MatrixXd jacobians(const Eigen::VectorXd& u) const;
  /// w_q det J0 (F a₀)·(∇λ a₀) at every quadrature point (E by nq), ∇λ = Σ_a λ_a ⊗ ∇N_a:
  /// the integrand of the adjoint control gradient (docs/formulation.md §4.4).
  Eigen::MatrixXd fiber_sensitivity(const Eigen::VectorXd& u, const Eigen::VectorXd& lambda) const;

  /// Deformation gradient (3 by 3, plane strain in 2D) at point q of element e.
  Eigen::Matrix3d deformation_gradient(const Eigen::VectorXd& u, Eigen::Index e, int q) const;

 private:
  Mesh mesh_;
  ReferenceGeometry geometry_;
  std::shared_ptr<const Material> material_;
  Eigen::Vector3d a0_;
  DofMap dofs_;
  SparseMatrix pattern_;
  /// Element colours: lists of element ids.
  std::vector<std::vector<int>> colours_;
  /// Per element, (ndof_e)² entries: index into the tangent's values or -1.
  std::vector<std::vector<int>> nz_map_;
};

}  // namespace softhd::fe
