#pragma once

#include <array>
// Helpers shared by the FE tests.

#include <Eigen/Core>
#include <memory>
#include <random>

#include "softhd/fe/assembly.hpp"
#include "softhd/fe/materials.hpp"
#include "softhd/fe/mesh.hpp"

namespace fe_test {

inline softhd::fe::Mesh box(int dim, int order, const std::array<double, 3>& len,
                            const std::array<int, 3>& cells) {
  // Plain arrays, not Eigen::Vector3d/3i: g++ 12 falsely warns (-Warray-bounds,
  // -Wmaybe-uninitialized) on Eigen's vectorised copies of 3-vectors under AVX.
  Eigen::VectorXd hi(dim);
  Eigen::VectorXi n(dim);
  for (int k = 0; k < dim; ++k) {
    hi[k] = len[k];
    n[k] = cells[k];
  }
  return softhd::fe::make_box_mesh(Eigen::VectorXd::Zero(dim), hi, n, order);
}

inline std::shared_ptr<const softhd::fe::Material> mooney_rivlin(double scale = 1.0) {
  return std::make_shared<softhd::fe::MooneyRivlin>(1.0 * scale, 0.2 * scale, 3.0 * scale);
}

inline Eigen::VectorXd random_vector(Eigen::Index n, double amplitude, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(-amplitude, amplitude);
  Eigen::VectorXd v(n);
  for (Eigen::Index i = 0; i < n; ++i) v[i] = U(rng);
  return v;
}

}  // namespace fe_test
