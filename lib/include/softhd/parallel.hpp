#pragma once
/// \file parallel.hpp
/// The number of threads of softhd's parallel loops (OpenMP: pair sums, element
/// assembly, per-point fields) and of the BLAS under the sparse factorisations.

namespace softhd {

/// Sets the OpenMP threads used by every later softhd call; 0 keeps OpenMP's default
/// (OMP_NUM_THREADS, else the number of cores). Also makes the BLAS single-threaded (see
/// limit_blas_threads). Throws InvalidArgument if threads < 0.
void set_threads(int threads);
/// The number of threads the next parallel loop will use.
int max_threads();
/// Makes an OpenBLAS (if that is the BLAS loaded) single-threaded. CHOLMOD's supernodes
/// on softhd's meshes are too small for BLAS threads to pay (bench_state solvers:
/// factorisation 0.17 s with 1 and 0.16 s with 2 OpenBLAS threads on the torsion mesh),
/// and idle OpenMP threads spinning after an assembly compete with them for the cores.
/// Called by NewtonSolver's constructor; harmless with any other BLAS.
void limit_blas_threads();

}  // namespace softhd
