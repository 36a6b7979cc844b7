#include <gtest/gtest.h>

#include <cmath>

#include "fe_test_util.hpp"
#include "softhd/fe/cloud.hpp"

using namespace softhd::fe;

// cloud_pullback is the derivative of a linear functional L(x, V) = <P, x> + <q, V> of the
// deformed cloud: central differences with observed second order; volumes sum to |Ω₀| or
// to the deformed volume.
TEST(Cloud, PullbackMatchesFiniteDifferences) {
  for (int dim : {2, 3})
    for (int order : {1, 2})
      for (CloudPoints pts : {CloudPoints::kNodes, CloudPoints::kQuadraturePoints})
        for (CloudVolumes vol : {CloudVolumes::kReference, CloudVolumes::kDeformed}) {
          const Assembler A(fe_test::box(dim, order, {2.0, 1.0, 0.5}, {2, 2, 1}),
                            fe_test::mooney_rivlin(), Eigen::Vector3d::UnitX(), {});
          const Eigen::VectorXd u = fe_test::random_vector(A.dofs().num_dofs, 0.05, 1);
          const softhd::PointCloud c = deformed_cloud(A, u, pts, vol);
          const double Vsum =
              vol == CloudVolumes::kDeformed ? A.deformed_volume(u) : (dim == 3 ? 1.0 : 2.0);
          EXPECT_NEAR(c.total_volume(), Vsum, 1e-12);
          const Eigen::MatrixXd P =
              fe_test::random_vector(c.size() * dim, 1.0, 2).reshaped(c.size(), dim);
          const Eigen::VectorXd q = fe_test::random_vector(c.size(), 1.0, 3);
          auto L = [&](const Eigen::VectorXd& v) {
            const softhd::PointCloud d = deformed_cloud(A, v, pts, vol);
            return d.points().cwiseProduct(P).sum() + d.volumes().dot(q);
          };
          const Eigen::VectorXd g = cloud_pullback(A, u, pts, vol, P, q);
          const Eigen::VectorXd w = fe_test::random_vector(u.size(), 1.0, 4);
          auto err = [&](double h) {
            return std::abs((L(u + h * w) - L(u - h * w)) / (2 * h) - g.dot(w));
          };
          const double e1 = err(1e-2), e2 = err(5e-3);
          EXPECT_LT(err(1e-6), 1e-7 * (1.0 + std::abs(g.dot(w))));
          if (vol == CloudVolumes::kDeformed && e1 > 1e-11) {
            EXPECT_GT(std::log2(e1 / e2), 1.8);
          }
        }
}
