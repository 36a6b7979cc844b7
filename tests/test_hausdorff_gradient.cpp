// Gradients of ρ̃ (docs/formulation.md §2.4) against finite differences: central differences per
// coordinate and a Taylor test whose remainder must fall as h² (observed order ≥ 1.9).

#include <gtest/gtest.h>

#include <functional>

#include "hausdorff_reference.hpp"
#include "softhd/hausdorff.hpp"

namespace softhd::test {
namespace {

enum class Variable { points, volumes, target };

struct Case {
  int dim;
  Variable var;
  HausdorffParams prm;
};

// ρ̃ as a function of the flattened variable, and the library's gradient of it.
struct Problem {
  PointCloud X, Y;
  Variable var;
  HausdorffParams prm;

  Eigen::VectorXd flat() const {
    if (var == Variable::volumes) return X.volumes();
    const Eigen::MatrixXd& P = var == Variable::points ? X.points() : Y.points();
    return Eigen::Map<const Eigen::VectorXd>(P.data(), P.size());
  }
  std::pair<PointCloud, PointCloud> clouds(const Eigen::VectorXd& z) const {
    if (var == Variable::volumes) return {PointCloud(X.points(), z), Y};
    const Eigen::MatrixXd& P = var == Variable::points ? X.points() : Y.points();
    Eigen::MatrixXd Q = Eigen::Map<const Eigen::MatrixXd>(z.data(), P.rows(), P.cols());
    if (var == Variable::points) return {PointCloud(Q, X.volumes()), Y};
    return {X, PointCloud(Q, Y.volumes())};
  }
  double value(const Eigen::VectorXd& z) const {
    HausdorffOptions o;
    o.params = prm;
    auto [x, y] = clouds(z);
    return hausdorff(x, y, o).rho;
  }
  Eigen::VectorXd gradient() const {
    HausdorffOptions o;
    o.params = prm;
    HausdorffRequest req;
    req.gradient_points = var == Variable::points;
    req.gradient_volumes = var == Variable::volumes;
    req.gradient_target = var == Variable::target;
    const HausdorffResult r = hausdorff(X, Y, o, req);
    if (var == Variable::volumes) return r.gradient_volumes;
    const Eigen::MatrixXd& G = var == Variable::points ? r.gradient_points : r.gradient_target;
    return Eigen::Map<const Eigen::VectorXd>(G.data(), G.size());
  }
};

Problem make_problem(const Case& c) {
  // Clouds of different sizes, overlapping: every regime of the kernel is visited.
  return Problem{random_cloud(23, c.dim, 11 + c.dim, 0.0, 1.0),
                 random_cloud(31, c.dim, 97 + c.dim, 0.2, 1.3), c.var, c.prm};
}

void PrintTo(const Case& c, std::ostream* os) {
  *os << c.dim << "D variable " << static_cast<int>(c.var) << " alpha " << c.prm.alpha;
}

class GradientTest : public ::testing::TestWithParam<Case> {};

TEST_P(GradientTest, MatchesCentralDifferences) {
  const Problem p = make_problem(GetParam());
  const Eigen::VectorXd z = p.flat();
  const Eigen::VectorXd g = p.gradient();
  ASSERT_EQ(g.size(), z.size());
  ASSERT_TRUE(g.allFinite());
  const double h = 1e-6;
  for (Eigen::Index k = 0; k < z.size(); ++k) {
    Eigen::VectorXd zp = z, zm = z;
    zp[k] += h;
    zm[k] -= h;
    const double fd = (p.value(zp) - p.value(zm)) / (2 * h);
    EXPECT_NEAR(g[k], fd, 1e-6 * g.cwiseAbs().maxCoeff()) << "component " << k;
  }
}

TEST_P(GradientTest, TaylorRemainderIsSecondOrder) {
  const Problem p = make_problem(GetParam());
  const Eigen::VectorXd z = p.flat();
  const Eigen::VectorXd g = p.gradient();
  Eigen::VectorXd dir = random_cloud(static_cast<int>(z.size()), 2, 5).points().col(0);
  dir.array() -= 0.5;
  const double f0 = p.value(z), slope = g.dot(dir);
  std::vector<double> remainder;
  for (double h = 1e-2; h > 1e-4; h /= 2)
    remainder.push_back(std::fabs(p.value(z + h * dir) - f0 - h * slope));
  for (size_t k = 0; k + 1 < remainder.size(); ++k) {
    const double order = std::log2(remainder[k] / remainder[k + 1]);
    EXPECT_GE(order, 1.9) << "between steps " << k << " and " << k + 1;
    EXPECT_LE(order, 2.1) << "between steps " << k << " and " << k + 1;
  }
}

HausdorffParams params(double a, double b, double g, double e) {
  HausdorffParams p;
  p.alpha = a;
  p.beta = b;
  p.gamma = g;
  p.epsilon = e;
  return p;
}

std::vector<Case> cases() {
  std::vector<Case> out;
  for (int d : {2, 3})
    for (Variable v : {Variable::points, Variable::volumes, Variable::target}) {
      out.push_back({d, v, HausdorffParams{}});
      out.push_back({d, v, params(7.5, 2.5, 3.0, 1e-2)});  // non-integer α, β
    }
  return out;
}

std::string case_name(const ::testing::TestParamInfo<Case>& info) {
  const char* names[] = {"points", "volumes", "target"};
  return std::to_string(info.param.dim) + "D_" + names[static_cast<int>(info.param.var)] +
         (info.param.prm.alpha == 4.0 ? "_paper" : "_fractional");
}

INSTANTIATE_TEST_SUITE_P(Hausdorff, GradientTest, ::testing::ValuesIn(cases()), case_name);

TEST(HausdorffGradient, MaskZeroesRowsAndKeepsTheOthers) {
  const PointCloud X = random_cloud(20, 3, 3), Y = random_cloud(25, 3, 4);
  HausdorffRequest all;
  all.gradient_points = all.gradient_volumes = true;
  HausdorffRequest some;
  some.gradient_points = some.gradient_volumes = true;
  some.differentiate.setConstant(X.size(), true);
  for (int i = 0; i < 20; i += 3) some.differentiate[i] = false;
  const HausdorffResult a = hausdorff(X, Y, {}, all), b = hausdorff(X, Y, {}, some);
  EXPECT_EQ(a.rho, b.rho);
  for (Eigen::Index i = 0; i < X.size(); ++i) {
    if (some.differentiate[i]) {
      EXPECT_EQ(a.gradient_points.row(i), b.gradient_points.row(i));
      EXPECT_EQ(a.gradient_volumes[i], b.gradient_volumes[i]);
    } else {
      EXPECT_TRUE(b.gradient_points.row(i).isZero());
      EXPECT_EQ(b.gradient_volumes[i], 0.0);
    }
  }
}

TEST(HausdorffGradient, CoincidentPairContributesZero) {
  // Moving point 0 sits exactly on target point 0: finite gradient, equal to the
  // symmetric central difference.
  PointCloud Y = random_cloud(9, 3, 8);
  Eigen::MatrixXd px = random_cloud(7, 3, 9).points();
  px.row(0) = Y.points().row(0);
  const PointCloud X(px);
  HausdorffRequest req;
  req.gradient_points = true;
  const HausdorffResult r = hausdorff(X, Y, {}, req);
  ASSERT_TRUE(r.gradient_points.allFinite());
  for (int k = 0; k < 3; ++k) {
    Eigen::MatrixXd pp = px, pm = px;
    const double h = 1e-7;
    pp(0, k) += h;
    pm(0, k) -= h;
    const double fd =
        (hausdorff(PointCloud(pp), Y).rho - hausdorff(PointCloud(pm), Y).rho) / (2 * h);
    EXPECT_NEAR(r.gradient_points(0, k), fd, 1e-5 * r.gradient_points.cwiseAbs().maxCoeff());
  }
}

}  // namespace
}  // namespace softhd::test
