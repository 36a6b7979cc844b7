# Every dependency comes from a Debian package; a missing one stops the
# configuration with the name of the package that provides it
# (scripts/install-deps.sh installs them all).
macro(softhd_require found_var debian_package what)
  if(NOT ${found_var})
    message(FATAL_ERROR
      "softhd needs ${what}: install the Debian package '${debian_package}' "
      "(apt-get install ${debian_package}, or run scripts/install-deps.sh)")
  endif()
endmacro()

find_package(Eigen3 3.4 CONFIG QUIET)
softhd_require(Eigen3_FOUND libeigen3-dev "Eigen 3.4")

find_package(nanoflann CONFIG QUIET)
softhd_require(nanoflann_FOUND libnanoflann-dev "nanoflann")

find_package(OpenMP QUIET COMPONENTS CXX)
softhd_require(OpenMP_CXX_FOUND libgomp1 "OpenMP (g++ ships it as libgomp)")

find_package(nlohmann_json 3 CONFIG QUIET)
softhd_require(nlohmann_json_FOUND nlohmann-json3-dev "nlohmann-json")

# Debian ships two NLoptConfig.cmake files (C and C++ APIs); softhd uses the
# C++ one, which defines NLopt::nlopt_cxx.
find_package(NLopt CONFIG QUIET
  PATHS /usr/lib/${CMAKE_LIBRARY_ARCHITECTURE}/cmake/nlopt_cxx NO_DEFAULT_PATH)
if(NOT TARGET NLopt::nlopt_cxx)
  find_package(NLopt CONFIG QUIET)
endif()
if(NOT TARGET NLopt::nlopt_cxx)
  set(NLopt_FOUND FALSE)
endif()
softhd_require(NLopt_FOUND libnlopt-cxx-dev "NLopt with its C++ API")

# MPI (SOFTHD_WITH_MPI only): Debian's Open MPI (libopenmpi-dev, openmpi-bin).
if(SOFTHD_WITH_MPI)
  find_package(MPI COMPONENTS CXX)
  softhd_require(MPI_FOUND libopenmpi-dev "MPI (SOFTHD_WITH_MPI=ON; or run scripts/install-deps.sh --mpi)")
  find_package(MPI REQUIRED COMPONENTS CXX)
endif()

# The Python module (python/): built when pybind11 and the Python headers are found, unless
# SOFTHD_BUILD_PYTHON is set OFF. Debian: pybind11-dev, python3-dev (and python3-numpy).
find_package(Python3 COMPONENTS Interpreter Development.Module QUIET)
if(Python3_Development.Module_FOUND)
  set(PYBIND11_FINDPYTHON ON)
  find_package(pybind11 CONFIG QUIET)
endif()
if(SOFTHD_SANITIZE OR SOFTHD_FUZZ)
  # An instrumented module needs an instrumented interpreter: the sanitizer and fuzz builds
  # leave the Python module out (its tests run in the main suite).
  option(SOFTHD_BUILD_PYTHON "Build the Python module softhd (pybind11)" OFF)
elseif(Python3_Development.Module_FOUND AND pybind11_FOUND)
  option(SOFTHD_BUILD_PYTHON "Build the Python module softhd (pybind11)" ON)
else()
  option(SOFTHD_BUILD_PYTHON "Build the Python module softhd (pybind11)" OFF)
  message(STATUS "softhd: the Python module is not built (needs the Debian packages "
    "pybind11-dev and python3-dev)")
endif()
if(SOFTHD_BUILD_PYTHON)
  softhd_require(Python3_Development.Module_FOUND python3-dev "the Python headers")
  softhd_require(pybind11_FOUND pybind11-dev "pybind11")
endif()

# SOFTHD_WITH_MPI: for the PETSc state backend, PETSc (cmake/SoftHDPetsc.cmake).
if(SOFTHD_WITH_MPI)
  include(SoftHDPetsc)
endif()

if(SOFTHD_BUILD_TESTS)
  find_package(GTest CONFIG QUIET)
  softhd_require(GTest_FOUND libgtest-dev "GoogleTest")
endif()

# SOFTHD_NATIVE: tune softhd's own targets (library, tools, tests, benchmarks, Python module)
# for the build machine. Private to each target: users of the installed library are not
# given -march=native (Eigen's alignment, the ABI-relevant part, is fixed in lib/).
set(SOFTHD_NATIVE_FLAGS "")
if(SOFTHD_NATIVE)
  include(CheckCXXCompilerFlag)
  check_cxx_compiler_flag(-march=native SOFTHD_HAS_MARCH_NATIVE)
  check_cxx_compiler_flag(-mno-avx512f SOFTHD_HAS_NO_AVX512)
  if(SOFTHD_HAS_MARCH_NATIVE)
    list(APPEND SOFTHD_NATIVE_FLAGS -march=native)
  endif()
  if(SOFTHD_HAS_NO_AVX512)
    # AVX2 at most: g++ 12 reports false -Wmaybe-uninitialized warnings inside
    # Eigen's AVX-512 reductions, and the pair kernel is bound by sqrt and division,
    # whose throughput AVX-512 does not raise on common CPUs.
    list(APPEND SOFTHD_NATIVE_FLAGS -mno-avx512f)
  endif()
endif()

# glibc's vector maths library (libmvec, part of libc6-dev): the dual tree's remainder
# bounds take their logarithms four at a time with it when softhd is built for AVX2
# (-march=native on today's x86 machines); otherwise std::log.
include(CheckCXXSourceCompiles)
string(REPLACE ";" " " CMAKE_REQUIRED_FLAGS "${SOFTHD_NATIVE_FLAGS}")
set(CMAKE_REQUIRED_LIBRARIES mvec)
check_cxx_source_compiles([=[
#include <immintrin.h>
#ifndef __AVX2__
#error "libmvec's 4-wide calls need AVX2"
#endif
extern "C" __m256d _ZGVdN4v_log(__m256d);
extern "C" __m256d _ZGVdN4v_log1p(__m256d);
int main() { return _mm256_cvtsd_f64(_ZGVdN4v_log1p(_ZGVdN4v_log(_mm256_set1_pd(3.0)))) > 0.0; }
]=] SOFTHD_HAVE_LIBMVEC)
unset(CMAKE_REQUIRED_FLAGS)
unset(CMAKE_REQUIRED_LIBRARIES)

# Per-target settings (no global flags): warnings, optional tuning and sanitizers.
function(softhd_target_defaults target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic ${SOFTHD_NATIVE_FLAGS})
  # softhd never reads errno after a math call; without this flag g++ cannot
  # vectorise sqrt in the pair loops (it must keep a scalar errno path).
  target_compile_options(${target} PRIVATE -fno-math-errno)
  if(SOFTHD_SANITIZE)
    target_compile_options(${target} PRIVATE -fsanitize=address,undefined -fno-omit-frame-pointer
      -fno-sanitize-recover=undefined)
    target_link_options(${target} PRIVATE -fsanitize=address,undefined)
  endif()
  if(SOFTHD_FUZZ)
    # Coverage instrumentation for libFuzzer everywhere; only fuzz targets link its main.
    target_compile_options(${target} PRIVATE -fsanitize=fuzzer-no-link)
    if(SOFTHD_FUZZ_IGNORELIST)  # the files left uninstrumented (clang's src: patterns)
      target_compile_options(${target} PRIVATE
        -fsanitize-coverage-ignorelist=${SOFTHD_FUZZ_IGNORELIST})
    endif()
  endif()
endfunction()

# CHOLMOD (SuiteSparse) for the sparse Cholesky of the FE tangent, used through Eigen's
# CholmodSupport. Debian 12's SuiteSparse 5 ships neither CMake configs nor .pc files;
# cmake/FindSoftHDCholmod.cmake defines softhd::cholmod (softhdConfig.cmake reuses it).
include(FindSoftHDCholmod)
softhd_require(CHOLMOD_FOUND libsuitesparse-dev "CHOLMOD (SuiteSparse)")

# ROL (Trilinos) for the trust-region Newton–CG optimiser (Algorithm::newton). Required, like
# NLopt: the library's optimiser layer is built with both backends. Debian's Trilinos CMake
# configs are broken; cmake/FindSoftHDRol.cmake defines softhd::rol (softhdConfig.cmake reuses it).
include(FindSoftHDRol)
softhd_require(ROL_FOUND "libtrilinos-rol-dev libtrilinos-teuchos-dev libtrilinos-kokkos-dev"
  "ROL (Trilinos' optimisation library, with Teuchos and the Kokkos headers)")
