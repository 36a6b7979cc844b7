#pragma once
// The shape objective's distance with quadrature cells (internal; docs/formulation.md §2.8, "The
// cell quadrature in the objective"): ρ̃ of the body deformed by u against the target's cells,
//
//     ρ̃ = ((A² + B²)/2)^(1/2),  A^4 over the target's cells against the body,
//                               B^4 over the body's cells against the target,
//
// or, against a scan's surface (points with surface weights; the form scan_to_body), ρ̃ = A with
// A^4 = (1/W) Σ_j w_j d̃_X(y_j)^4 against the body's continuum J (directed_point_mean); with a
// pose Q (the body's frame → the scan's, rigid; docs/formulation.md §8.11) the body moved by Q,
// that is the scan's points pulled back by Q⁻¹ (J and |Ω_X| do not change under a rigid motion):
// d̃_{Q(X)}(y_j) = d̃_X(Q⁻¹ y_j),
//
// and dρ̃/du = mapᵀ ∂ρ̃/∂(hexahedron points) (node-major), the body's hexahedra being
// points = map · (X + u) (fe::hex_decomposition). The body's decomposition and the target's
// hexahedra, boundary, J, signed distance and volume are built once; the body's J and signed
// distance at every evaluation (its boundary moves).

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "../fe/hex_decomposition.hpp"
#include "../hausdorff/cell_distance.hpp"
#include "softhd/fe/mesh.hpp"
#include "softhd/scan/pose.hpp"

namespace softhd::detail {

/// ρ̃ of a body's mesh deformed by u against a fixed target mesh, both 3D (any cell type).
class CellForm {
 public:
  /// `body` must outlive the form; `target` has its nodes where the target is. Throws
  /// InvalidArgument for a 2D mesh or invalid options.
  CellForm(const fe::Mesh& body, const fe::Mesh& target, const CellDistanceOptions& options);
  /// Against a scan's surface: `points` (M by 3) with their surface weights (M, sum > 0); ρ̃ = A
  /// (scan → body). Throws InvalidArgument for a 2D body, mismatched sizes or invalid options.
  CellForm(const fe::Mesh& body, const Eigen::MatrixXd& points, const Eigen::VectorXd& weights,
           const CellDistanceOptions& options);
  ~CellForm();

  /// ρ̃ (and its directed means) of the body at X + u (u node-major, num_nodes × 3 values);
  /// with grad, dρ̃/du into *grad (node-major).
  CellRho evaluate(const Eigen::VectorXd& u, Eigen::VectorXd* grad = nullptr) const;

  /// The body at X + u (its hexahedra, boundary and J), built once and held for several poses
  /// of the scan (the projection's inner minimisation, docs/formulation.md §8.11).
  struct Deformed;
  std::shared_ptr<const Deformed> deform(const Eigen::VectorXd& u) const;
  /// Against a scan's surface with the body moved by the pose Q (its frame → the scan's, rigid):
  /// ρ̃ = A of Q(X + u) against the scan, and with `twist` ∂ρ̃/∂δ of the twist δ = (ω, v) about
  /// `centre` (the pose T_δ ∘ Q, scan::PoseMap) at δ = 0, as scan::pose_distance:
  ///   ∂ρ̃/∂v = −Σ_j k_j,  ∂ρ̃/∂ω = −Σ_j (y_j − c) × k_j,  k_j = R ∂ρ̃/∂z_j,  z_j = Q⁻¹ y_j
  /// (moving the body by T_δ is moving the scan by T_δ⁻¹). InvalidArgument unless surface() or
  /// for a Q that is not rigid (naming `pose`).
  double posed_rho(const Deformed& d, const scan::Pose& Q, const Eigen::Vector3d& centre,
                   Eigen::VectorXd* twist) const;
  /// evaluate() against a scan's surface with the body moved by Q (as posed_rho): ρ̃, and dρ̃/du
  /// in the body's frame (node-major) into *grad.
  CellRho evaluate(const Eigen::VectorXd& u, const scan::Pose& Q,
                   Eigen::VectorXd* grad = nullptr) const;

  /// Per-point fields of the continuum distance (docs/formulation.md §2.8):
  /// d̃ = (J/|Ω|)^(−1/4) − ε at `moving` (N by 3) against the target's J (empty against a scan's
  /// surface, which bounds no volume), and at `target_points` (M by 3) against the body's at
  /// X + u; with ρ̃, A, B of evaluate().
  struct Fields {
    CellRho rho;
    Eigen::VectorXd moving, target;
  };
  Fields fields(const Eigen::VectorXd& u, const Eigen::MatrixXd& moving,
                const Eigen::MatrixXd& target_points) const;

  /// ρ̃ of the target's cells against themselves (the self floor); InvalidArgument against a
  /// scan's surface (it has no cells: no self floor).
  double self_rho() const;
  /// True against a scan's surface (the second constructor).
  bool surface() const { return scan_points_.rows() > 0; }
  const HexCells& target() const { return target_; }
  long body_hexahedra() const { return static_cast<long>(body_cells_.cells.rows()); }

 private:
  Deformed deformed(const Eigen::VectorXd& u) const;
  CellRho rho(const Deformed& d, Eigen::VectorXd* grad) const;
  CellRho scan_rho(const Deformed& d, const Eigen::MatrixXd& points, Eigen::VectorXd* grad) const;
  Eigen::MatrixXd pulled(const scan::Pose& Q) const;  // the scan's points moved by Q⁻¹

  const fe::Mesh& body_;
  fe::HexDecomposition body_cells_;
  CellDistanceOptions options_;
  HexCells target_;
  std::unique_ptr<BodyIntegral> target_j_;
  std::unique_ptr<SurfaceDistance> target_sd_;
  double target_volume_ = 0.0;
  Eigen::MatrixXd scan_points_;   // against a scan's surface: its points, ordered by place
  Eigen::VectorXd scan_weights_;  // and their surface weights
};

}  // namespace softhd::detail
