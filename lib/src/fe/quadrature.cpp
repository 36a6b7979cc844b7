// Quadrature rules of the reference cells (fe/reference_element.hpp): Gauss-Legendre tensor
// rules on [-1, 1]^d, and on the simplices symmetric positive rules where one is known
// (degrees 1, 2, 4, 5 on the triangle; 1, 2, 5 on the tetrahedron), otherwise collapsed
// (Duffy) Gauss-Jacobi tensor rules, which exist for every degree, have all points strictly
// inside and all weights positive.

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <cmath>
#include <utility>
#include <vector>

#include "softhd/error.hpp"
#include "softhd/fe/reference_element.hpp"
#include "softhd/fe/shape.hpp"

namespace softhd::fe {

namespace {

/// The highest degree cell_quadrature accepts (Gauss with 16 points per axis).
constexpr int kMaxDegree = 31;

// Golub-Welsch on [-1, 1] with weight (1 − x)^α: the monic Jacobi recurrence (β = 0)
//   a_k = −α² / ((2k+α)(2k+α+2)),  b_k² = 4k²(k+α)² / ((2k+α)² (2k+α+1)(2k+α−1)),
// nodes = eigenvalues of the Jacobi matrix, weights = μ0 v_0², μ0 = 2^{α+1}/(α+1).
void golub_welsch(int n, double alpha, Eigen::VectorXd* x, Eigen::VectorXd* w) {
  Eigen::VectorXd diag(n), sub(std::max(n - 1, 1));
  for (int k = 0; k < n; ++k) {
    const double s = 2.0 * k + alpha;
    diag[k] = alpha == 0.0 ? 0.0 : -alpha * alpha / (s * (s + 2.0));
    if (k > 0) {
      const double kk = k, ka = k + alpha;
      sub[k - 1] = std::sqrt(4.0 * kk * kk * ka * ka / (s * s * (s + 1.0) * (s - 1.0)));
    }
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es;
  es.computeFromTridiagonal(diag, sub.head(n - 1), Eigen::ComputeEigenvectors);
  const double mu0 = std::pow(2.0, alpha + 1.0) / (alpha + 1.0);
  *x = es.eigenvalues();
  *w = mu0 * es.eigenvectors().row(0).transpose().array().square();
  if (alpha == 0.0)  // Legendre: symmetric about 0 up to rounding; make it exact
    for (int i = 0; i < n / 2; ++i) {
      const int j = n - 1 - i;
      const double xs = 0.5 * ((*x)[j] - (*x)[i]), ws = 0.5 * ((*w)[i] + (*w)[j]);
      (*x)[i] = -xs, (*x)[j] = xs, (*w)[i] = ws, (*w)[j] = ws;
    }
}

// Gauss-Jacobi on [0, 1] with weight (1 − t)^α: t = (1 + x)/2, ∫ f (1−t)^α dt = 2^{−α−1} Σ w f.
void gauss_jacobi_01(int n, int alpha, Eigen::VectorXd* t, Eigen::VectorXd* w) {
  Eigen::VectorXd x;
  golub_welsch(n, alpha, &x, w);
  *t = 0.5 * (x.array() + 1.0);
  *w *= std::pow(0.5, alpha + 1);
}

// Tensor Gauss rule on [-1, 1]^dim, n points per axis, q = i + n(j + n k), w_q = Π w_i
// (formed as the former element_quadrature did, so box results stay bitwise equal).
void tensor_rule(int dim, int n, Eigen::MatrixXd* points, Eigen::VectorXd* weights) {
  Eigen::VectorXd g, w;
  gauss_legendre(n, &g, &w);
  const int nq = dim == 2 ? n * n : n * n * n;
  points->resize(nq, dim);
  weights->resize(nq);
  for (int q = 0; q < nq; ++q) {
    const int idx[3] = {q % n, (q / n) % n, q / (n * n)};
    double wq = 1.0;
    for (int d = 0; d < dim; ++d) {
      (*points)(q, d) = g[idx[d]];
      wq *= w[idx[d]];
    }
    (*weights)[q] = wq;
  }
}

// Collapsed Gauss-Jacobi rule on the unit simplex, n points per axis:
//   triangle    x = a(1−b), y = b,                 dx dy = (1−b) da db
//   tetrahedron x = a(1−b)(1−c), y = b(1−c), z = c, dV = (1−b)(1−c)² da db dc
// with Gauss-Legendre in a and Gauss-Jacobi (weights (1−b), (1−c)²) in b and c: a polynomial
// of total degree k becomes one of degree <= k in each of a, b, c, exact for 2n − 1 >= k.
void collapsed_rule(int dim, int n, Eigen::MatrixXd* points, Eigen::VectorXd* weights) {
  Eigen::VectorXd a, wa, b, wb, c, wc;
  gauss_jacobi_01(n, 0, &a, &wa);
  gauss_jacobi_01(n, 1, &b, &wb);
  gauss_jacobi_01(n, 2, &c, &wc);
  const int nq = dim == 2 ? n * n : n * n * n;
  points->resize(nq, dim);
  weights->resize(nq);
  int q = 0;
  for (int k = 0; k < (dim == 3 ? n : 1); ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i, ++q) {
        if (dim == 2) {
          (*points).row(q) << a[i] * (1.0 - b[j]), b[j];
          (*weights)[q] = wa[i] * wb[j];
        } else {
          (*points).row(q) << a[i] * (1.0 - b[j]) * (1.0 - c[k]), b[j] * (1.0 - c[k]), c[k];
          (*weights)[q] = wa[i] * wb[j] * wc[k];
        }
      }
}

// Symmetric rules from orbits of barycentric points: (orbit kind, coordinate, weight), the
// weights relative to the reference measure. Kinds: 0 centroid; triangle 1 (a, a, 1−2a);
// tetrahedron 1 (a, a, a, 1−3a), 2 (a, a, 1/2−a, 1/2−a).
struct Orbit {
  int kind;
  double a, w;
};

void append(int dim, const double* L, double w, Eigen::MatrixXd* P, Eigen::VectorXd* W) {
  const Eigen::Index q = P->rows();
  P->conservativeResize(q + 1, dim);
  W->conservativeResize(q + 1);
  for (int k = 0; k < dim; ++k) (*P)(q, k) = L[k + 1];
  (*W)[q] = w;
}

void orbit_rule(int dim, const std::vector<Orbit>& orbits, Eigen::MatrixXd* P, Eigen::VectorXd* W) {
  const double measure = dim == 2 ? 0.5 : 1.0 / 6.0;
  P->resize(0, dim);
  W->resize(0);
  for (const Orbit& o : orbits) {
    const double w = o.w * measure;
    if (o.kind == 0) {
      const double L[4] = {1.0 / (dim + 1), 1.0 / (dim + 1), 1.0 / (dim + 1), 1.0 / (dim + 1)};
      append(dim, L, w, P, W);
    } else if (o.kind == 1) {  // the odd one out at each vertex
      const double b = 1.0 - dim * o.a;
      for (int v = 0; v <= dim; ++v) {
        double L[4] = {o.a, o.a, o.a, o.a};
        L[v] = b;
        append(dim, L, w, P, W);
      }
    } else {  // one pair per edge of the tetrahedron
      const double b = 0.5 - o.a;
      for (int i = 0; i < 4; ++i)
        for (int j = i + 1; j < 4; ++j) {
          double L[4] = {b, b, b, b};
          L[i] = L[j] = o.a;
          append(dim, L, w, P, W);
        }
    }
  }
}

// Known positive symmetric rules; false if none is stored for this degree.
bool symmetric_rule(int dim, int degree, Eigen::MatrixXd* P, Eigen::VectorXd* W) {
  const double s15 = std::sqrt(15.0);
  if (degree <= 1) {  // centroid
    orbit_rule(dim, {{0, 0.0, 1.0}}, P, W);
  } else if (degree == 2) {  // 3 points (1/6, 1/6, 2/3); 4 points a = (5 − √5)/20
    orbit_rule(dim, {{1, dim == 2 ? 1.0 / 6.0 : (5.0 - std::sqrt(5.0)) / 20.0, 1.0 / (dim + 1)}}, P,
               W);
  } else if (dim == 2 && degree <= 4) {  // Strang-Fix / Dunavant, 6 points
    orbit_rule(2,
               {{1, 0.44594849091596488632, 0.22338158967801146570},
                {1, 0.091576213509770743460, 0.10995174365532186764}},
               P, W);
  } else if (dim == 2 && degree == 5) {  // Radon's 7 points, a = (6 ∓ √15)/21
    orbit_rule(2,
               {{0, 0.0, 9.0 / 40.0},
                {1, (6.0 - s15) / 21.0, (155.0 - s15) / 1200.0},
                {1, (6.0 + s15) / 21.0, (155.0 + s15) / 1200.0}},
               P, W);
  } else if (dim == 3 && degree <= 5) {  // Walkington's 14 points (weights for volume 1/6 × 6)
    orbit_rule(3,
               {{1, 0.31088591926330060980, 6.0 * 0.018781320953002641800},
                {1, 0.092735250310891226402, 6.0 * 0.012248840519393658257},
                {2, 0.045503704125649649492, 6.0 * 0.0070910034628469110730}},
               P, W);
  } else {
    return false;
  }
  return true;
}

}  // namespace

void gauss_legendre(int n, Eigen::VectorXd* points, Eigen::VectorXd* weights) {
  if (n < 1) throw InvalidArgument("gauss_legendre: need at least one point");
  points->resize(n);
  weights->resize(n);
  if (n == 1) {
    *points << 0.0;
    *weights << 2.0;
  } else if (n == 2) {
    const double g = 1.0 / std::sqrt(3.0);
    *points << -g, g;
    *weights << 1.0, 1.0;
  } else if (n == 3) {
    const double g = std::sqrt(0.6);
    *points << -g, 0.0, g;
    *weights << 5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0;
  } else if (n == 4) {
    const double a = std::sqrt(3.0 / 7.0 - 2.0 / 7.0 * std::sqrt(1.2));
    const double b = std::sqrt(3.0 / 7.0 + 2.0 / 7.0 * std::sqrt(1.2));
    const double wa = (18.0 + std::sqrt(30.0)) / 36.0, wb = (18.0 - std::sqrt(30.0)) / 36.0;
    *points << -b, -a, a, b;
    *weights << wb, wa, wa, wb;
  } else {
    golub_welsch(n, 0.0, points, weights);
  }
}

namespace {

// The zero eigenvalues of M = Σ_q B_qᵀ B_q on the cell mapped by X = A ξ, B_q the symmetric
// gradient ε(u)(ξ_q) of the element's displacements: the kernel of the linearised stiffness
// Σ_q w_q B_qᵀ C B_q for any positive weights and positive definite C.
int kernel_dimension(CellType type, const Eigen::MatrixXd& points, const Eigen::MatrixXd& A) {
  const ReferenceElement& r = reference_element(type);
  const int dim = r.dim, nd = r.nodes * dim;
  const Eigen::MatrixXd Ainv = A.inverse();
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(nd, nd), B(dim * (dim + 1) / 2, nd);
  std::vector<double> N(static_cast<std::size_t>(r.nodes)), dN(N.size() * dim);
  for (Eigen::Index q = 0; q < points.rows(); ++q) {
    const Eigen::VectorXd xi = points.row(q).transpose();
    shape_functions(type, xi.data(), N.data(), dN.data());
    const Eigen::MatrixXd G =  // dN_a/dX = dN_a/dξ A⁻¹: nodes by dim
        Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
            dN.data(), r.nodes, dim) *
        Ainv;
    B.setZero();
    int row = 0;  // ε_ij = (∂u_i/∂X_j + ∂u_j/∂X_i) / 2, i <= j
    for (int i = 0; i < dim; ++i)
      for (int j = i; j < dim; ++j, ++row)
        for (int a = 0; a < r.nodes; ++a) {
          B(row, a * dim + i) += 0.5 * G(a, j);
          B(row, a * dim + j) += 0.5 * G(a, i);
        }
    M += B.transpose() * B;
  }
  const Eigen::VectorXd lambda = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(M).eigenvalues();
  int zeros = 0;
  for (Eigen::Index k = 0; k < lambda.size(); ++k)
    zeros += std::abs(lambda[k]) <= 1e-10 * lambda.maxCoeff();
  return zeros;
}

}  // namespace

int spurious_zero_modes(CellType type, int degree) {
  const ReferenceElement& r = reference_element(type);
  Eigen::MatrixXd points;
  Eigen::VectorXd weights;
  cell_quadrature(type, degree, &points, &weights);
  // The reference cell itself, a stretched one (axis-aligned boxes) and a sheared one (the
  // generic case): the most zero modes of the three, less the rigid motions.
  const Eigen::MatrixXd identity = Eigen::MatrixXd::Identity(r.dim, r.dim);
  Eigen::MatrixXd stretch = identity, shear(r.dim, r.dim);
  stretch(0, 0) = 4.0;
  if (r.dim == 3)
    shear << 1.0, 0.2, 0.1, -0.1, 0.8, 0.3, 0.05, -0.2, 1.3;
  else
    shear << 1.0, 0.3, -0.2, 0.9;
  int zeros = 0;
  for (const Eigen::MatrixXd* A : {&identity, &std::as_const(stretch), &std::as_const(shear)})
    zeros = std::max(zeros, kernel_dimension(type, points, *A));
  return zeros - (r.dim == 3 ? 6 : 3);
}

void cell_quadrature(CellType type, int degree, Eigen::MatrixXd* points, Eigen::VectorXd* weights) {
  if (degree < 1 || degree > kMaxDegree)
    throw InvalidArgument("quadrature degree " + std::to_string(degree) + " is outside 1.." +
                          std::to_string(kMaxDegree));
  const ReferenceElement& r = reference_element(type);
  const int n = degree / 2 + 1;  // 2n − 1 >= degree
  if (!r.simplex)
    tensor_rule(r.dim, n, points, weights);
  else if (!symmetric_rule(r.dim, degree, points, weights))
    collapsed_rule(r.dim, n, points, weights);
}

int smallest_stable_degree(CellType type) {
  for (int degree = 1;; ++degree)
    if (spurious_zero_modes(type, degree) == 0) return degree;
}

void check_quadrature_degree(CellType type, int degree) {
  const int spurious = spurious_zero_modes(type, degree);  // also checks the range
  if (spurious > 0)
    throw InvalidArgument("quadrature degree " + std::to_string(degree) + " on " + to_string(type) +
                          " leaves " + std::to_string(spurious) +
                          " spurious zero-energy modes (a free element's stiffness must vanish "
                          "on its rigid motions only): use degree " +
                          std::to_string(smallest_stable_degree(type)) + " or higher");
}

}  // namespace softhd::fe
