// HausdorffTarget is documented as safe to evaluate from many threads at once: a stress
// test. Eight std::threads evaluate one shared target (exact and tree methods, values and
// gradients, OpenMP inside each evaluation too) over and over; every result must equal,
// bitwise, the one computed serially beforehand.

#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <thread>
#include <vector>

#include "hausdorff_reference.hpp"
#include "softhd/hausdorff.hpp"

namespace softhd::test {
namespace {

bool same_bits(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return a.rows() == b.rows() && a.cols() == b.cols() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}

bool same_result(const HausdorffResult& a, const HausdorffResult& b) {
  return std::memcmp(&a.rho, &b.rho, sizeof a.rho) == 0 &&
         std::memcmp(&a.A, &b.A, sizeof a.A) == 0 && std::memcmp(&a.B, &b.B, sizeof a.B) == 0 &&
         same_bits(a.gradient_points, b.gradient_points) &&
         same_bits(a.gradient_volumes, b.gradient_volumes) &&
         same_bits(a.field_moving, b.field_moving);
}

class Concurrency : public ::testing::TestWithParam<Method> {};

TEST_P(Concurrency, ManyThreadsOnOneTargetGiveTheSerialResults) {
  HausdorffOptions o;
  o.method = GetParam();
  o.threads = 2;  // OpenMP inside every evaluation as well
  const HausdorffTarget target(random_cloud(2000, 3, 1, -1.0, 1.0), o);
  constexpr int kClouds = 8, kThreads = 8, kRepeats = 4;
  std::vector<PointCloud> moving;
  std::vector<HausdorffResult> serial;
  HausdorffRequest req;
  req.gradient_points = req.gradient_volumes = req.fields = true;
  for (int c = 0; c < kClouds; ++c) {
    moving.push_back(random_cloud(500 + 100 * c, 3, 100 + c, -1.0, 1.0));
    serial.push_back(target.evaluate(moving.back(), req));
  }
  std::atomic<int> mismatches{0}, evaluations{0};
  std::vector<std::thread> pool;
  for (int t = 0; t < kThreads; ++t) {
    pool.emplace_back([&, t] {
      for (int r = 0; r < kRepeats; ++r) {
        const int c = (t + r) % kClouds;  // threads on different clouds at the same time
        if (!same_result(target.evaluate(moving[c], req), serial[c])) ++mismatches;
        ++evaluations;
      }
    });
  }
  for (std::thread& th : pool) th.join();
  EXPECT_EQ(evaluations.load(), kThreads * kRepeats);
  EXPECT_EQ(mismatches.load(), 0);
}

INSTANTIATE_TEST_SUITE_P(Methods, Concurrency, ::testing::Values(Method::exact, Method::tree),
                         [](const auto& info) { return to_string(info.param); });

}  // namespace
}  // namespace softhd::test
