#pragma once
/// \file assembly.hpp
/// Energy Π(u; m) = ∫ W(F) + W_m(F) dX, residual R = ∫ P ∇N dX and tangent
/// K = ∫ ∇N C ∇N dX on the free dofs (docs/formulation.md §3.5), assembled in parallel with OpenMP.
///
/// Determinism: element energies, residuals and matrices are computed in parallel into
/// per-element buffers (passes of a fixed number of elements) and added to the global
/// vectors serially in element order, so the results are bitwise identical for any
/// number of threads. The sparsity pattern of K (lower triangle,
/// free dofs) and the element-to-nonzero maps are built once in the constructor, unless
/// the assembler is lean (AssemblerStorage::kLean: element tangents go to a sink).

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

/// What an Assembler keeps in memory.
enum class AssemblerStorage {
  /// The sparsity pattern and element-to-nonzero maps of a SparseMatrix tangent, and dN/dX
  /// at every quadrature point (the serial solvers).
  kFull,
  /// Neither: tangents go to an ElementMatrixSink (e.g. a distributed matrix) and dN/dX is
  /// recomputed at every point (GradientStorage::kOnDemand). On Q2 hexahedra that saves
  /// about 3 KB per free dof (pattern 1.2, element maps 1.1, gradients 0.7) for a few
  /// hundred flops more per quadrature point.
  kLean,
};

/// Receives element tangents from Assembler::evaluate_elements, a pass of consecutive elements at a
/// time (one call per pass, never per element), serially and in element order.
class ElementMatrixSink {
 public:
  virtual ~ElementMatrixSink() = default;
  /// K_e of the elements first .. first + count - 1: element first + i at Ke + i nd², nd by
  /// nd row-major with local dof a·dim + k (nd = nodes per element times dim; both
  /// triangles, exactly symmetric). Entries of fixed dofs are included.
  virtual void add(Eigen::Index first, Eigen::Index count, const double* Ke) = 0;
};

/// Fibre directions a₀ of a body: one for all, or a field per element or per node
/// (interpolated to the quadrature points as axes, see aligned_fibers, and normalised there).
struct FiberField {
  /// Where the directions live.
  enum class Kind {
    kUniform,  ///< one direction for the whole body
    kElement,  ///< one per element
    kNode,     ///< one per node, interpolated
  };
  Kind kind = Kind::kUniform;  ///< where `values` live
  /// 3 by 1 (uniform), 3 by E (per element) or 3 by N (per node); non-zero columns.
  Eigen::Matrix3Xd values = Eigen::Vector3d::UnitX();
};

/// The fibre directions a_b (columns) turned to one axis: a_b s_b with s_b = ±1 the sign of
/// a_b · r, r the dominant eigenvector of Σ_b a_b a_bᵀ / |a_b|² (+1 on a tie; zero columns
/// are left). The fibre term depends on a₀ ⊗ a₀ only, so a_b and −a_b are the same fibre;
/// fields are interpolated or averaged after this, so opposite vectors never cancel.
Eigen::Matrix3Xd aligned_fibers(const Eigen::Matrix3Xd& a);

/// Everything that defines the discrete state problem except the control.
class Assembler {
 public:
  /// `a0` is the fiber direction (normalised here; in 2D its third component must be 0).
  /// Throws InvalidArgument on inconsistent input. With AssemblerStorage::kLean no sparsity
  /// pattern is built (tangent_pattern() and the SparseMatrix evaluate() throw); tangents
  /// then go to an ElementMatrixSink through evaluate_elements().
  Assembler(Mesh mesh, std::shared_ptr<const Material> material, const Eigen::Vector3d& a0,
            const std::vector<DirichletConstraint>& constraints,
            AssemblerStorage storage = AssemblerStorage::kFull);
  /// A body of several parts: `materials[r]` on the elements of region r
  /// (mesh.element_region; one entry per mesh.region_names), and a fibre field. Throws
  /// InvalidArgument on a missing material, a field of the wrong size, or a fibre that is
  /// zero or (in 2D) out of the plane at a quadrature point.
  /// `quadrature_degree` 0 takes the cell type's default (ReferenceGeometry).
  Assembler(Mesh mesh, std::vector<std::shared_ptr<const Material>> materials,
            const FiberField& fibers, const std::vector<DirichletConstraint>& constraints,
            AssemblerStorage storage = AssemblerStorage::kFull, int quadrature_degree = 0);

  /// The mesh.
  const Mesh& mesh() const { return mesh_; }
  /// Its quadrature data.
  const ReferenceGeometry& geometry() const { return geometry_; }
  /// The numbering of the free dofs.
  const DofMap& dofs() const { return dofs_; }
  /// The stored energy of region 0 (of the whole body when it has one material).
  const Material& material() const { return *materials_[0]; }
  /// The stored energy of region r.
  const Material& material(int region) const { return *materials_[region]; }
  /// The number of materials (one per region).
  int num_materials() const { return static_cast<int>(materials_.size()); }
  /// The largest stiffness_scale() of the materials.
  double stiffness_scale() const;
  /// The unit fiber direction a₀ at quadrature point q of element e.
  Eigen::Vector3d fiber(Eigen::Index e, int q) const {
    return fibers_.cols() == 1
               ? Eigen::Vector3d(fibers_.col(0))
               : Eigen::Vector3d(fibers_.col(e * geometry_.points_per_element() + q));
  }

  /// An all-zero tangent with the fixed sparsity pattern (free by free, lower triangle).
  SparseMatrix tangent_pattern() const;

  /// Evaluates at the full displacement `u` (num_dofs; fixed entries ignored) and the
  /// control at the quadrature points `m_qp` (E by nq). Any output may be null (skipped).
  /// `residual` gets num_free entries; `tangent` must come from tangent_pattern().
  /// Returns false, with *energy = +inf and other outputs unspecified, if det F <= 0 at
  /// some quadrature point.
  bool evaluate(const Eigen::VectorXd& u, const Eigen::MatrixXd& m_qp, double* energy,
                Eigen::VectorXd* residual, SparseMatrix* tangent) const;
  /// evaluate() with the element tangents handed to `tangent` (may be null) instead of
  /// assembled here (any AssemblerStorage); passes containing an element with det F <= 0 are
  /// not handed over.
  bool evaluate_elements(const Eigen::VectorXd& u, const Eigen::MatrixXd& m_qp, double* energy,
                         Eigen::VectorXd* residual, ElementMatrixSink* tangent) const;

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
  /// The pass loop of evaluate(): `add_pass(first, count, Ke, ok)` adds a pass's element
  /// tangents (called when want_tangent; ok[i] == 0 marks an element with det F <= 0).
  template <class AddPass>
  bool evaluate_passes(const Eigen::VectorXd& u, const Eigen::MatrixXd& m_qp, double* energy,
                       Eigen::VectorXd* residual, bool want_tangent, AddPass&& add_pass) const;
  /// Π_e, r_e (nd) and K_e (nd by nd, row-major, local dof a·dim + i) of element e; null
  /// outputs are skipped. Returns false if det F <= 0 at one of its points.
  /// kStored: dN/dX read from the geometry (kFull), else recomputed (kLean).
  template <bool kStored>
  bool element_kernel(const Eigen::VectorXd& u, const Eigen::MatrixXd& m_qp, Eigen::Index e,
                      double* energy, double* residual, double* tangent, ElementWork& work) const;

  Mesh mesh_;
  AssemblerStorage storage_;
  ReferenceGeometry geometry_;
  std::vector<std::shared_ptr<const Material>> materials_;  ///< per region
  Eigen::Matrix3Xd fibers_;  ///< unit a₀: one column, or one per quadrature point (e nq + q)
  /// Sets fibers_ from `field`; throws InvalidArgument.
  void set_fibers(const FiberField& field);
  DofMap dofs_;
  SparseMatrix pattern_;
  /// Per element, (ndof_e)² entries: index into the tangent's values or -1.
  std::vector<std::vector<int>> nz_map_;
};

}  // namespace softhd::fe
