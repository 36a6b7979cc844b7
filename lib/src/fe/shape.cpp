#include "softhd/fe/shape.hpp"

#include <cassert>
#include <cmath>

namespace softhd::fe {

namespace {

// 1-D Lagrange basis of order p at equispaced nodes -1 + 2i/p: values and derivatives.
void lagrange_1d(int p, double x, double* l, double* dl) {
  if (p == 1) {
    l[0] = 0.5 * (1.0 - x);
    l[1] = 0.5 * (1.0 + x);
    dl[0] = -0.5;
    dl[1] = 0.5;
  } else {
    l[0] = 0.5 * x * (x - 1.0);
    l[1] = 1.0 - x * x;
    l[2] = 0.5 * x * (x + 1.0);
    dl[0] = x - 0.5;
    dl[1] = -2.0 * x;
    dl[2] = x + 0.5;
  }
}

}  // namespace

void lagrange_shape(int dim, int order, const Eigen::VectorXd& xi, Eigen::VectorXd* N,
                    Eigen::MatrixXd* dN) {
  assert(order == 1 || order == 2);
  const int n1 = order + 1;
  double l[3][3], dl[3][3];
  for (int d = 0; d < dim; ++d) lagrange_1d(order, xi[d], l[d], dl[d]);
  const int nen = dim == 2 ? n1 * n1 : n1 * n1 * n1;
  N->resize(nen);
  dN->resize(nen, dim);
  for (int a = 0; a < nen; ++a) {
    const int idx[3] = {a % n1, (a / n1) % n1, a / (n1 * n1)};
    double v = 1.0;
    for (int d = 0; d < dim; ++d) v *= l[d][idx[d]];
    (*N)[a] = v;
    for (int g = 0; g < dim; ++g) {
      double w = 1.0;
      for (int d = 0; d < dim; ++d) w *= (d == g) ? dl[d][idx[d]] : l[d][idx[d]];
      (*dN)(a, g) = w;
    }
  }
}

void element_quadrature(int dim, int order, Eigen::MatrixXd* points, Eigen::VectorXd* weights) {
  Eigen::VectorXd g, w;
  gauss_legendre(order + 1, &g, &w);
  const int n1 = static_cast<int>(g.size());
  const int nq = dim == 2 ? n1 * n1 : n1 * n1 * n1;
  points->resize(nq, dim);
  weights->resize(nq);
  for (int q = 0; q < nq; ++q) {
    const int idx[3] = {q % n1, (q / n1) % n1, q / (n1 * n1)};
    double wq = 1.0;
    for (int d = 0; d < dim; ++d) {
      (*points)(q, d) = g[idx[d]];
      wq *= w[idx[d]];
    }
    (*weights)[q] = wq;
  }
}

}  // namespace softhd::fe
