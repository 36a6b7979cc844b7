#pragma once
/// \file state_backend.hpp
/// Which engine solves the state equation: the serial Newton with CHOLMOD factorisations
/// (fe/newton.hpp), or the distributed Newton of fe/petsc_state.hpp on PETSc with MUMPS
/// (direct) or CG preconditioned by smoothed-aggregation AMG (GAMG, iterative). The PETSc
/// backends exist only in a build with SOFTHD_WITH_MPI=ON (petsc_backend_available()).

#include <string>

namespace softhd::fe {

/// The state solver's engine.
enum class StateBackend {
  kCholmod,     ///< serial Newton, CHOLMOD factorisations reused as PCG preconditioners
  kPetscMumps,  ///< distributed Newton, MUMPS LDLᵀ of the tangent (with an inertia check)
  kPetscGamg,   ///< distributed Newton, CG + GAMG with the rigid-body near-null space
};

/// "cholmod", "petsc-mumps", "petsc-gamg".
std::string to_string(StateBackend backend);
/// Inverse of to_string; throws InvalidArgument listing the valid names.
StateBackend parse_state_backend(const std::string& name);
/// True if this build has the PETSc backends (SOFTHD_WITH_MPI=ON).
bool petsc_backend_available();

}  // namespace softhd::fe
