// The pose of a scan (softhd/scan/pose.hpp): Rodrigues' exp and log against Eigen's
// AngleAxis, round trips through the matrix and the twist, refusals of a wrong 4×4.

#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <random>

#include "expect_error.hpp"
#include "softhd/scan/pose.hpp"

namespace softhd::scan {
namespace {

Eigen::Vector3d random_axis(std::mt19937_64& gen) {
  std::normal_distribution<double> n;
  return Eigen::Vector3d(n(gen), n(gen), n(gen)).normalized();
}

TEST(Pose, ExpMatchesAngleAxisFromTinyToNearPi) {
  std::mt19937_64 gen(7);
  for (double angle : {0.0, 1e-12, 1e-8, 1e-5, 9.9e-5, 1.01e-4, 1e-2, 0.5, 1.5, 3.0, M_PI - 1e-7}) {
    const Eigen::Vector3d axis = random_axis(gen);
    const Eigen::Matrix3d expected = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
    // Two evaluations of Rodrigues' formula, each entry (≤ 1) from about eight rounded
    // operations: they agree to a few ulps, 4 DBL_EPSILON, whichever products a compiler
    // fuses (clang's ASan build contracts to FMAs and differed by 5.0e-16 at π − 1e-7).
    EXPECT_LT((rotation_exp(angle * axis) - expected).cwiseAbs().maxCoeff(), 4 * DBL_EPSILON)
        << "angle " << angle;
  }
}

TEST(Pose, LogInvertsExpAcrossTheRange) {
  std::mt19937_64 gen(8);
  for (double angle :
       {0.0, 1e-12, 1e-8, 1e-5, 1.01e-4, 0.3, 1.5707, 1.5709, 2.5, 3.1, M_PI - 1e-9}) {
    const Eigen::Vector3d w = angle * random_axis(gen);
    const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, w.normalized()).toRotationMatrix();
    const Eigen::Vector3d back = rotation_log(R);
    // Near π the angle's conditioning costs √ε in the axis (R + Rᵀ loses the sign of sin θ).
    const double tol = angle > 3.0 ? 1e-7 : 2e-15 + 4e-16 * angle;
    EXPECT_LT((back - w).norm(), tol) << "angle " << angle;
    EXPECT_LT((rotation_exp(back) - R).cwiseAbs().maxCoeff(), 1e-15);
  }
}

TEST(Pose, LeftJacobianMatchesCentralDifferencesOfExp) {
  // exp([ω + hδ]×) exp([ω]×)ᵀ = exp([h J_l δ]×) + O(h²), so the central difference of
  // log(exp([ω ± hδ]×) exp([ω]×)ᵀ) is J_l δ + O(h²) (h = 1e-5: truncation ~1e-10, rounding
  // ~ε/h = 2e-11); both sides of the series switch at θ = 1e-4 are taken.
  std::mt19937_64 gen(9);
  const double h = 1e-5;
  for (double angle : {0.0, 1e-6, 9.9e-5, 1.01e-4, 0.3, 1.5, 2.8}) {
    const Eigen::Vector3d w = angle * random_axis(gen);
    const Eigen::Vector3d d = random_axis(gen);
    const Eigen::Matrix3d Et = rotation_exp(w).transpose();
    const Eigen::Vector3d fd =
        (rotation_log(rotation_exp(w + h * d) * Et) - rotation_log(rotation_exp(w - h * d) * Et)) /
        (2 * h);
    EXPECT_LT((rotation_left_jacobian(w) * d - fd).norm(), 1e-8) << "angle " << angle;
  }
}

TEST(Pose, MatrixAndTwistRoundTrips) {
  std::mt19937_64 gen(9);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (int k = 0; k < 20; ++k) {
    Eigen::Matrix<double, 7, 1> x;
    x.head<3>() = std::abs(u(gen)) * 1.5 * random_axis(gen);
    x.segment<3>(3) << u(gen), u(gen), u(gen);
    x[6] = 0.3 * u(gen);
    const Pose p = Pose::from_twist(x);
    EXPECT_LT((p.twist() - x).norm(), 1e-14);
    const Pose q = Pose::from_matrix(p.matrix());
    EXPECT_LT((q.matrix() - p.matrix()).cwiseAbs().maxCoeff(), 1e-14);
    // inverse and compose: p⁻¹ ∘ p is the identity, on points too
    const Pose id = compose(p.inverse(), p);
    EXPECT_LT((id.matrix() - Eigen::Matrix4d::Identity()).cwiseAbs().maxCoeff(), 1e-14);
    Eigen::MatrixXd y(2, 3);
    y << 1, 2, 3, -1, 0.5, 0.25;
    const Eigen::MatrixXd py = apply_points(p, y);
    for (int r = 0; r < 2; ++r) {
      const Eigen::Vector4d h(y(r, 0), y(r, 1), y(r, 2), 1.0);
      EXPECT_LT((py.row(r).transpose() - (p.matrix() * h).head<3>()).norm(), 1e-13);
    }
  }
}

TEST(Pose, ApplyScalesVolumesBySquareOrCube) {
  Pose p;
  p.s = 2.0;
  const PointCloud c(Eigen::MatrixXd::Ones(3, 3), Eigen::VectorXd::Constant(3, 1.5));
  EXPECT_DOUBLE_EQ(p.apply(c, true).volumes()[0], 6.0);
  EXPECT_DOUBLE_EQ(p.apply(c, false).volumes()[0], 12.0);
}

TEST(Pose, WrongMatrixRefusedNamingWhatIsWrong) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m(3, 1) = 0.5;
  test::expect_error<InvalidArgument>([&] { Pose::from_matrix(m); }, "entry (4, 2)");
  m = Eigen::Matrix4d::Identity();
  m(1, 2) = std::nan("");
  test::expect_error<InvalidArgument>([&] { Pose::from_matrix(m); }, "entry (2, 3) is not finite");
  m = Eigen::Matrix4d::Identity();
  m(0, 0) = -1.0;  // a reflection
  test::expect_error<InvalidArgument>([&] { Pose::from_matrix(m); }, "determinant");
  m = Eigen::Matrix4d::Identity();
  m(0, 1) = 0.1;  // a shear
  test::expect_error<InvalidArgument>([&] { Pose::from_matrix(m); }, "not a scaled rotation");
  m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() *= 3.0;  // a scaled rotation is fine
  EXPECT_NEAR(Pose::from_matrix(m).s, 3.0, 1e-15);
}

}  // namespace
}  // namespace softhd::scan
