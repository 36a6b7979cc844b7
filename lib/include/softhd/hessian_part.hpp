#pragma once
/// \file hessian_part.hpp
/// Which second derivative a Hessian-vector product applies: the exact one, or its
/// Gauss–Newton part. One name for the distance's product (docs/formulation.md §2.7), the state
/// equation's (§4.4.1) and the objective's.

#include <string>

namespace softhd {

/// The exact second derivative, or its Gauss–Newton part.
enum class HessianPart {
  /// The exact Hessian. For ρ̃ w.r.t. the moving points: volumes held fixed; for the reduced
  /// J(m): the state's second-order terms included.
  full,
  /// The Gauss–Newton part. For ρ̃: the positive semi-definite part H_GN (H = H_GN + a negative
  /// semi-definite rest); for the reduced J(m): the terms carrying the adjoint λ dropped, so
  /// the product is Sᵀ F_uu S (S = du/dm), positive semi-definite when F_uu is.
  gauss_newton,
};

/// "full" or "gauss_newton".
std::string to_string(HessianPart part);
/// The HessianPart named by to_string; throws InvalidArgument naming `what` for another name.
HessianPart hessian_part_from_string(const std::string& name,
                                     const std::string& what = "Hessian part");

}  // namespace softhd
