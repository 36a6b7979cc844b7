#pragma once
/// \file materials.hpp
/// Polyconvex stored energies W(F, H, J) (docs/formulation.md §3.2) and the active fiber term
/// W_m = −½ m |F a₀|². A material supplies W and its derivatives w.r.t. F, H, J;
/// kinematics.hpp turns them into P and C. Materials are immutable and safe to share
/// between threads.

#include <Eigen/Core>
#include <memory>
#include <string>

#include "softhd/fe/kinematics.hpp"

namespace softhd::fe {

/// A stored energy W(F, H, J) with W(I) = 0 and P(I) = 0.
class Material {
 public:
  virtual ~Material() = default;
  /// W and its first derivatives at (F, H = cof F, J = det F > 0); with `second`, also
  /// the second derivatives.
  virtual EnergyDerivatives evaluate(const Eigen::Matrix3d& F, const Eigen::Matrix3d& H, double J,
                                     bool second) const = 0;
  /// ∂³W/∂J³ at J > 0. Together with W_FF and W_HH independent of (F, H, J) (W quadratic in F
  /// and in H, as in every softhd material) it is all the third derivative of W(F) needs: the
  /// exact derivative of the tangent (fe/second_order.hpp, docs/formulation.md §4.4.1).
  virtual double W_JJJ(double J) const = 0;
  /// The coefficient a of |F|²: the active tension must satisfy m < 2a (docs/formulation.md §3.3).
  virtual double a() const = 0;
  /// A stiffness scale (for tolerances), e.g. a + b + c.
  virtual double stiffness_scale() const = 0;
};

/// W = a|F|² + b|H|² + c(J − 1)² − 2(a + 2b) ln J − 3(a + b), a, b, c > 0 (paper eq. 2.3).
class MooneyRivlin final : public Material {
 public:
  /// Throws InvalidArgument unless a, b, c > 0.
  MooneyRivlin(double a, double b, double c);
  EnergyDerivatives evaluate(const Eigen::Matrix3d& F, const Eigen::Matrix3d& H, double J,
                             bool second) const override;
  /// −4(a + 2b)/J³.
  double W_JJJ(double J) const override;
  double a() const override { return a_; }
  double stiffness_scale() const override { return a_ + b_ + c_; }

 private:
  double a_, b_, c_;
};

/// W = a|F|² + b|H|² + c(|Ff|² + |Hf|²) + d(J − 1)² − 2(a + 2b + c) ln J − 3(a + b + 2c/3)
/// with a unit direction f (paper eq. 6.2); a, b, d > 0, c >= 0.
class TransverselyIsotropic final : public Material {
 public:
  /// `f` is normalised; throws InvalidArgument if it is zero or a coefficient is invalid.
  TransverselyIsotropic(double a, double b, double c, double d, const Eigen::Vector3d& f);
  EnergyDerivatives evaluate(const Eigen::Matrix3d& F, const Eigen::Matrix3d& H, double J,
                             bool second) const override;
  /// −4(a + 2b + c)/J³.
  double W_JJJ(double J) const override;
  double a() const override { return a_; }
  double stiffness_scale() const override { return a_ + b_ + c_ + d_; }

 private:
  double a_, b_, c_, d_;
  Eigen::Vector3d f_;
};

/// Energy density, stress and tangent at one point: the material plus the fiber term.
struct PointResponse {
  double W = 0.0;                               ///< W(F) + W_m(F)
  Eigen::Matrix3d P = Eigen::Matrix3d::Zero();  ///< ∂W/∂F
  Matrix9d C = Matrix9d::Zero();                ///< ∂²W/∂F² (only if requested)
};

/// W_m = −½ m |F a₀|².
double fiber_energy(double m, const Eigen::Matrix3d& F, const Eigen::Vector3d& a0);
/// ∂W_m/∂F = −m (F a₀) ⊗ a₀.
Eigen::Matrix3d fiber_stress(double m, const Eigen::Matrix3d& F, const Eigen::Vector3d& a0);
/// δF : ∂²W_m/∂F² : ΔF = −m (δF a₀)·(ΔF a₀).
Matrix9d fiber_tangent(double m, const Eigen::Vector3d& a0);

/// W, P (and C if `tangent`) of material + fiber term at F with det F > 0.
PointResponse evaluate_point(const Material& material, const Eigen::Vector3d& a0, double m,
                             const Eigen::Matrix3d& F, bool with_tangent);

}  // namespace softhd::fe
