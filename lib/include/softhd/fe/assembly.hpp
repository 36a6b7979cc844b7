#pragma once
/// \file assembly.hpp
/// Energy Π(u; m) = ∫ W(F) + W_m(F) dX, residual R = ∫ P ∇N dX and tangent
/// K = ∫ ∇N C ∇N dX on the free dofs (docs/formulation.md §3.5), assembled in parallel with OpenMP.
///
/// Determinism: element energies, residuals and matrices are computed in parallel into
/// per-element buffers (passes of a fixed number of elements) and added to the global
/// vectors serially in element order, so the results are bitwise identical for any
/// number of threads. The sparsity pattern of K (lower triangle,
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
  struct ElementWork;
  /// Π_e, r_e (nd) and K_e (nd by nd, row-major, local dof a·dim + i) of element e; null
  /// outputs are skipped. Returns false if det F <= 0 at one of its points.
  bool element_kernel(const Eigen::VectorXd& u, const Eigen::MatrixXd& m_qp, Eigen::Index e,
                      double* energy, double* residual, double* tangent, ElementWork& work) const;

  Mesh mesh_;
  ReferenceGeometry geometry_;
  std::shared_ptr<const Material> material_;
  Eigen::Vector3d a0_;
  DofMap dofs_;
  SparseMatrix pattern_;
  /// Per element, (ndof_e)² entries: index into the tangent's values or -1.
  std::vector<std::vector<int>> nz_map_;
};

}  // namespace softhd::fe
