#pragma once
/// \file kinematics.hpp
/// The tensor cross product and the map from W(F, H, J) derivatives to the first
/// Piola-Kirchhoff stress P and the tangent C (docs/formulation.md §3.4). Second-order tensors are
/// 3 by 3; fourth-order ones are 9 by 9 acting on vec(A) (column-major: entry (i, I)
/// at index i + 3 I), so that δF : C : ΔF = vec(δF)ᵀ C vec(ΔF).

#include <Eigen/Core>

namespace softhd::fe {

/// A fourth-order tensor acting on vec(A) (9 by 9).
using Matrix9d = Eigen::Matrix<double, 9, 9>;
/// vec(A) of a 3 by 3 tensor (column-major).
using Vector9d = Eigen::Matrix<double, 9, 1>;

/// (A ⨯ B)_iI = ε_ijk ε_IJK A_jJ B_kK.
Eigen::Matrix3d cross(const Eigen::Matrix3d& A, const Eigen::Matrix3d& B);

/// The symmetric 9 by 9 matrix E(A) with vec(δF)ᵀ E(A) vec(ΔF) = A : (δF ⨯ ΔF);
/// also vec(A ⨯ ΔF) = E(A) vec(ΔF).
Matrix9d cross_matrix(const Eigen::Matrix3d& A);

/// cof F = ½ F ⨯ F = J F^{-T}.
inline Eigen::Matrix3d cofactor(const Eigen::Matrix3d& F) { return 0.5 * cross(F, F); }

/// Derivatives of a stored energy written as W(F, H, J), with no mixed terms
/// (W_FH = W_FJ = W_HJ = 0, which holds for every softhd material).
struct EnergyDerivatives {
  double W = 0.0;                                 ///< the energy density
  Eigen::Matrix3d W_F = Eigen::Matrix3d::Zero();  ///< ∂W/∂F
  Eigen::Matrix3d W_H = Eigen::Matrix3d::Zero();  ///< ∂W/∂H
  double W_J = 0.0;                               ///< ∂W/∂J
  Matrix9d W_FF = Matrix9d::Zero();               ///< ∂²W/∂F² (if requested)
  Matrix9d W_HH = Matrix9d::Zero();               ///< ∂²W/∂H² (if requested)
  double W_JJ = 0.0;                              ///< ∂²W/∂J² (if requested)
};

/// P = W_F + W_H ⨯ F + W_J H.
Eigen::Matrix3d first_piola(const EnergyDerivatives& d, const Eigen::Matrix3d& F,
                            const Eigen::Matrix3d& H);

/// δF:C:ΔF = δF:W_FF:ΔF + (F⨯δF):W_HH:(F⨯ΔF) + W_JJ (H:δF)(H:ΔF)
///           + W_H:(δF⨯ΔF) + W_J F:(δF⨯ΔF).
Matrix9d tangent(const EnergyDerivatives& d, const Eigen::Matrix3d& F, const Eigen::Matrix3d& H);

}  // namespace softhd::fe
