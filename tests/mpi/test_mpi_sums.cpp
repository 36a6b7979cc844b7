// Distributed pair sums (docs/scaling.md §1), run under mpiexec with 2 or more ranks: every
// rank evaluates the same clouds once serially (no share) and once with the pair sums shared
// over MPI_COMM_WORLD, and the two must agree to 1e-12 (relative) for methods exact, tree
// and nearest, values, fields and every gradient. The backends are also checked pass by
// pass: each rank computes a proper part of the rows, and the parts cover every row once.

#include <gtest/gtest.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <string>

#include "hausdorff/dual_tree.hpp"
#include "hausdorff/pair_backend.hpp"
#include "hausdorff_reference.hpp"
#include "softhd/mpi/work_share.hpp"

namespace softhd::test {
namespace {

constexpr double kRelative = 1e-12;

/// Clusters of very different density: equal counts are far from equal costs.
PointCloud clustered_cloud(int n, unsigned seed) {
  std::mt19937_64 gen(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Eigen::MatrixXd p(n, 3);
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) {
    const bool dense = i % 4 != 0;  // three quarters of the points in one small blob
    for (int k = 0; k < 3; ++k) p(i, k) = dense ? 0.5 + 0.03 * g(gen) : u(gen);
    v[i] = 0.5 + u(gen);
  }
  return PointCloud(p, v);
}

/// max |a − b| ≤ kRelative · max |b| (b the serial value), entry by entry of the arrays.
template <class A>
void expect_close(const A& a, const A& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  if (b.size() == 0) return;
  const double scale = b.cwiseAbs().maxCoeff();
  const double diff = (a - b).cwiseAbs().maxCoeff();
  EXPECT_LE(diff, kRelative * scale) << what << ": max difference " << diff << " of " << scale;
}

void expect_close(double a, double b, const std::string& what) {
  EXPECT_LE(std::fabs(a - b), kRelative * std::fabs(b)) << what << ": " << a << " vs " << b;
}

struct Case {
  Method method;
  bool fallback;  // tree: the cost model may sum a pass exactly
  double alpha;
  const char* name;
};

class Distributed : public ::testing::TestWithParam<Case> {};

TEST_P(Distributed, EqualsSerial) {
  const Case c = GetParam();
  const PointCloud X = clustered_cloud(2500, 1);
  const PointCloud Y = random_cloud(2000, 3, 2, -0.1, 1.1);
  HausdorffOptions opt;
  opt.method = c.method;
  opt.params.alpha = c.alpha;
  opt.tolerance = 1e-2;  // a loose τ: the far field does most of the work
  opt.tree_fallback = c.fallback;
  opt.threads = 1;
  HausdorffRequest req;
  req.fields = true;
  if (c.method != Method::nearest) {
    req.gradient_points = req.gradient_volumes = req.gradient_target = true;
    req.differentiate.setConstant(X.size(), true);
    for (Eigen::Index i = 0; i < X.size(); i += 7) req.differentiate[i] = false;
  }
  const HausdorffResult serial = HausdorffTarget(Y, opt).evaluate(X, req);
  opt.share = mpi::work_share(MPI_COMM_WORLD);
  ASSERT_GE(opt.share->size(), 2) << "run under mpiexec -n 2 (or more)";
  const HausdorffResult shared = HausdorffTarget(Y, opt).evaluate(X, req);

  expect_close(shared.rho, serial.rho, "rho");
  expect_close(shared.A, serial.A, "A");
  expect_close(shared.B, serial.B, "B");
  expect_close(shared.field_target, serial.field_target, "field_target");
  expect_close(shared.field_moving, serial.field_moving, "field_moving");
  expect_close(shared.gradient_points, serial.gradient_points, "gradient_points");
  expect_close(shared.gradient_volumes, serial.gradient_volumes, "gradient_volumes");
  expect_close(shared.gradient_target, serial.gradient_target, "gradient_target");
  // The work counts are summed over the ranks: the serial pass's, whoever did what.
  EXPECT_EQ(shared.kernel_evaluations, serial.kernel_evaluations);
  EXPECT_EQ(shared.work.exact_passes, serial.work.exact_passes);
  if (c.method == Method::tree && !c.fallback) {
    EXPECT_EQ(serial.work.exact_passes, 0);
    // The tree did its job (far field or pruning), so the split of its plan was tested.
    EXPECT_LT(serial.work.near_pairs, serial.work.passes * X.size() * Y.size());
    if (c.alpha <= 16.0) {
      EXPECT_GT(serial.work.far_kernel, 0) << "the far field was not used";
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Methods, Distributed,
                         ::testing::Values(Case{Method::exact, true, 4.0, "exact"},
                                           Case{Method::tree, false, 4.0, "tree"},
                                           Case{Method::tree, true, 4.0, "tree_cost_model"},
                                           Case{Method::tree, false, 24.0, "tree_pruning"},
                                           Case{Method::nearest, true, 4.0, "nearest"}),
                         [](const ::testing::TestParamInfo<Case>& info) {
                           return std::string(info.param.name);
                         });

/// Rows of `s` with any nonzero sum.
std::int64_t rows_computed(const detail::PassSums& s) {
  std::int64_t n = 0;
  for (Eigen::Index i = 0; i < s.S.size(); ++i) n += s.S[i] != 0.0 ? 1 : 0;
  return n;
}

TEST(DistributedPasses, EachRankComputesItsPartAndThePartsCoverEveryRow) {
  const PointCloud X = clustered_cloud(3000, 3);
  const PointCloud Y = random_cloud(1500, 3, 4);
  const double eps = 1e-3;
  const Eigen::VectorXd w = X.volumes() / X.total_volume();
  Eigen::VectorXd scale(Y.size());
  for (Eigen::Index j = 0; j < Y.size(); ++j)
    scale[j] = brute_nearest(X, Y.points().row(j).transpose()) + eps;
  const detail::KdTree xt(X.points(), detail::kLeafSize), yt(Y.points(), detail::kLeafSize);
  const detail::KernelPower power(4.0);
  detail::DualTreeConfig cfg;
  cfg.cost_model = false;
  const std::shared_ptr<const WorkShare> share = mpi::work_share(MPI_COMM_WORLD);
  const char* names[3] = {"exact", "single tree", "dual tree"};
  std::unique_ptr<detail::PairSumBackend> backends[3] = {
      detail::make_exact_backend(), detail::make_single_tree_backend(),
      detail::make_dual_tree_backend(cfg, nullptr)};
  const detail::PassSources src{&X.points(), &xt, w.data(), nullptr, nullptr};
  const detail::PassOuter out{&Y.points(), &yt, scale.data(),
                              detail::kOuterSum | detail::kOuterGrad, nullptr};
  detail::PassSettings set{&power, eps, 1e-4, 1};
  for (int b = 0; b < 3; ++b) {
    set.share = nullptr;
    const detail::PassSums serial = backends[b]->sums(src, out, set);
    set.share = share.get();
    const std::int64_t mine = rows_computed(backends[b]->sums(src, out, set));
    std::int64_t total = mine;
    share->sum(&total, 1);
    EXPECT_GT(mine, 0) << names[b];
    EXPECT_LT(mine, Y.size()) << names[b];
    EXPECT_EQ(total, Y.size()) << names[b] << ": rows computed twice or not at all";
    const detail::PassSums shared = detail::run_pass(*backends[b], src, out, set);
    if (b < 2) {  // one point's sums do not depend on the others: the same bits
      EXPECT_TRUE(shared.S == serial.S) << names[b];
      EXPECT_TRUE(shared.G == serial.G) << names[b];
    } else {
      expect_close(shared.S, serial.S, names[b]);
      expect_close(shared.G, serial.G, names[b]);
    }
    EXPECT_EQ(shared.kernel_evaluations, serial.kernel_evaluations) << names[b];
  }
}

}  // namespace
}  // namespace softhd::test

int main(int argc, char** argv) {
  const softhd::mpi::Session session(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  int failed = RUN_ALL_TESTS();
  MPI_Allreduce(MPI_IN_PLACE, &failed, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);  // any rank

  return failed;
}
