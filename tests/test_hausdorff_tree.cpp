// Method tree (docs/formulation.md §2.5): every kernel sum within its guaranteed relative tolerance
// τ of a long-double all-pairs reference, on random, clustered, surface and degenerate clouds in 2D
// and 3D; the field and mean bounds derived in docs/tree_tolerance.md; a tiny τ reproducing method
// exact.

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "hausdorff/kd_tree.hpp"
#include "hausdorff/tree_sums.hpp"
#include "hausdorff_reference.hpp"
#include "softhd/error.hpp"
#include "softhd/hausdorff.hpp"

namespace softhd::test {
namespace {

enum class Shape { cube, clusters, sphere, line, plane, duplicates };

const char* name(Shape s) {
  const char* names[] = {"cube", "clusters", "sphere", "line", "plane", "duplicates"};
  return names[static_cast<int>(s)];
}

/// n points of the given shape in R^d (fixed seed), volumes in [0.5, 1.5].
PointCloud make_cloud(Shape shape, int n, int d, unsigned seed) {
  std::mt19937_64 gen(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd p(n, d);
  Eigen::VectorXd v(n);
  Eigen::MatrixXd centres(4, d);
  for (int c = 0; c < 4; ++c)
    for (int k = 0; k < d; ++k) centres(c, k) = 3.0 * u(gen);
  for (int i = 0; i < n; ++i) {
    v[i] = 0.5 + u(gen);
    switch (shape) {
      case Shape::cube:
        for (int k = 0; k < d; ++k) p(i, k) = u(gen);
        break;
      case Shape::clusters: {  // four tight blobs far apart
        const int c = static_cast<int>(gen() % 4);
        for (int k = 0; k < d; ++k) p(i, k) = centres(c, k) + 0.02 * g(gen);
        break;
      }
      case Shape::sphere: {  // the unit sphere (circle in 2D)
        double r2 = 0.0;
        for (int k = 0; k < d; ++k) {
          p(i, k) = g(gen);
          r2 += p(i, k) * p(i, k);
        }
        p.row(i) /= std::sqrt(r2);
        break;
      }
      case Shape::line: {
        const double s = u(gen);
        for (int k = 0; k < d; ++k) p(i, k) = 0.2 + s * (k + 1);
        break;
      }
      case Shape::plane:  // the last coordinate is constant
        for (int k = 0; k < d; ++k) p(i, k) = k + 1 < d ? u(gen) : 0.25;
        break;
      case Shape::duplicates: {  // 12 distinct points, each repeated many times
        std::mt19937_64 site(seed * 31 + gen() % 12);
        std::uniform_real_distribution<double> us(0.0, 1.0);
        for (int k = 0; k < d; ++k) p(i, k) = us(site);
        break;
      }
    }
  }
  return PointCloud(p, v);
}

struct LongSums {
  long double S = 0, H = 0, Gm = 0, G2m = 0;
  long double G[3] = {0, 0, 0}, G2[3] = {0, 0, 0};
};

/// The sums of pair_kernel.hpp for one outer point, naively in long double.
LongSums reference_sums(const Eigen::VectorXd& o, long double c_o, const PointCloud& src,
                        const Eigen::VectorXd& w, const Eigen::VectorXd& h,
                        const Eigen::VectorXd& c, double alpha, double eps) {
  LongSums s;
  const int d = src.dim();
  for (Eigen::Index n = 0; n < src.size(); ++n) {
    long double diff[3] = {0, 0, 0}, r2 = 0;
    for (int k = 0; k < d; ++k) {
      diff[k] = static_cast<long double>(o[k]) - src.points()(n, k);
      r2 += diff[k] * diff[k];
    }
    const long double r = std::sqrt(r2), t = 1.0L / (r + eps);
    const long double p = std::pow(c_o * t, static_cast<long double>(alpha));
    const long double pi = std::pow(c[n] * t, static_cast<long double>(alpha));
    s.S += w[n] * p;
    s.H += h[n] * pi;
    if (r > 0) {
      s.Gm += w[n] * p * t;
      s.G2m += h[n] * pi * t;
      for (int k = 0; k < d; ++k) {
        s.G[k] += w[n] * p * t * diff[k] / r;
        s.G2[k] += h[n] * pi * t * diff[k] / r;
      }
    }
  }
  return s;
}

double brute_nearest_ld(const PointCloud& P, const Eigen::VectorXd& q) {
  return brute_nearest(P, q);
}

// Rounding allowance on top of τ: the double sums themselves carry a relative rounding
// error of a few ulps times log2 of the number of terms; 1e-13 covers it many times over
// and is 10⁻⁴ of the smallest τ tested.
constexpr double kRounding = 1e-13;

struct SumCase {
  Shape sources, outer;
  int dim;
};

class TreeSums : public ::testing::TestWithParam<SumCase> {};

// Every sum of every outer point within τ of the long-double reference, for several τ,
// α = 4 and a fractional α; the tree must also have approximated something at τ = 1e-3
// (or the test would prove nothing).
TEST_P(TreeSums, WithinToleranceOfLongDoubleReference) {
  const SumCase sc = GetParam();
  const PointCloud X = make_cloud(sc.sources, 1500, sc.dim, 7);
  const PointCloud Y = make_cloud(sc.outer, 160, sc.dim, 8);
  const double eps = 1e-3;
  const Eigen::VectorXd w = X.volumes() / X.total_volume();
  Eigen::VectorXd h(X.size()), c(X.size());
  std::mt19937_64 gen(9);
  for (Eigen::Index n = 0; n < X.size(); ++n) {
    h[n] = (gen() % 5 == 0) ? 0.0 : static_cast<double>(gen() >> 11) * 0x1.0p-53;
    c[n] = brute_nearest_ld(Y, X.points().row(n).transpose()) + eps;  // c_n ≤ r_n + ε
  }
  const detail::KdTree tree(X.points(), 8);
  const Eigen::VectorXd wt = tree.permute(w), ht = tree.permute(h), ct = tree.permute(c);
  for (double alpha : {4.0, 2.5}) {
    const detail::KernelPower power(alpha);
    const std::vector<detail::NodeMoments> mw =
        detail::node_moments(tree, wt.data(), nullptr, power);
    const std::vector<detail::NodeMoments> mh =
        detail::node_moments(tree, ht.data(), ct.data(), power);
    detail::TreePass pass;
    pass.tree = &tree;
    pass.src.dim = sc.dim;
    pass.src.size = X.size();
    for (int k = 0; k < sc.dim; ++k) pass.src.coord[k] = tree.points().col(k).data();
    pass.src.weight = wt.data();
    pass.src.coef = ht.data();
    pass.src.scale = ct.data();
    pass.outer = mw.data();
    pass.inner = mh.data();
    std::vector<LongSums> ref;
    std::vector<double> scale;
    for (Eigen::Index j = 0; j < Y.size(); ++j) {
      const Eigen::VectorXd o = Y.points().row(j).transpose();
      scale.push_back(brute_nearest_ld(X, o) + eps);
      ref.push_back(reference_sums(o, scale.back(), X, w, h, c, alpha, eps));
    }
    for (double tau : {1e-3, 1e-6, 1e-9}) {
      std::int64_t evaluations = 0;
      for (Eigen::Index j = 0; j < Y.size(); ++j) {
        const Eigen::VectorXd o = Y.points().row(j).transpose();
        const unsigned flags = detail::kOuterSum | detail::kOuterGrad | detail::kInner;
        const detail::PairSums s =
            detail::tree_sums(o.data(), scale[j], pass, power, eps, tau, flags, evaluations);
        const LongSums& r = ref[static_cast<size_t>(j)];
        long double dG = 0, dG2 = 0;
        for (int k = 0; k < sc.dim; ++k) {
          dG += (s.G[k] - r.G[k]) * (s.G[k] - r.G[k]);
          dG2 += (s.G2[k] - r.G2[k]) * (s.G2[k] - r.G2[k]);
        }
        const long double bound = tau + kRounding;
        ASSERT_LE(std::fabs(s.S - r.S), bound * r.S) << "S, tau " << tau << " point " << j;
        ASSERT_LE(std::fabs(s.H - r.H), bound * r.H) << "H, tau " << tau << " point " << j;
        ASSERT_LE(std::sqrt(dG), bound * r.Gm) << "G, tau " << tau << " point " << j;
        ASSERT_LE(std::sqrt(dG2), bound * r.G2m) << "G2, tau " << tau << " point " << j;
        // The magnitude sums returned are lower bounds of the exact ones.
        ASSERT_LE(s.Gm, r.Gm * (1 + kRounding));
        ASSERT_LE(s.G2m, r.G2m * (1 + kRounding));
      }
      const std::int64_t all = X.size() * Y.size();
      if (tau == 1e-3) {
        EXPECT_LT(evaluations, all) << "nothing approximated";
      }
    }
  }
}

std::vector<SumCase> sum_cases() {
  std::vector<SumCase> out;
  for (int d : {2, 3}) {
    out.push_back({Shape::cube, Shape::cube, d});
    out.push_back({Shape::clusters, Shape::cube, d});
    out.push_back({Shape::sphere, Shape::sphere, d});
    out.push_back({Shape::line, Shape::cube, d});
    out.push_back({Shape::plane, Shape::plane, d});
    out.push_back({Shape::duplicates, Shape::clusters, d});
  }
  return out;
}

std::string sum_case_name(const ::testing::TestParamInfo<SumCase>& info) {
  return std::to_string(info.param.dim) + "D_" + name(info.param.sources) + "_over_" +
         name(info.param.outer);
}

INSTANTIATE_TEST_SUITE_P(Hausdorff, TreeSums, ::testing::ValuesIn(sum_cases()), sum_case_name);

HausdorffOptions tree_options(double tau, int threads = 0) {
  HausdorffOptions o;
  o.method = Method::tree;
  o.tolerance = tau;
  o.threads = threads;
  return o;
}

// The propagated bounds of docs/tree_tolerance.md, e = (1 − τ)^(−1/α) − 1:
// |Δd̃| ≤ e (d̃ + ε) per field value, |ΔA| ≤ e (A + ε), |ΔB| ≤ e (B + ε), |Δρ̃| ≤ e (ρ̃ + ε),
// against the naive long-double formula of docs/formulation.md §2.1.
TEST(HausdorffTree, FieldsAndMeansWithinThePropagatedBound) {
  for (int d : {2, 3})
    for (Shape shape : {Shape::cube, Shape::clusters, Shape::sphere, Shape::plane}) {
      const PointCloud X = make_cloud(shape, 700, d, 21), Y = make_cloud(Shape::cube, 500, d, 22);
      const Reference ref = naive_hausdorff(X, Y, HausdorffParams{});
      ASSERT_TRUE(ref.representable);
      for (double tau : {1e-3, 1e-6, 1e-9}) {
        HausdorffRequest req;
        req.fields = true;
        const HausdorffOptions o = tree_options(tau);
        const HausdorffResult r = hausdorff(X, Y, o, req);
        const long double e = std::pow(1.0L - tau, -1.0L / o.params.alpha) - 1.0L + kRounding;
        const long double eps = o.params.epsilon;
        for (Eigen::Index j = 0; j < Y.size(); ++j) {
          const long double ref_j = ref.field_target[static_cast<size_t>(j)];
          ASSERT_LE(std::fabs(r.field_target[j] - ref_j), e * (ref_j + eps)) << name(shape);
        }
        for (Eigen::Index i = 0; i < X.size(); ++i) {
          const long double ref_i = ref.field_moving[static_cast<size_t>(i)];
          ASSERT_LE(std::fabs(r.field_moving[i] - ref_i), e * (ref_i + eps)) << name(shape);
        }
        EXPECT_LE(std::fabs(r.A - ref.A), e * (ref.A + eps)) << name(shape) << " " << tau;
        EXPECT_LE(std::fabs(r.B - ref.B), e * (ref.B + eps)) << name(shape) << " " << tau;
        EXPECT_LE(std::fabs(r.rho - ref.rho), e * (ref.rho + eps)) << name(shape) << " " << tau;
      }
    }
}

// A tolerance far below rounding makes every node fail its test except where the
// approximation is exact (coincident points): the result equals method exact.
TEST(HausdorffTree, TinyToleranceEqualsExact) {
  for (int d : {2, 3}) {
    const PointCloud X = make_cloud(Shape::clusters, 900, d, 31);
    const PointCloud Y = make_cloud(Shape::cube, 1100, d, 32);
    HausdorffRequest req;
    req.fields = req.gradient_points = req.gradient_volumes = req.gradient_target = true;
    const HausdorffResult ex = hausdorff(X, Y, HausdorffOptions{}, req);
    const HausdorffResult tr = hausdorff(X, Y, tree_options(1e-15), req);
    EXPECT_LE(relative_error(tr.rho, ex.rho), 1e-13);
    EXPECT_LE((tr.field_target - ex.field_target).norm(), 1e-13 * ex.field_target.norm());
    EXPECT_LE((tr.field_moving - ex.field_moving).norm(), 1e-13 * ex.field_moving.norm());
    EXPECT_LE((tr.gradient_points - ex.gradient_points).norm(), 1e-13 * ex.gradient_points.norm());
    EXPECT_LE((tr.gradient_volumes - ex.gradient_volumes).norm(),
              1e-13 * ex.gradient_volumes.norm());
    EXPECT_LE((tr.gradient_target - ex.gradient_target).norm(), 1e-13 * ex.gradient_target.norm());
  }
}

// Assembled gradients of ρ̃ (no closed bound is claimed for them, docs/tree_tolerance.md
// §5) approach method exact as τ falls; the thread count changes nothing.
TEST(HausdorffTree, GradientsConvergeToExactAndAreDeterministic) {
  const PointCloud X = make_cloud(Shape::sphere, 2000, 3, 41);
  const PointCloud Y = make_cloud(Shape::sphere, 1500, 3, 42);
  HausdorffRequest req;
  req.gradient_points = req.gradient_volumes = req.gradient_target = true;
  const HausdorffResult ex = hausdorff(X, Y, HausdorffOptions{}, req);
  double previous = INFINITY;
  for (double tau : {1e-2, 1e-4, 1e-6, 1e-8}) {
    const HausdorffResult tr = hausdorff(X, Y, tree_options(tau), req);
    const double err = (tr.gradient_points - ex.gradient_points).norm() / ex.gradient_points.norm();
    EXPECT_TRUE(err < previous || err == 0.0) << tau << ": " << err << " after " << previous;
    previous = err;
  }
  const HausdorffResult t1 = hausdorff(X, Y, tree_options(1e-4, 1), req);
  const HausdorffResult t2 = hausdorff(X, Y, tree_options(1e-4, 2), req);
  EXPECT_EQ(t1.rho, t2.rho);
  EXPECT_EQ(t1.kernel_evaluations, t2.kernel_evaluations);
  EXPECT_TRUE(t1.gradient_points == t2.gradient_points);
  EXPECT_TRUE(t1.gradient_target == t2.gradient_target);
  EXPECT_LT(t1.kernel_evaluations, ex.kernel_evaluations);
}

TEST(HausdorffTree, RejectsToleranceOutsideTheOpenUnitInterval) {
  const PointCloud X = make_cloud(Shape::cube, 5, 3, 1), Y = make_cloud(Shape::cube, 5, 3, 2);
  for (double tau : {0.0, -1e-3, 1.0, 2.0, std::nan("")}) {
    try {
      hausdorff(X, Y, tree_options(tau));
      ADD_FAILURE() << "tolerance " << tau << " accepted";
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find("tolerance"), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(method_from_string("tree"), Method::tree);
  EXPECT_EQ(to_string(Method::tree), "tree");
}

}  // namespace
}  // namespace softhd::test
