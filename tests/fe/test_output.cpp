#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

#include "fe_test_util.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/control.hpp"
#include "softhd/fe/output.hpp"

using namespace softhd::fe;

// Q2 interpolation reproduces a quadratic displacement field exactly between nodes.
TEST(Output, ProbeInterpolatesQuadraticFieldsExactly) {
  const Assembler A(fe_test::box(3, 2, {2.0, 1.0, 0.5}, {3, 2, 1}), fe_test::mooney_rivlin(),
                    Eigen::Vector3d::UnitX(), {});
  auto field = [](const Eigen::Vector3d& X) {
    return Eigen::Vector3d(X[0] * X[1], X[2] * X[2] - X[0], 0.3 * X[0] * X[0] + X[1] * X[2]);
  };
  Eigen::VectorXd u(A.dofs().num_dofs);
  for (Eigen::Index n = 0; n < A.mesh().num_nodes(); ++n) {
    const Eigen::Vector3d f = field(A.mesh().nodes.row(n).transpose());
    for (int k = 0; k < 3; ++k) u[3 * n + k] = f[k];
  }
  for (const Eigen::Vector3d& X :
       {Eigen::Vector3d(0.123, 0.77, 0.31), Eigen::Vector3d(2.0, 1.0, 0.5),
        Eigen::Vector3d(1.0, 0.5, 0.0)}) {
    EXPECT_LT((probe_displacement(A, u, X) - field(X)).norm(), 1e-13);
  }
  EXPECT_THROW(probe_displacement(A, u, Eigen::Vector3d(2.1, 0, 0)), softhd::InvalidArgument);
}

TEST(Output, ControlFileRoundTripAndMissingNode) {
  const Assembler A(fe_test::box(3, 2, {2.0, 1.0, 0.5}, {3, 2, 1}), fe_test::mooney_rivlin(),
                    Eigen::Vector3d::UnitX(), {});
  const ControlSpace c(A.mesh(), A.geometry(), ControlKind::kVertex);
  const Eigen::MatrixXd P = c.positions(A.mesh());
  const Eigen::VectorXd m = fe_test::random_vector(c.size(), 1e4, 3);
  const std::string path = std::string(SOFTHD_BINARY_DIR) + "/test_output_control.txt";
  write_control_file(path, P, m);
  EXPECT_EQ((read_control_file(path, P) - m).cwiseAbs().maxCoeff(), 0.0);
  // Rows in another order are matched by coordinates.
  {
    std::ofstream out(path);
    for (Eigen::Index k = P.rows() - 1; k >= 0; --k)
      out << P(k, 0) << ", " << P(k, 1) << ", " << P(k, 2) << ", " << k << "  # node\n";
  }
  const Eigen::VectorXd idx = read_control_file(path, P);
  for (Eigen::Index k = 0; k < P.rows(); ++k) EXPECT_EQ(idx[k], k);
  {
    std::ofstream out(path);
    out << "0 0 0 1\n";
  }
  try {
    read_control_file(path, P);
    ADD_FAILURE() << "no error";
  } catch (const softhd::FileError& e) {
    EXPECT_NE(std::string(e.what()).find("control node 1"), std::string::npos) << e.what();
  }
  std::remove(path.c_str());
}

TEST(Output, VtuHasOneQuadraticCellPerElement) {
  const Assembler A(fe_test::box(2, 2, {2.0, 1.0, 0.0}, {3, 2, 1}), fe_test::mooney_rivlin(),
                    Eigen::Vector3d::UnitX(), {});
  const std::string path = std::string(SOFTHD_BINARY_DIR) + "/test_output.vtu";
  const Eigen::MatrixXd z =
      Eigen::MatrixXd::Zero(A.mesh().num_elements(), A.geometry().points_per_element());
  write_vtu(path, A.mesh(), Eigen::VectorXd::Zero(A.dofs().num_dofs), z, z);
  std::ifstream in(path);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("NumberOfPoints=\"35\""), std::string::npos);  // 7 × 5 nodes
  EXPECT_NE(text.find("NumberOfCells=\"6\""), std::string::npos);  // one VTK_BIQUADRATIC_QUAD each
  EXPECT_NE(text.find("\n 28 28 28 28 28 28\n"), std::string::npos);
  std::remove(path.c_str());
}
