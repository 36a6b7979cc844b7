#include "softhd/fe/kinematics.hpp"

namespace softhd::fe {

Eigen::Matrix3d cross(const Eigen::Matrix3d& A, const Eigen::Matrix3d& B) {
  // With (i, j, k) and (I, J, K) cyclic:
  // (A⨯B)_iI = A_jJ B_kK − A_jK B_kJ − A_kJ B_jK + A_kK B_jJ.
  Eigen::Matrix3d C;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    for (int I = 0; I < 3; ++I) {
      const int J = (I + 1) % 3, K = (I + 2) % 3;
      C(i, I) = A(j, J) * B(k, K) - A(j, K) * B(k, J) - A(k, J) * B(j, K) + A(k, K) * B(j, J);
    }
  }
  return C;
}

Matrix9d cross_matrix(const Eigen::Matrix3d& A) {
  // E(A)_(aA),(bB) = Σ_cC ε_cab ε_CAB A_cC: for each a ≠ b the only c is the third
  // index, with sign ε_cab.
  Matrix9d E = Matrix9d::Zero();
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      if (a == b) continue;
      const int c = 3 - a - b;
      const double sab = ((b - a + 3) % 3 == 1) ? 1.0 : -1.0;  // ε_cab = ε_abc
      for (int Aa = 0; Aa < 3; ++Aa)
        for (int Bb = 0; Bb < 3; ++Bb) {
          if (Aa == Bb) continue;
          const int Cc = 3 - Aa - Bb;
          const double sAB = ((Bb - Aa + 3) % 3 == 1) ? 1.0 : -1.0;
          E(a + 3 * Aa, b + 3 * Bb) = sab * sAB * A(c, Cc);
        }
    }
  return E;
}

Eigen::Matrix3d first_piola(const EnergyDerivatives& d, const Eigen::Matrix3d& F,
                            const Eigen::Matrix3d& H) {
  return d.W_F + cross(d.W_H, F) + d.W_J * H;
}

Matrix9d tangent(const EnergyDerivatives& d, const Eigen::Matrix3d& F, const Eigen::Matrix3d& H) {
  const Matrix9d X = cross_matrix(F);  // vec(F ⨯ δF) = X vec(δF)
  const Eigen::Map<const Vector9d> h(H.data());
  Matrix9d C = d.W_FF + X.transpose() * d.W_HH * X + d.W_JJ * h * h.transpose();
  C += cross_matrix(d.W_H + d.W_J * F);
  return C;
}

}  // namespace softhd::fe
