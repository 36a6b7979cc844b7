#pragma once
/// \file shape.hpp
/// Gauss-Legendre quadrature on [-1, 1] (the shape functions and cell rules of every cell
/// type are in fe/reference_element.hpp).

#include <Eigen/Core>

namespace softhd::fe {

/// Gauss-Legendre rule with n >= 1 points on [-1, 1]: points and weights (closed forms up to
/// 4 points, Golub-Welsch beyond; lib/src/fe/quadrature.cpp).
void gauss_legendre(int n, Eigen::VectorXd* points, Eigen::VectorXd* weights);

}  // namespace softhd::fe
