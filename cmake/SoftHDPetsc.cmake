# The PETSc state backend (SOFTHD_WITH_MPI=ON; lib/src/fe/petsc/, docs/scaling_state.md):
# Debian's petsc-dev (PETSc 3.18 with MUMPS, hypre and GAMG), found through its pkg-config
# module "PETSc". softhd_use_petsc(target) gives a target PETSc's headers and libraries
# (privately: softhd's public headers do not include PETSc).
find_package(PkgConfig QUIET)
if(PkgConfig_FOUND)
  pkg_check_modules(PETSC QUIET PETSc)
endif()
softhd_require(PETSC_FOUND petsc-dev "PETSc (the state backend of SOFTHD_WITH_MPI)")

function(softhd_use_petsc target)
  target_include_directories(${target} SYSTEM PRIVATE ${PETSC_INCLUDE_DIRS})
  target_link_libraries(${target} PRIVATE ${PETSC_LINK_LIBRARIES} MPI::MPI_CXX)
endfunction()
