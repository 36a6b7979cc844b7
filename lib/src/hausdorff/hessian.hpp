#pragma once
// Hessian-vector products of ρ̃ w.r.t. the moving points (docs/formulation.md §2.7, internal):
// the state an evaluation keeps for them, and the product.

#include <Eigen/Core>

#include "pair_backend.hpp"
#include "pair_kernel.hpp"
#include "softhd/hausdorff.hpp"

namespace softhd {

/// What one evaluation at X leaves for H·v (HausdorffRequest::hessian_points). With
/// D = d̃ + ε, S the scaled kernel sum of a point at scale c = r_min + ε, ψ the cap:
/// per target y_j (side A) and per moving x_i (side B, empty for scan_to_body).
struct HausdorffHessian {
  const void* owner = nullptr;  ///< the HausdorffTarget::Impl that evaluated it
  Eigen::MatrixXd x;            ///< N by d: the moving points
  Eigen::VectorXd v;            ///< V_i/|X|
  DistanceForm form;            ///< sides, cap, visible mask
  detail::Mask differentiate;   ///< the request's mask (empty: all)
  HausdorffParams prm;
  double A = 0.0, B = 0.0, rho = 0.0, rho_A = 0.0, rho_B = 0.0;
  Eigen::VectorXd scale_y, S_y, D_y, a, psi_y;  ///< c_j, S_j, D_j, a_j = ∂A/∂d̃_j, ψ(d̃_j)
  Eigen::VectorXd scale_x, S_x, D_x, b, psi_x;  ///< c_i, S_i, D_i, b_i = ∂B/∂d̃_i, ψ(d̃_i)
  Eigen::MatrixXd n_x;  ///< N by d: n_i = G_i/S_i = ∇d̃_i/D_i (zero rows where masked)
};

namespace detail {

/// H·dir (or H_GN·dir) at the state `h`, targets Y with weights w_j = W_j/|Y|. Two
/// all-pairs passes, OpenMP over their outer points (static schedule: the same bits for
/// any thread count); `work` (optional) gets their counts.
Eigen::MatrixXd hessian_product(const HausdorffHessian& h, const Eigen::MatrixXd& Y,
                                const Eigen::VectorXd& w, const Eigen::MatrixXd& dir,
                                HessianPart part, int threads, SumWork* work);

}  // namespace detail
}  // namespace softhd
