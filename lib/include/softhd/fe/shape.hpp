#pragma once
/// \file shape.hpp
/// Lagrange shape functions on [-1, 1]^d (tensor products of 1-D Lagrange
/// polynomials at equispaced nodes) and Gauss-Legendre quadrature.

#include <Eigen/Core>

namespace softhd::fe {

/// Gauss-Legendre rule with n >= 1 points on [-1, 1]: points and weights (closed forms up to
/// 4 points, Golub-Welsch beyond; lib/src/fe/quadrature.cpp).
void gauss_legendre(int n, Eigen::VectorXd* points, Eigen::VectorXd* weights);

/// Values (nen) and reference gradients (nen by dim) of the order-p Lagrange shape
/// functions at xi (size dim); local node order as in Mesh.
void lagrange_shape(int dim, int order, const Eigen::VectorXd& xi, Eigen::VectorXd* N,
                    Eigen::MatrixXd* dN);

/// Tensor Gauss rule with (p+1)^dim points (full integration of Q_p): nq by dim
/// points and nq weights.
void element_quadrature(int dim, int order, Eigen::MatrixXd* points, Eigen::VectorXd* weights);

}  // namespace softhd::fe
