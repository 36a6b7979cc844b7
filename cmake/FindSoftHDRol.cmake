# Finds ROL (Trilinos' optimisation library) and the Teuchos libraries it needs, and defines
# the imported target softhd::rol; sets ROL_FOUND. Debian's Trilinos CMake configs are not
# usable (ROLConfig.cmake names targets of Trilinos packages that are not installed), so the
# headers and libraries are found directly. ROL's headers include Kokkos' (libtrilinos-kokkos-dev).
find_path(ROL_INCLUDE_DIR ROL_TypeB_LinMoreAlgorithm.hpp PATH_SUFFIXES trilinos)
find_path(ROL_KOKKOS_INCLUDE_DIR Kokkos_Macros.hpp PATH_SUFFIXES trilinos)
set(ROL_LIBRARIES)
set(ROL_FOUND FALSE)
set(_softhd_rol_missing FALSE)
foreach(lib trilinos_rol trilinos_teuchoscore trilinos_teuchosparameterlist trilinos_teuchoscomm
    trilinos_teuchosnumerics)
  find_library(ROL_LIBRARY_${lib} ${lib})
  if(ROL_LIBRARY_${lib})
    list(APPEND ROL_LIBRARIES ${ROL_LIBRARY_${lib}})
  else()
    set(_softhd_rol_missing TRUE)
  endif()
endforeach()
if(ROL_INCLUDE_DIR AND ROL_KOKKOS_INCLUDE_DIR AND NOT _softhd_rol_missing)
  set(ROL_FOUND TRUE)
  if(NOT TARGET softhd::rol)
    add_library(softhd::rol INTERFACE IMPORTED)
    # SYSTEM: ROL's headers are not -Wall -Wextra -Wpedantic clean.
    set_target_properties(softhd::rol PROPERTIES INTERFACE_SYSTEM_INCLUDE_DIRECTORIES
      "${ROL_INCLUDE_DIR}")
    target_include_directories(softhd::rol INTERFACE ${ROL_INCLUDE_DIR})
    target_link_libraries(softhd::rol INTERFACE ${ROL_LIBRARIES})
  endif()
endif()
unset(_softhd_rol_missing)
