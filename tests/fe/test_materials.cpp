#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <memory>
#include <random>

#include "softhd/error.hpp"
#include "softhd/fe/materials.hpp"

using namespace softhd::fe;

namespace {

struct Case {
  std::string name;
  std::shared_ptr<const Material> material;
  double m;  // active tension
  int dim;   // 2: plane strain (F33 = 1, in-plane components only)
};

std::vector<Case> cases() {
  auto mr = std::make_shared<MooneyRivlin>(1.0, 0.2, 3.0);
  auto ti = std::make_shared<TransverselyIsotropic>(1.0, 0.2, 3.0, 10.0,
                                                    Eigen::Vector3d(1, 1, 0) / std::sqrt(2.0));
  std::vector<Case> c;
  for (int dim : {2, 3}) {
    c.push_back({"MR", mr, 0.0, dim});
    c.push_back({"TI", ti, 0.0, dim});
    c.push_back({"MR+fiber", mr, -0.7, dim});
    c.push_back({"TI+fiber", ti, 0.4, dim});
  }
  return c;
}

const Eigen::Vector3d kFiber = Eigen::Vector3d(1.0, 0.3, 0.2).normalized();

// Random F = I + 0.3 R with det F > 0 (plane strain in 2D).
Eigen::Matrix3d random_F(std::mt19937& rng, int dim) {
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  Eigen::Matrix3d F;
  do {
    F.setIdentity();
    for (int i = 0; i < dim; ++i)
      for (int j = 0; j < dim; ++j) F(i, j) += 0.3 * U(rng);
  } while (F.determinant() < 0.3);
  return F;
}

Eigen::Vector3d fiber_for(int dim) {
  return dim == 3 ? kFiber : Eigen::Vector3d(kFiber[0], kFiber[1], 0).normalized();
}

double W(const Case& c, const Eigen::Matrix3d& F) {
  return evaluate_point(*c.material, fiber_for(c.dim), c.m, F, false).W;
}

class MaterialTest : public ::testing::TestWithParam<int> {};

}  // namespace

TEST(Materials, StressFreeAndZeroEnergyAtIdentity) {
  for (const Case& c : cases()) {
    const PointResponse r =
        evaluate_point(*c.material, fiber_for(c.dim), 0.0, Eigen::Matrix3d::Identity(), true);
    EXPECT_NEAR(r.W, 0.0, 1e-13) << c.name;
    EXPECT_NEAR(r.P.norm(), 0.0, 1e-13) << c.name;
  }
}

// P against central differences of W, C against central differences of P, with the
// observed order of the difference error checked (≈ 2 when halving the step).
TEST(Materials, StressAndTangentMatchFiniteDifferences) {
  std::mt19937 rng(42);
  for (const Case& c : cases()) {
    const int d = c.dim;
    for (int trial = 0; trial < 5; ++trial) {
      const Eigen::Matrix3d F = random_F(rng, d);
      const PointResponse r = evaluate_point(*c.material, fiber_for(d), c.m, F, true);
      auto fd_errors = [&](double h) {
        double eP = 0.0, eC = 0.0;
        for (int k = 0; k < d; ++k)
          for (int K = 0; K < d; ++K) {
            Eigen::Matrix3d Fp = F, Fm = F;
            Fp(k, K) += h;
            Fm(k, K) -= h;
            eP = std::max(eP, std::abs((W(c, Fp) - W(c, Fm)) / (2 * h) - r.P(k, K)));
            const Eigen::Matrix3d dP =
                (evaluate_point(*c.material, fiber_for(d), c.m, Fp, false).P -
                 evaluate_point(*c.material, fiber_for(d), c.m, Fm, false).P) /
                (2 * h);
            for (int i = 0; i < d; ++i)
              for (int I = 0; I < d; ++I)
                eC = std::max(eC, std::abs(dP(i, I) - r.C(i + 3 * I, k + 3 * K)));
          }
        return std::make_pair(eP, eC);
      };
      const auto [eP1, eC1] = fd_errors(1e-6);
      EXPECT_LT(eP1, 1e-7 * (1.0 + r.P.norm())) << c.name;
      EXPECT_LT(eC1, 1e-6 * (1.0 + r.C.norm())) << c.name;
      const auto [eP2, eC2] = fd_errors(2e-3);
      const auto [eP3, eC3] = fd_errors(1e-3);
      EXPECT_GT(std::log2(eP2 / eP3), 1.8) << c.name;
      EXPECT_GT(std::log2(eC2 / eC3), 1.8) << c.name;
      EXPECT_TRUE(r.C.isApprox(r.C.transpose(), 1e-12)) << c.name;
    }
  }
}

TEST(Materials, FrameInvariance) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-3.0, 3.0);
  for (const Case& c : cases()) {
    for (int trial = 0; trial < 5; ++trial) {
      const Eigen::Matrix3d F = random_F(rng, c.dim);
      Eigen::Matrix3d Q;
      if (c.dim == 2) {
        const double t = U(rng);
        Q << std::cos(t), -std::sin(t), 0, std::sin(t), std::cos(t), 0, 0, 0, 1;
      } else {
        Q = Eigen::AngleAxisd(U(rng), Eigen::Vector3d(U(rng), U(rng), U(rng)).normalized())
                .toRotationMatrix();
      }
      EXPECT_NEAR(W(c, Q * F), W(c, F), 1e-12 * (1.0 + std::abs(W(c, F)))) << c.name;
    }
  }
}

// At F = I the tangent is positive definite on symmetric δF (strains) and vanishes on
// skew δF (infinitesimal rotations, consistent with frame invariance and P(I) = 0).
TEST(Materials, TangentAtIdentityPositiveOnStrains) {
  for (const Case& c : cases()) {
    if (c.m != 0.0) continue;
    const Matrix9d C =
        evaluate_point(*c.material, fiber_for(c.dim), 0.0, Eigen::Matrix3d::Identity(), true).C;
    std::vector<Eigen::Matrix3d> sym, skew;
    for (int i = 0; i < c.dim; ++i)
      for (int j = i; j < c.dim; ++j) {
        Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
        S(i, j) = S(j, i) = 1.0;
        sym.push_back(S);
        if (i != j) {
          Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
          A(i, j) = 1.0;
          A(j, i) = -1.0;
          skew.push_back(A);
        }
      }
    const int n = static_cast<int>(sym.size());
    Eigen::MatrixXd G(n, n);
    for (int a = 0; a < n; ++a)
      for (int b = 0; b < n; ++b)
        G(a, b) = Eigen::Map<const Vector9d>(sym[a].data())
                      .dot(C * Eigen::Map<const Vector9d>(sym[b].data()));
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(G);
    EXPECT_GT(es.eigenvalues().minCoeff(), 0.1) << c.name;
    for (const auto& A : skew) {
      const Eigen::Map<const Vector9d> a(A.data());
      EXPECT_NEAR((C * a).norm(), 0.0, 1e-12) << c.name;
    }
  }
}

TEST(Materials, CrossProductGivesCofactor) {
  std::mt19937 rng(5);
  const Eigen::Matrix3d F = random_F(rng, 3);
  EXPECT_TRUE(cofactor(F).isApprox(F.determinant() * F.inverse().transpose(), 1e-13));
}

TEST(Materials, RejectInvalidCoefficients) {
  EXPECT_THROW(MooneyRivlin(0.0, 1.0, 1.0), softhd::InvalidArgument);
  EXPECT_THROW(MooneyRivlin(1.0, -1.0, 1.0), softhd::InvalidArgument);
  EXPECT_THROW(TransverselyIsotropic(1, 1, 1, 1, Eigen::Vector3d::Zero()), softhd::InvalidArgument);
}
