#include "softhd/fe/assembly.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "softhd/error.hpp"

namespace softhd::fe {

namespace {

// Greedy colouring: no two elements of one colour share a node.
std::vector<std::vector<int>> colour_elements(const Mesh& mesh) {
  std::vector<std::vector<int>> node_elements(mesh.num_nodes());
  std::vector<int> colour(mesh.num_elements(), -1);
  std::vector<std::vector<int>> colours;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    std::vector<char> used(colours.size() + 1, 0);
    for (int a = 0; a < mesh.nodes_per_element(); ++a)
      for (int other : node_elements[mesh.elements(e, a)]) used[colour[other]] = 1;
    int c = 0;
    while (used[c]) ++c;
    colour[e] = c;
    if (c == static_cast<int>(colours.size())) colours.emplace_back();
    colours[c].push_back(e);
    for (int a = 0; a < mesh.nodes_per_element(); ++a)
      node_elements[mesh.elements(e, a)].push_back(e);
  }
  return colours;
}

// Per-thread work arrays of the element kernel (never shared between threads).
struct Scratch {
  Eigen::MatrixXd ue, B, CB, K;
  Eigen::VectorXd r;
  Scratch(int nen, int dim)
      : ue(3, nen), B(9, nen * dim), CB(9, nen * dim), K(nen * dim, nen * dim), r(nen * dim) {}
};

}  // namespace

Assembler::Assembler(Mesh mesh, std::shared_ptr<const Material> material, const Eigen::Vector3d& a0,
                     const std::vector<DirichletConstraint>& constraints)
    : mesh_(std::move(mesh)), geometry_(mesh_), material_(std::move(material)) {
  if (!material_) throw InvalidArgument("assembler: no material given");
  const double n = a0.norm();
  if (!(n > 0.0) || !std::isfinite(n))
    throw InvalidArgument("assembler: fiber direction must be non-zero");
  a0_ = a0 / n;
  if (mesh_.dim == 2 && a0_[2] != 0.0) {
    throw InvalidArgument("assembler: in 2D the fiber direction must lie in the plane (a0[2] = 0)");
  }
  dofs_ = make_dof_map(mesh_, constraints);
  colours_ = colour_elements(mesh_);
  // Sparsity pattern of the lower triangle on the free dofs, then element maps into it.
  const int dim = mesh_.dim, nen = mesh_.nodes_per_element(), nd = nen * dim;
  const Eigen::Index E = mesh_.num_elements();
  std::vector<Eigen::Triplet<double, int>> trip;
  trip.reserve(static_cast<size_t>(E) * nd * (nd + 1) / 2);
  std::vector<int> fr(nd);
  for (Eigen::Index e = 0; e < E; ++e) {
    for (int a = 0; a < nen; ++a)
      for (int k = 0; k < dim; ++k)
        fr[a * dim + k] = dofs_.free_index[mesh_.elements(e, a) * dim + k];
    for (int i = 0; i < nd; ++i)
      for (int j = 0; j < nd; ++j)
        if (fr[i] >= 0 && fr[j] >= 0 && fr[i] >= fr[j]) trip.emplace_back(fr[i], fr[j], 0.0);
  }
  pattern_.resize(dofs_.num_free, dofs_.num_free);
  pattern_.setFromTriplets(trip.begin(), trip.end());
  pattern_.makeCompressed();
  nz_map_.assign(E, std::vector<int>(static_cast<size_t>(nd) * nd, -1));
  const int* outer = pattern_.outerIndexPtr();
  const int* inner = pattern_.innerIndexPtr();
  for (Eigen::Index e = 0; e < E; ++e) {
    for (int a = 0; a < nen; ++a)
      for (int k = 0; k < dim; ++k)
        fr[a * dim + k] = dofs_.free_index[mesh_.elements(e, a) * dim + k];
    for (int i = 0; i < nd; ++i)
      for (int j = 0; j < nd; ++j) {
        if (fr[i] < 0 || fr[j] < 0 || fr[i] < fr[j]) continue;
        const int* begin = inner + outer[fr[j]];
        const int* end = inner + outer[fr[j] + 1];
        nz_map_[e][static_cast<size_t>(i) * nd + j] =
            static_cast<int>(std::lower_bound(begin, end, fr[i]) - inner);
      }
  }
}

SparseMatrix Assembler::tangent_pattern() const { return pattern_; }

Eigen::Matrix3d Assembler::deformation_gradient(const Eigen::VectorXd& u, Eigen::Index e,
                                                int q) const {
  // F = I + Σ_a u_a ⊗ ∇N_a (F33 = 1 in 2D: plane strain)
  const int dim = mesh_.dim;
  const auto G = geometry_.gradients(e, q);
  Eigen::Matrix3d F = Eigen::Matrix3d::Identity();
  for (int a = 0; a < mesh_.nodes_per_element(); ++a) {
    const Eigen::Index n = mesh_.elements(e, a);
    for (int i = 0; i < dim; ++i)
      for (int J = 0; J < dim; ++J) F(i, J) += u[n * dim + i] * G(J, a);
  }
  return F;
}

bool Assembler::evaluate(const Eigen::VectorXd& u, const Eigen::MatrixXd& m_qp, double* energy,
                         Eigen::VectorXd* residual, SparseMatrix* tangent) const {
  const int dim = mesh_.dim, nen = mesh_.nodes_per_element(), nd = nen * dim;
  const int nq = geometry_.points_per_element();
  const Eigen::Index E = mesh_.num_elements();
  if (u.size() != dofs_.num_dofs) throw InvalidArgument("assembler: u has the wrong size");
  if (m_qp.rows() != E || m_qp.cols() != nq)
    throw InvalidArgument("assembler: m_qp must be E by nq");
  if (tangent && tangent->nonZeros() != pattern_.nonZeros()) {
    throw InvalidArgument("assembler: the tangent must come from tangent_pattern()");
  }
  const bool want_r = residual != nullptr, want_K = tangent != nullptr;
  if (want_r) residual->setZero(dofs_.num_free);
  double* Kval = want_K ? tangent->valuePtr() : nullptr;
  if (want_K) std::fill(Kval, Kval + tangent->nonZeros(), 0.0);
  std::vector<double> element_energy(E, 0.0);
  std::vector<char> element_ok(E, 1);
  for (const std::vector<int>& colour : colours_) {
    const int n_el = static_cast<int>(colour.size());
#pragma omp parallel if (n_el >= 32)
    {
      Scratch s(nen, dim);
#pragma omp for schedule(static)
      for (int i = 0; i < n_el; ++i) {
        const int e = colour[i];
        if (want_r) s.r.setZero();
        if (want_K) s.K.setZero();
        double We = 0.0;
        for (int q = 0; q < nq && element_ok[e]; ++q) {
          const Eigen::Matrix3d F = deformation_gradient(u, e, q);
          if (!(F.determinant() > 0.0)) {
            element_ok[e] = 0;
            break;
          }
          const PointResponse pr = evaluate_point(*material_, a0_, m_qp(e, q), F, want_K);
          const double w = geometry_.weights()(e, q);
          We += w * pr.W;  // Π_e = Σ_q w_q det J0 (W + W_m)
          if (!want_r && !want_K) continue;
          // B: vec(δF) = B δu_e, column (b dim + k) holds e_k ⊗ ∇N_b.
          const auto G = geometry_.gradients(e, q);
          s.B.setZero();
          for (int b = 0; b < nen; ++b)
            for (int k = 0; k < dim; ++k)
              for (int L = 0; L < dim; ++L) s.B(k + 3 * L, b * dim + k) = G(L, b);
          if (want_r)
            s.r.noalias() += w * s.B.transpose() * Eigen::Map<const Vector9d>(pr.P.data());
          if (want_K) {
            s.CB.noalias() = pr.C * s.B;
            s.K.noalias() += w * s.B.transpose() * s.CB;
          }
        }
        element_energy[e] = We;
        if (!element_ok[e]) continue;
        for (int a = 0; a < nen; ++a)
          for (int k = 0; k < dim; ++k) {
            const int l = a * dim + k;
            const int f = dofs_.free_index[mesh_.elements(e, a) * dim + k];
            if (want_r && f >= 0) (*residual)[f] += s.r[l];
          }
        if (want_K) {
          const std::vector<int>& map = nz_map_[e];
          for (int l1 = 0; l1 < nd; ++l1)
            for (int l2 = 0; l2 < nd; ++l2) {
              const int idx = map[static_cast<size_t>(l1) * nd + l2];
              if (idx >= 0) Kval[idx] += s.K(l1, l2);
            }
        }
      }
    }
  }
  const bool ok = std::all_of(element_ok.begin(), element_ok.end(), [](char c) { return c != 0; });
  if (energy) {
    double total = 0.0;
    for (double We : element_energy) total += We;  // fixed order: deterministic
    *energy = ok ? total : std::numeric_limits<double>::infinity();
  }
  return ok;
}

Eigen::MatrixXd Assembler::jacobians(const Eigen::VectorXd& u) const {
  const int nq = geometry_.points_per_element();
  Eigen::MatrixXd J(mesh_.num_elements(), nq);
#pragma omp parallel for schedule(static)
  for (Eigen::Index e = 0; e < mesh_.num_elements(); ++e)
    for (int q = 0; q < nq; ++q) J(e, q) = deformation_gradient(u, e, q).determinant();
  return J;
}

double Assembler::min_jacobian(const Eigen::VectorXd& u) const { return jacobians(u).minCoeff(); }

double Assembler::deformed_volume(const Eigen::VectorXd& u) const {
  // ∫ J dX = Σ_e Σ_q w_q det J0 det F
  return jacobians(u).cwiseProduct(geometry_.weights()).sum();
}

Eigen::MatrixXd Assembler::fiber_sensitivity(const Eigen::VectorXd& u,
                                             const Eigen::VectorXd& lambda) const {
  const int nq = geometry_.points_per_element();
  Eigen::MatrixXd s(mesh_.num_elements(), nq);
#pragma omp parallel for schedule(static)
  for (Eigen::Index e = 0; e < mesh_.num_elements(); ++e)
    for (int q = 0; q < nq; ++q) {
      const Eigen::Matrix3d F = deformation_gradient(u, e, q);
      // ∇λ = Σ_a λ_a ⊗ ∇N_a, computed as "F − I" of λ
      const Eigen::Matrix3d Glam = deformation_gradient(lambda, e, q) - Eigen::Matrix3d::Identity();
      s(e, q) = geometry_.weights()(e, q) * (F * a0_).dot(Glam * a0_);
    }
  return s;
}

}  // namespace softhd::fe
