#include "softhd/fe/materials.hpp"

#include <Eigen/LU>
#include <cmath>

#include "softhd/error.hpp"

namespace softhd::fe {

namespace {

// vec(A)ᵀ (I ⊗ ffᵀ-type) vec(B) = (A f)·(B f): the 9 by 9 matrix kron(f fᵀ, I3).
Matrix9d directional_identity(const Eigen::Vector3d& f) {
  Matrix9d M = Matrix9d::Zero();
  for (int I = 0; I < 3; ++I)
    for (int L = 0; L < 3; ++L)
      for (int i = 0; i < 3; ++i) M(i + 3 * I, i + 3 * L) = f[I] * f[L];
  return M;
}

void require_positive(double v, const char* name, const char* model) {
  if (!(v > 0.0) || !std::isfinite(v)) {
    throw InvalidArgument(std::string(model) + ": coefficient " + name +
                          " must be finite and > 0, got " + std::to_string(v));
  }
}

}  // namespace

MooneyRivlin::MooneyRivlin(double a, double b, double c) : a_(a), b_(b), c_(c) {
  require_positive(a, "a", "Mooney-Rivlin");
  require_positive(b, "b", "Mooney-Rivlin");
  require_positive(c, "c", "Mooney-Rivlin");
}

EnergyDerivatives MooneyRivlin::evaluate(const Eigen::Matrix3d& F, const Eigen::Matrix3d& H,
                                         double J, bool second) const {
  // W = a|F|² + b|H|² + c(J − 1)² − 2(a + 2b) ln J − 3(a + b)
  EnergyDerivatives d;
  d.W = a_ * F.squaredNorm() + b_ * H.squaredNorm() + c_ * (J - 1.0) * (J - 1.0) -
        2.0 * (a_ + 2.0 * b_) * std::log(J) - 3.0 * (a_ + b_);
  d.W_F = 2.0 * a_ * F;
  d.W_H = 2.0 * b_ * H;
  d.W_J = 2.0 * c_ * (J - 1.0) - 2.0 * (a_ + 2.0 * b_) / J;
  if (second) {
    d.W_FF = 2.0 * a_ * Matrix9d::Identity();
    d.W_HH = 2.0 * b_ * Matrix9d::Identity();
    d.W_JJ = 2.0 * c_ + 2.0 * (a_ + 2.0 * b_) / (J * J);
  }
  return d;
}

double MooneyRivlin::W_JJJ(double J) const {
  // W_JJ = 2c + 2(a + 2b)/J²  ⇒  W_JJJ = −4(a + 2b)/J³
  return -4.0 * (a_ + 2.0 * b_) / (J * J * J);
}

TransverselyIsotropic::TransverselyIsotropic(double a, double b, double c, double d,
                                             const Eigen::Vector3d& f)
    : a_(a), b_(b), c_(c), d_(d) {
  require_positive(a, "a", "transversely isotropic");
  require_positive(b, "b", "transversely isotropic");
  require_positive(d, "d", "transversely isotropic");
  if (!(c >= 0.0) || !std::isfinite(c)) {
    throw InvalidArgument("transversely isotropic: coefficient c must be finite and >= 0");
  }
  const double n = f.norm();
  if (!(n > 0.0) || !std::isfinite(n)) {
    throw InvalidArgument("transversely isotropic: direction f must be finite and non-zero");
  }
  f_ = f / n;
}

EnergyDerivatives TransverselyIsotropic::evaluate(const Eigen::Matrix3d& F,
                                                  const Eigen::Matrix3d& H, double J,
                                                  bool second) const {
  // W = a|F|² + b|H|² + c(|Ff|² + |Hf|²) + d(J − 1)² − 2(a + 2b + c) ln J − 3(a + b + 2c/3)
  const Eigen::Vector3d Ff = F * f_, Hf = H * f_;
  EnergyDerivatives r;
  r.W = a_ * F.squaredNorm() + b_ * H.squaredNorm() + c_ * (Ff.squaredNorm() + Hf.squaredNorm()) +
        d_ * (J - 1.0) * (J - 1.0) - 2.0 * (a_ + 2.0 * b_ + c_) * std::log(J) -
        3.0 * (a_ + b_ + 2.0 * c_ / 3.0);
  r.W_F = 2.0 * a_ * F + 2.0 * c_ * Ff * f_.transpose();
  r.W_H = 2.0 * b_ * H + 2.0 * c_ * Hf * f_.transpose();
  r.W_J = 2.0 * d_ * (J - 1.0) - 2.0 * (a_ + 2.0 * b_ + c_) / J;
  if (second) {
    const Matrix9d Df = directional_identity(f_);
    r.W_FF = 2.0 * a_ * Matrix9d::Identity() + 2.0 * c_ * Df;
    r.W_HH = 2.0 * b_ * Matrix9d::Identity() + 2.0 * c_ * Df;
    r.W_JJ = 2.0 * d_ + 2.0 * (a_ + 2.0 * b_ + c_) / (J * J);
  }
  return r;
}

double TransverselyIsotropic::W_JJJ(double J) const {
  // W_JJ = 2d + 2(a + 2b + c)/J²  ⇒  W_JJJ = −4(a + 2b + c)/J³
  return -4.0 * (a_ + 2.0 * b_ + c_) / (J * J * J);
}

double fiber_energy(double m, const Eigen::Matrix3d& F, const Eigen::Vector3d& a0) {
  return -0.5 * m * (F * a0).squaredNorm();
}

Eigen::Matrix3d fiber_stress(double m, const Eigen::Matrix3d& F, const Eigen::Vector3d& a0) {
  return -m * (F * a0) * a0.transpose();
}

Matrix9d fiber_tangent(double m, const Eigen::Vector3d& a0) {
  return -m * directional_identity(a0);
}

PointResponse evaluate_point(const Material& material, const Eigen::Vector3d& a0, double m,
                             const Eigen::Matrix3d& F, bool with_tangent) {
  const Eigen::Matrix3d H = cofactor(F);
  const double J = F.determinant();
  const EnergyDerivatives d = material.evaluate(F, H, J, with_tangent);
  PointResponse r;
  r.W = d.W + fiber_energy(m, F, a0);
  r.P = first_piola(d, F, H) + fiber_stress(m, F, a0);
  if (with_tangent) r.C = tangent(d, F, H) + fiber_tangent(m, a0);
  return r;
}

}  // namespace softhd::fe
