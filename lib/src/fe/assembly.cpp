#include "softhd/fe/assembly.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

#include "softhd/error.hpp"
#include "softhd/parallel.hpp"

namespace softhd::fe {

namespace {

// Elements per parallel pass: the element results of one pass are buffered (about
// kPassBytes of them), then added to R and K serially in element order (bounded memory,
// deterministic for any thread count). Every pass is one fork and join of the threads, and
// on a loaded machine a join may wait a scheduler time slice for a thread that lost its
// core: small elements (a P2 tetrahedron's matrix is 1/7 of a Q2 hexahedron's) therefore
// get proportionally more elements per pass, and the elements are handed out dynamically.
constexpr std::size_t kPassBytes = std::size_t(8) << 20;
constexpr Eigen::Index kMinPass = 128;

Eigen::Index pass_elements(int nd, bool want_r, bool want_K) {
  const std::size_t per_element = sizeof(double) * (want_K ? nd * nd + nd : want_r ? nd : 1);
  return std::max<Eigen::Index>(kMinPass, static_cast<Eigen::Index>(kPassBytes / per_element));
}

}  // namespace

namespace {

FiberField uniform(const Eigen::Vector3d& a0) {
  FiberField f;
  f.values = a0;
  return f;
}

}  // namespace

Assembler::Assembler(Mesh mesh, std::shared_ptr<const Material> material, const Eigen::Vector3d& a0,
                     const std::vector<DirichletConstraint>& constraints, AssemblerStorage storage)
    : Assembler(std::move(mesh),
                std::vector<std::shared_ptr<const Material>>(1, std::move(material)), uniform(a0),
                constraints, storage) {}

Assembler::Assembler(Mesh mesh, std::vector<std::shared_ptr<const Material>> materials,
                     const FiberField& fibers, const std::vector<DirichletConstraint>& constraints,
                     AssemblerStorage storage, int quadrature_degree)
    : mesh_(std::move(mesh)),
      storage_(storage),
      geometry_(mesh_,
                storage == AssemblerStorage::kFull ? GradientStorage::kStored
                                                   : GradientStorage::kOnDemand,
                quadrature_degree),
      materials_(std::move(materials)) {
  if (materials_.empty()) throw InvalidArgument("assembler: no material given");
  if (materials_.size() == 1)  // one material for the whole body, whatever its regions
    materials_.resize(std::max<std::size_t>(1, mesh_.region_names.size()), materials_[0]);
  for (const auto& m : materials_)
    if (!m) throw InvalidArgument("assembler: no material given");
  if (mesh_.element_region.size() == 0) mesh_.element_region.setZero(mesh_.num_elements());
  if (mesh_.element_region.size() != mesh_.num_elements() ||
      mesh_.element_region.maxCoeff() >= static_cast<int>(materials_.size()) ||
      mesh_.element_region.minCoeff() < 0)
    throw InvalidArgument("assembler: " + std::to_string(materials_.size()) +
                          " materials for the mesh's regions");
  set_fibers(fibers);
  dofs_ = make_dof_map(mesh_, constraints);
  if (storage_ == AssemblerStorage::kLean) return;
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

Eigen::Matrix3Xd aligned_fibers(const Eigen::Matrix3Xd& a) {
  Eigen::Matrix3d T = Eigen::Matrix3d::Zero();  // Σ_b a_b a_bᵀ / |a_b|²
  for (Eigen::Index b = 0; b < a.cols(); ++b)
    if (a.col(b).squaredNorm() > 0.0) T += a.col(b) * a.col(b).transpose() / a.col(b).squaredNorm();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
  es.computeDirect(T);
  const Eigen::Vector3d r = es.eigenvectors().col(2);  // eigenvalues ascending
  Eigen::Matrix3Xd out = a;
  for (Eigen::Index b = 0; b < a.cols(); ++b)
    if (a.col(b).dot(r) < 0.0) out.col(b) = -a.col(b);
  return out;
}

void Assembler::set_fibers(const FiberField& field) {
  const Eigen::Index E = mesh_.num_elements(), N = mesh_.num_nodes();
  const int nq = geometry_.points_per_element(), nen = mesh_.nodes_per_element();
  const Eigen::Index expected = field.kind == FiberField::Kind::kUniform   ? 1
                                : field.kind == FiberField::Kind::kElement ? E
                                                                           : N;
  if (field.values.cols() != expected)
    throw InvalidArgument("assembler: the fiber field has " + std::to_string(field.values.cols()) +
                          " directions for " + std::to_string(expected));
  if (field.kind == FiberField::Kind::kUniform) {
    fibers_ = field.values;
  } else {
    fibers_.resize(3, E * nq);
    Eigen::Matrix3Xd ae(3, nen);
    for (Eigen::Index e = 0; e < E; ++e) {
      if (field.kind == FiberField::Kind::kNode) {  // the element's node axes, one sign
        for (int b = 0; b < nen; ++b) ae.col(b) = field.values.col(mesh_.elements(e, b));
        ae = aligned_fibers(ae);
      }
      for (int q = 0; q < nq; ++q) {
        // a₀(X_q) = Σ_b N_b(ξ_q) s_b a_b (per node) or the element's, then normalised
        Eigen::Vector3d a = Eigen::Vector3d::Zero();
        if (field.kind == FiberField::Kind::kElement)
          a = field.values.col(e);
        else
          for (int b = 0; b < nen; ++b) a += geometry_.shape_values()(q, b) * ae.col(b);
        fibers_.col(e * nq + q) = a;
      }
    }
  }
  for (Eigen::Index k = 0; k < fibers_.cols(); ++k) {
    const double n = fibers_.col(k).norm();
    if (!(n > 0.0) || !std::isfinite(n))
      throw InvalidArgument(
          "assembler: fiber direction must be non-zero and finite" +
          (fibers_.cols() > 1 ? " (" + mesh_.element_name(k / nq) + ")" : std::string()));
    fibers_.col(k) /= n;
    if (mesh_.dim == 2 && fibers_(2, k) != 0.0)
      throw InvalidArgument(
          "assembler: in 2D the fiber direction must lie in the plane (a0[2] = 0)");
  }
}

double Assembler::stiffness_scale() const {
  double s = 0.0;
  for (const auto& m : materials_) s = std::max(s, m->stiffness_scale());
  return s;
}

SparseMatrix Assembler::tangent_pattern() const {
  if (storage_ != AssemblerStorage::kFull)
    throw InvalidArgument("assembler: built without a tangent pattern (AssemblerStorage::kLean)");
  return pattern_;
}

Eigen::Matrix3d Assembler::deformation_gradient(const Eigen::VectorXd& u, Eigen::Index e,
                                                int q) const {
  // F = I + Σ_a u_a ⊗ ∇N_a (F33 = 1 in 2D: plane strain)
  const int dim = mesh_.dim;
  double buffer[3 * ReferenceGeometry::kMaxNodes];
  const double* G = buffer;  // G[a dim + J] = dN_a/dX_J
  if (geometry_.stores_gradients())
    G = geometry_.gradients(e, q).data();
  else
    geometry_.point_gradients(mesh_, e, q, buffer);
  Eigen::Matrix3d F = Eigen::Matrix3d::Identity();
  for (int a = 0; a < mesh_.nodes_per_element(); ++a) {
    const Eigen::Index n = mesh_.elements(e, a);
    for (int i = 0; i < dim; ++i)
      for (int J = 0; J < dim; ++J) F(i, J) += u[n * dim + i] * G[a * dim + J];
  }
  return F;
}

// Per-thread work arrays of the element kernel (never shared between threads).
struct Assembler::ElementWork {
  Eigen::MatrixXd Ue;        // dim by nen: the element's displacements
  Eigen::MatrixXd Gs, H;     // (dim nq) by nen: stacked ∇N_q and C^{ik}_q ∇N_q
  Eigen::MatrixXd Kb;        // nen by nen: one component block of K_e
  Eigen::MatrixXd Gq;        // dim by nen: ∇N_q when the geometry does not store it
  std::vector<Matrix9d> wC;  // w_q C_q per quadrature point
  ElementWork(int dim, int nen, int nq)
      : Ue(dim, nen), Gs(dim * nq, nen), H(dim * nq, nen), Kb(nen, nen), Gq(dim, nen), wC(nq) {}
};

template <bool kStored>
bool Assembler::element_kernel(const Eigen::VectorXd& u, const Eigen::MatrixXd& m_qp,
                               Eigen::Index e, double* energy, double* residual, double* tangent,
                               ElementWork& w) const {
  const int dim = mesh_.dim, nen = mesh_.nodes_per_element(), nd = nen * dim;
  const int nq = geometry_.points_per_element();
  for (int a = 0; a < nen; ++a)
    for (int i = 0; i < dim; ++i) w.Ue(i, a) = u[mesh_.elements(e, a) * dim + i];
  Eigen::Map<Eigen::MatrixXd> r(residual, dim, residual ? nen : 0);  // r(i, a) = r_e[a dim + i]
  if (residual) r.setZero();
  double We = 0.0;
  for (int q = 0; q < nq; ++q) {
    if constexpr (!kStored) geometry_.point_gradients(mesh_, e, q, w.Gq.data());
    // dim by nen: ∇N_a at X_q
    const Eigen::Ref<const Eigen::MatrixXd> G =
        kStored ? geometry_.gradients(e, q) : Eigen::Ref<const Eigen::MatrixXd>(w.Gq);
    // F = I + Σ_a u_a ⊗ ∇N_a (F33 = 1 in 2D: plane strain)
    Eigen::Matrix3d F = Eigen::Matrix3d::Identity();
    F.topLeftCorner(dim, dim).noalias() += w.Ue * G.transpose();
    if (!(F.determinant() > 0.0)) return false;
    const PointResponse pr = evaluate_point(*materials_[mesh_.element_region[e]], fiber(e, q),
                                            m_qp(e, q), F, tangent != nullptr);
    const double wq = geometry_.weights()(e, q);
    We += wq * pr.W;  // Π_e = Σ_q w_q det J0 (W + W_m)
    // r_e(a, i) = Σ_q w_q Σ_J P_iJ ∂N_a/∂X_J
    if (residual) r.noalias() += (wq * pr.P.topLeftCorner(dim, dim)) * G;
    if (tangent) {
      w.Gs.middleRows(q * dim, dim) = G;
      w.wC[q] = wq * pr.C;
    }
  }
  *energy = We;
  if (!tangent) return true;
  // K_e(a i, b k) = Σ_q Σ_{J,L} ∂N_a/∂X_J w_q C_{iJ,kL} ∂N_b/∂X_L, one component block
  // (i, k), i <= k, at a time: H = blockdiag_q(w_q C^{ik}_q) Gs, K^{ik} = Gsᵀ H (a GEMM);
  // K^{ki} = (K^{ik})ᵀ by symmetry. About 1/5 of the flops of Bᵀ C B with a dense 9-row B.
  for (int i = 0; i < dim; ++i)
    for (int k = i; k < dim; ++k) {
      for (int q = 0; q < nq; ++q) {
        Eigen::Matrix3d Cik;  // Cik(J, L) = w_q C(i + 3J, k + 3L)
        for (int J = 0; J < dim; ++J)
          for (int L = 0; L < dim; ++L) Cik(J, L) = w.wC[q](i + 3 * J, k + 3 * L);
        w.H.middleRows(q * dim, dim).noalias() =
            Cik.topLeftCorner(dim, dim) * w.Gs.middleRows(q * dim, dim);
      }
      w.Kb.noalias() = w.Gs.transpose() * w.H;
      for (int a = 0; a < nen; ++a)
        for (int b = 0; b < nen; ++b) {
          tangent[static_cast<size_t>(a * dim + i) * nd + b * dim + k] = w.Kb(a, b);
          tangent[static_cast<size_t>(b * dim + k) * nd + a * dim + i] = w.Kb(a, b);
        }
    }
  return true;
}

template <class AddPass>
bool Assembler::evaluate_passes(const Eigen::VectorXd& u, const Eigen::MatrixXd& m_qp,
                                double* energy, Eigen::VectorXd* residual, bool want_K,
                                AddPass&& add_pass) const {
  const int dim = mesh_.dim, nen = mesh_.nodes_per_element(), nd = nen * dim;
  const int nq = geometry_.points_per_element();
  const Eigen::Index E = mesh_.num_elements();
  if (u.size() != dofs_.num_dofs) throw InvalidArgument("assembler: u has the wrong size");
  if (m_qp.rows() != E || m_qp.cols() != nq)
    throw InvalidArgument("assembler: m_qp must be E by nq");
  const bool want_r = residual != nullptr;
  if (want_r) residual->setZero(dofs_.num_free);
  std::vector<double> element_energy(E, 0.0);
  std::vector<char> element_ok(E, 1);
  const Eigen::Index chunk = std::min(pass_elements(nd, want_r, want_K), E);
  std::vector<double> rbuf(want_r ? chunk * nd : 0);
  std::vector<double> kbuf(want_K ? chunk * nd * nd : 0);
  std::vector<ElementWork> work(softhd::max_threads(), ElementWork(dim, nen, nq));
  const bool stored = geometry_.stores_gradients();
  for (Eigen::Index start = 0; start < E; start += chunk) {
    const Eigen::Index n = std::min(chunk, E - start);
#pragma omp parallel for schedule(dynamic, 8) \
    num_threads(static_cast <int>(work.size())) if (n >= 8)
    for (Eigen::Index i = 0; i < n; ++i) {
      double* re = want_r ? &rbuf[i * nd] : nullptr;
      double* Ke = want_K ? &kbuf[i * nd * nd] : nullptr;
      element_ok[start + i] =
          stored ? element_kernel<true>(u, m_qp, start + i, &element_energy[start + i], re, Ke,
                                        work[thread_id()])
                 : element_kernel<false>(u, m_qp, start + i, &element_energy[start + i], re, Ke,
                                         work[thread_id()]);
    }
    // Serial scatter in element order.
    if (want_r) {
      for (Eigen::Index i = 0; i < n; ++i) {
        const Eigen::Index e = start + i;
        if (!element_ok[e]) continue;
        for (int a = 0; a < nen; ++a)
          for (int k = 0; k < dim; ++k) {
            const int f = dofs_.free_index[mesh_.elements(e, a) * dim + k];
            if (f >= 0) (*residual)[f] += rbuf[i * nd + a * dim + k];
          }
      }
    }
    if (want_K) add_pass(start, n, kbuf.data(), &element_ok[start]);
  }
  const bool ok = std::all_of(element_ok.begin(), element_ok.end(), [](char c) { return c != 0; });
  if (energy) {
    double total = 0.0;
    for (double We : element_energy) total += We;  // fixed order: deterministic
    *energy = ok ? total : std::numeric_limits<double>::infinity();
  }
  return ok;
}

bool Assembler::evaluate(const Eigen::VectorXd& u, const Eigen::MatrixXd& m_qp, double* energy,
                         Eigen::VectorXd* residual, SparseMatrix* tangent) const {
  if (tangent &&
      (storage_ != AssemblerStorage::kFull || tangent->nonZeros() != pattern_.nonZeros()))
    throw InvalidArgument("assembler: the tangent must come from tangent_pattern()");
  const int nd = mesh_.nodes_per_element() * mesh_.dim;
  double* Kval = tangent ? tangent->valuePtr() : nullptr;
  if (tangent) std::fill(Kval, Kval + tangent->nonZeros(), 0.0);
  return evaluate_passes(
      u, m_qp, energy, residual, tangent != nullptr,
      [&](Eigen::Index start, Eigen::Index n, const double* kbuf, const char* ok) {
        for (Eigen::Index i = 0; i < n; ++i) {
          if (!ok[i]) continue;
          const int* map = nz_map_[start + i].data();
          const double* Ke = &kbuf[i * nd * nd];
          for (int l = 0; l < nd * nd; ++l)
            if (map[l] >= 0) Kval[map[l]] += Ke[l];
        }
      });
}

bool Assembler::evaluate_elements(const Eigen::VectorXd& u, const Eigen::MatrixXd& m_qp,
                                  double* energy, Eigen::VectorXd* residual,
                                  ElementMatrixSink* tangent) const {
  return evaluate_passes(
      u, m_qp, energy, residual, tangent != nullptr,
      [&](Eigen::Index start, Eigen::Index n, const double* kbuf, const char* ok) {
        if (std::all_of(ok, ok + n, [](char c) { return c != 0; })) tangent->add(start, n, kbuf);
      });
}

Eigen::MatrixXd Assembler::jacobians(const Eigen::VectorXd& u) const {
  const int nq = geometry_.points_per_element();
  Eigen::MatrixXd J(mesh_.num_elements(), nq);
#pragma omp parallel for schedule(static) num_threads(softhd::max_threads())
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
#pragma omp parallel for schedule(static) num_threads(softhd::max_threads())
  for (Eigen::Index e = 0; e < mesh_.num_elements(); ++e)
    for (int q = 0; q < nq; ++q) {
      const Eigen::Matrix3d F = deformation_gradient(u, e, q);
      // ∇λ = Σ_a λ_a ⊗ ∇N_a, computed as "F − I" of λ
      const Eigen::Matrix3d Glam = deformation_gradient(lambda, e, q) - Eigen::Matrix3d::Identity();
      const Eigen::Vector3d a0 = fiber(e, q);
      s(e, q) = geometry_.weights()(e, q) * (F * a0).dot(Glam * a0);
    }
  return s;
}

}  // namespace softhd::fe
