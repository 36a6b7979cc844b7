#include "softhd/fe/state_backend.hpp"

#include "softhd/enum_names.hpp"

namespace softhd::fe {

constexpr auto kStateBackendNames =
    enum_sequence<StateBackend::kPetscGamg>({"cholmod", "petsc-mumps", "petsc-gamg"});

std::string to_string(StateBackend backend) { return enum_name(kStateBackendNames, backend); }

StateBackend parse_state_backend(const std::string& name) {
  return enum_from_name(kStateBackendNames, name, "state backend");
}

bool petsc_backend_available() {
#if defined(SOFTHD_WITH_MPI) && SOFTHD_WITH_MPI
  return true;
#else
  return false;
#endif
}

}  // namespace softhd::fe
