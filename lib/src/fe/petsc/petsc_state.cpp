#include "softhd/fe/petsc_state.hpp"

#include <mpi.h>

#include "petsc_newton.hpp"
#include "petsc_system.hpp"
#include "softhd/error.hpp"
#include "softhd/fe/adjoint.hpp"
#include "softhd/fe/control.hpp"

namespace softhd::fe {

using petsc_detail::DistributedNewton;
using petsc_detail::DistributedSystem;

void PetscStateOptions::validate() const {
  newton.validate();
  if (backend != StateBackend::kPetscMumps && backend != StateBackend::kPetscGamg)
    throw InvalidArgument("PETSc state options: backend must be petsc-mumps or petsc-gamg");
  if (max_krylov_iterations < 1)
    throw InvalidArgument("PETSc state options: max_krylov_iterations must be >= 1");
}

namespace {

PetscStateOptions validated(PetscStateOptions options) {
  options.validate();
  return options;
}

}  // namespace

struct PetscStateSolver::Impl {
  Impl(const Body& body, const PetscStateOptions& options)
      : options(validated(options)),
        system(body, options.backend, options.max_krylov_iterations),
        control(system.assembler().mesh(), system.assembler().geometry(), body.control_kind,
                body.control_regions),
        global_controls(body.control_kind == ControlKind::kVertex
                            ? system.part().num_global_vertices
                            : system.part().num_global_elements),
        newton(system, options.newton),
        u(Eigen::VectorXd::Zero(system.owned())),
        m_qp(Eigen::MatrixXd::Zero(system.assembler().mesh().num_elements(),
                                   system.assembler().geometry().points_per_element())) {}

  /// The part's ids of the global controls (vertices or elements).
  const std::vector<int>& control_ids() const {
    return control.kind() == ControlKind::kVertex ? system.part().global_vertex
                                                  : system.part().global_element;
  }
  /// Sums per-part E by nq values into the whole mesh's (global element order).
  Eigen::MatrixXd gather_elements(const Eigen::MatrixXd& local) const {
    Eigen::MatrixXd all = Eigen::MatrixXd::Zero(system.part().num_global_elements, local.cols());
    for (Eigen::Index e = 0; e < local.rows(); ++e)
      all.row(system.part().global_element[e]) = local.row(e);
    MPI_Allreduce(MPI_IN_PLACE, all.data(), static_cast<int>(all.size()), MPI_DOUBLE, MPI_SUM,
                  PETSC_COMM_WORLD);
    return all;
  }

  PetscStateOptions options;
  DistributedSystem system;
  ControlSpace control;  ///< the part's
  Eigen::Index global_controls;
  DistributedNewton newton;
  Eigen::VectorXd u;     ///< owned rows
  Eigen::MatrixXd m_qp;  ///< the part's control at its quadrature points
  bool solved = false;   ///< the state is the last solve's (not set since)
};

PetscStateSolver::PetscStateSolver(const Body& body, PetscStateOptions options)
    : impl_(std::make_unique<Impl>(body, options)) {}

PetscStateSolver::~PetscStateSolver() = default;

NewtonSummary PetscStateSolver::solve(const Eigen::VectorXd& m) {
  Impl& s = *impl_;
  if (m.size() != s.global_controls)
    throw InvalidArgument("PETSc state: the control has " + std::to_string(m.size()) +
                          " values, the scene " + std::to_string(s.global_controls));
  const std::vector<int>& ids = s.control_ids();
  Eigen::VectorXd local(s.control.size());
  for (Eigen::Index k = 0; k < local.size(); ++k) local[k] = m[ids[k]];
  s.solved = true;
  return s.newton.solve(s.control.to_quadrature(local), &s.u, &s.m_qp);
}

GridSequencingReport PetscStateSolver::grid_sequenced_start(const Body& body,
                                                            const Eigen::VectorXd& m,
                                                            const GridSequencingOptions& options) {
  Impl& s = *impl_;
  options.validate();
  GridSequencingReport report;
  const MeshHierarchy levels = grid_hierarchy(body, options);
  if (m.size() != s.global_controls)
    throw InvalidArgument("grid sequencing: m must have one value per control");
  s.u.setZero();
  s.m_qp.setZero();
  s.solved = false;
  if (levels.size() == 1) return report;
  const Mesh body_mesh = body.make_mesh();
  Mesh coarse_mesh;
  State coarse;
  if (!solve_coarse_levels(levels, body_mesh, body.control_kind, m, s.options.newton, &report,
                           &coarse_mesh, &coarse)) {
    report.fell_back_to_rest = true;
    return report;
  }
  // Onto the whole body's nodes (a P1/Q1 level transfers to the mesh of its own cells, not
  // to a slab of it), then this rank's rows.
  const Eigen::VectorXd u = prolongate(coarse_mesh, coarse.u, body_mesh);
  const std::vector<std::int64_t>& dofs = s.system.numbering().owned_global_dof;
  for (Eigen::Index i = 0; i < s.u.size(); ++i) s.u[i] = u[dofs[i]];
  const std::vector<int>& ids = s.control_ids();
  Eigen::VectorXd local(s.control.size());
  for (Eigen::Index k = 0; k < local.size(); ++k) local[k] = m[ids[k]];
  s.m_qp = s.control.to_quadrature(local);  // the fine solve starts at full load
  return report;
}

bool PetscStateSolver::converged() const { return impl_->solved && impl_->newton.converged(); }

StateBackend PetscStateSolver::backend() const { return impl_->options.backend; }

Eigen::Index PetscStateSolver::free_dofs() const { return impl_->system.numbering().num_global; }

State PetscStateSolver::state() const { return {displacement(), control_at_quadrature()}; }

void PetscStateSolver::set_state(const State& state) {
  Impl& s = *impl_;
  const petsc_detail::Partition& part = s.system.part();
  if (state.u.size() != part.num_global_nodes * part.mesh.dim ||
      state.m_qp.rows() != part.num_global_elements || state.m_qp.cols() != s.m_qp.cols())
    throw InvalidArgument("PETSc state: set_state with a state of another problem");
  const std::vector<std::int64_t>& dofs = s.system.numbering().owned_global_dof;
  for (Eigen::Index i = 0; i < s.u.size(); ++i) s.u[i] = state.u[dofs[i]];
  for (Eigen::Index e = 0; e < s.m_qp.rows(); ++e)
    s.m_qp.row(e) = state.m_qp.row(part.global_element[e]);
  s.solved = false;  // the kept tangent is not this state's
}

void PetscStateSolver::reset() {
  impl_->newton.reset();
  impl_->solved = false;
}

int PetscStateSolver::adjoint_factorizations() const { return impl_->newton.adjoint_attempts(); }

Eigen::VectorXd PetscStateSolver::sensitivity(const Eigen::VectorXd&) {
  throw InvalidArgument(
      "state solver: Hessian-vector products are not available with the petsc backend");
}

Eigen::VectorXd PetscStateSolver::hessian_product(const Eigen::VectorXd&, const Eigen::VectorXd&,
                                                  const Eigen::VectorXd&, HessianPart) {
  throw InvalidArgument(
      "state solver: Hessian-vector products are not available with the petsc backend");
}

Eigen::VectorXd PetscStateSolver::displacement() const {
  const Impl& s = *impl_;
  const int dim = s.system.part().mesh.dim;
  Eigen::VectorXd all = Eigen::VectorXd::Zero(s.system.part().num_global_nodes * dim);
  const std::vector<std::int64_t>& dofs = s.system.numbering().owned_global_dof;
  for (size_t i = 0; i < dofs.size(); ++i) all[dofs[i]] = s.u[static_cast<Eigen::Index>(i)];
  MPI_Allreduce(MPI_IN_PLACE, all.data(), static_cast<int>(all.size()), MPI_DOUBLE, MPI_SUM,
                PETSC_COMM_WORLD);
  return all;
}

Eigen::VectorXd PetscStateSolver::gradient(const Eigen::VectorXd& g) {
  Impl& s = *impl_;
  const Eigen::Index num_dofs = s.system.part().num_global_nodes * s.system.part().mesh.dim;
  if (g.size() != num_dofs)
    throw InvalidArgument("PETSc state: g must have " + std::to_string(num_dofs) + " entries");
  if (!converged()) throw InvalidArgument("PETSc state: gradient() needs a converged solve");
  const std::vector<std::int64_t>& dofs = s.system.numbering().owned_global_dof;
  Eigen::VectorXd b(s.system.owned());
  for (Eigen::Index i = 0; i < b.size(); ++i) b[i] = g[dofs[i]];
  const Eigen::VectorXd lambda = s.newton.solve_converged_tangent(b);
  const Eigen::VectorXd local = control_gradient(
      s.system.assembler(), s.control, s.system.local_vector(s.u), s.system.local_vector(lambda));
  Eigen::VectorXd all = Eigen::VectorXd::Zero(s.global_controls);
  const std::vector<int>& ids = s.control_ids();
  for (Eigen::Index k = 0; k < local.size(); ++k) all[ids[k]] += local[k];
  MPI_Allreduce(MPI_IN_PLACE, all.data(), static_cast<int>(all.size()), MPI_DOUBLE, MPI_SUM,
                PETSC_COMM_WORLD);
  return all;
}

double PetscStateSolver::energy() const {
  const Impl& s = *impl_;
  double e = 0.0;
  s.system.assembler().evaluate(s.system.local_vector(s.u), s.m_qp, &e, nullptr, nullptr);
  return s.system.sum(e);
}

double PetscStateSolver::deformed_volume() const {
  const Impl& s = *impl_;
  return s.system.sum(s.system.assembler().deformed_volume(s.system.local_vector(s.u)));
}

double PetscStateSolver::min_jacobian() const {
  const Impl& s = *impl_;
  return s.system.min(s.system.assembler().min_jacobian(s.system.local_vector(s.u)));
}

Eigen::MatrixXd PetscStateSolver::control_at_quadrature() const {
  return impl_->gather_elements(impl_->m_qp);
}

Eigen::MatrixXd PetscStateSolver::jacobians() const {
  const Impl& s = *impl_;
  return s.gather_elements(s.system.assembler().jacobians(s.system.local_vector(s.u)));
}

PetscStateLayout PetscStateSolver::layout() const {
  const DistributedSystem& sys = impl_->system;
  PetscStateLayout l;
  l.rank = sys.part().rank;
  l.size = sys.part().size;
  l.cut_axis = sys.part().axis;
  l.local_elements = sys.assembler().mesh().num_elements();
  l.owned_rows = sys.owned();
  l.global_rows = sys.numbering().num_global;
  l.block_size = sys.block_size();
  return l;
}

}  // namespace softhd::fe
