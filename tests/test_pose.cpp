// The pose of a scan (softhd/scan/pose.hpp): Rodrigues' exp and log against Eigen's
// AngleAxis, round trips through the matrix and the twist, refusals of a wrong 4×4; the pose
// map of a twist (softhd/scan/pose_map.hpp) against its definition and central differences.

#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <random>

#include "expect_error.hpp"
#include "softhd/scan/pose.hpp"
#include "softhd/scan/pose_map.hpp"

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

// Q_ξ = T_ξ ∘ Q₀ applied to a point equals c + e^σ exp([ω]×)(Q₀(x) − c) + v, its definition.
TEST(PoseMap, AtIsTheTwistAboutTheCentreAfterTheStart) {
  const Pose q0 =
      Pose::from_twist((Eigen::Matrix<double, 7, 1>() << 0.3, -0.2, 0.9, 1, 2, 3, 0.1).finished());
  const Eigen::Vector3d c(0.5, -1.0, 2.0), x(1.0, 0.25, -0.5);
  const Eigen::VectorXd xi =
      (Eigen::VectorXd(7) << 0.2, 0.1, -0.4, 0.3, -0.2, 0.5, -0.3).finished();
  const PoseMap map(q0, c, PoseKind::similarity);
  const Eigen::Vector3d q0x = q0.s * q0.R * x + q0.t;
  const Eigen::Vector3d expected =
      c +
      std::exp(xi[6]) *
          Eigen::AngleAxisd(xi.head<3>().norm(), xi.head<3>().normalized()).toRotationMatrix() *
          (q0x - c) +
      xi.segment<3>(3);
  const Pose q = map.at(xi);
  EXPECT_LT((q.s * q.R * x + q.t - expected).norm(), 1e-14);
  EXPECT_LT((map.at(Eigen::VectorXd()).matrix() - q0.matrix()).norm(), 1e-15);  // ξ = 0: Q₀
}

// twist_of is at's inverse: ξ → at(ξ) → twist_of gives ξ back (to rounding), rigid and similarity.
TEST(PoseMap, TwistOfInvertsAt) {
  const Pose q0 =
      Pose::from_twist((Eigen::Matrix<double, 7, 1>() << 0.3, -0.2, 0.9, 1, 2, 3, 0.1).finished());
  const Eigen::Vector3d c(0.5, -1.0, 2.0);
  const Eigen::VectorXd xi =
      (Eigen::VectorXd(7) << 0.2, 0.1, -0.4, 0.3, -0.2, 0.5, -0.3).finished();
  const PoseMap similarity(q0, c, PoseKind::similarity);
  EXPECT_LT((similarity.twist_of(similarity.at(xi)) - xi).norm(), 1e-14);
  const PoseMap rigid(q0, c, PoseKind::rigid);
  const Eigen::VectorXd xr = xi.head(6);
  EXPECT_LT((rigid.twist_of(rigid.at(xr)) - xr).norm(), 1e-14);
  EXPECT_LT(rigid.twist_of(q0).norm(), 1e-15);  // the start: ξ = 0
}

// f(x') = Σ_i ½|x'_i − a_i|² at x' = Q_ξ(x): the twist gradient and the pull-back against
// central differences (second order: the error falls 100x when h falls 10x), rigid and similarity.
TEST(PoseMap, TwistGradientAndPullbackMatchCentralDifferences) {
  std::mt19937_64 gen(12);
  std::normal_distribution<double> n;
  Eigen::MatrixXd x(20, 3), a(20, 3);
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    x.data()[i] = n(gen);
    a.data()[i] = n(gen);
  }
  const auto f = [&](const PoseMap& m, const Eigen::VectorXd& xi, const Eigen::MatrixXd& pts) {
    return 0.5 * (apply_points(m.at(xi), pts) - a).squaredNorm();
  };
  for (PoseKind kind : {PoseKind::rigid, PoseKind::similarity}) {
    const Pose q0 = Pose::from_twist(
        (Eigen::Matrix<double, 7, 1>() << -0.4, 0.2, 0.3, 0.5, -1, 0.2, 0.05).finished());
    const PoseMap map(q0, Eigen::Vector3d(0.3, 0.1, -0.2), kind);
    const int nv = map.variables();
    ASSERT_EQ(nv, kind == PoseKind::rigid ? 6 : 7);
    Eigen::VectorXd xi(nv);
    for (int k = 0; k < nv; ++k) xi[k] = 0.3 * n(gen);
    const Eigen::MatrixXd moved = apply_points(map.at(xi), x);
    const Eigen::MatrixXd g = moved - a;  // ∂f/∂x'
    const Eigen::VectorXd gxi = map.twist_gradient(moved, g, xi);
    const Eigen::MatrixXd gx = map.pullback(g, xi);
    for (int k = 0; k < nv; ++k) {
      double err[2];
      for (int s = 0; s < 2; ++s) {
        const double h = s == 0 ? 1e-3 : 1e-4;
        Eigen::VectorXd e = Eigen::VectorXd::Zero(nv);
        e[k] = h;
        err[s] = std::fabs((f(map, xi + e, x) - f(map, xi - e, x)) / (2 * h) - gxi[k]);
      }
      EXPECT_LT(err[1], 0.02 * err[0] + 1e-9) << "twist variable " << k;
    }
    const double h = 1e-5;
    for (int c = 0; c < 3; ++c) {
      Eigen::MatrixXd e = Eigen::MatrixXd::Zero(20, 3);
      e(7, c) = h;
      const double fd = (f(map, xi, x + e) - f(map, xi, x - e)) / (2 * h);
      EXPECT_NEAR(fd, gx(7, c), 1e-7 * (1 + std::fabs(fd))) << "point 7, coordinate " << c;
    }
  }
  const PoseMap rigid(Pose(), Eigen::Vector3d::Zero(), PoseKind::rigid);
  test::expect_error<InvalidArgument>([&] { rigid.checked(Eigen::VectorXd::Zero(7)); },
                                      "pose twist has 7 values, expected 6");
  test::expect_error<InvalidArgument>(
      [&] { rigid.checked(Eigen::VectorXd::Constant(6, std::nan(""))); }, "not finite");
}

}  // namespace
}  // namespace softhd::scan
