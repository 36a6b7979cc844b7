#pragma once
/// \file parallel.hpp
/// The number of threads of softhd's parallel loops (OpenMP: pair sums, element
/// assembly, per-point fields) and of the BLAS under the sparse factorisations.

namespace softhd {

/// The most OpenMP threads softhd runs a loop with. More threads than cores only compete
/// for them, and a few thousand make libgomp fail (a segfault inside GOMP_parallel, or an
/// abort for lack of memory). Every `threads` setting (set_threads, HausdorffOptions::threads,
/// the CLI's --threads, Python's threads=) above it is refused (check_threads); OpenMP's
/// default above it (OMP_NUM_THREADS=100000) is clamped to it (max_threads).
constexpr int kMaxThreads = 1024;

/// Throws InvalidArgument naming `threads` and the range [0, kMaxThreads] unless
/// 0 <= threads <= kMaxThreads (0: OpenMP's default).
void check_threads(int threads);
/// Sets the OpenMP threads used by every later softhd call from this thread; 0 keeps
/// OpenMP's default (OMP_NUM_THREADS, else the number of cores, at most kMaxThreads). Also
/// makes the BLAS single-threaded (see limit_blas_threads). Throws InvalidArgument unless
/// 0 <= threads <= kMaxThreads (check_threads).
void set_threads(int threads);
/// The number of threads the next parallel loop will use: the count of set_threads, else
/// OpenMP's default (OMP_NUM_THREADS, else the number of cores), clamped to kMaxThreads.
int max_threads();
/// The threads of a loop asked for `threads` (a `threads` option): `threads` if > 0, else
/// max_threads(); 1 without OpenMP. Throws InvalidArgument as check_threads.
int resolve_threads(int threads);
/// The calling thread's number in the current OpenMP team (0 outside one, or without OpenMP).
int thread_id();
/// Makes an OpenBLAS (if that is the BLAS loaded) single-threaded. CHOLMOD's supernodes
/// on softhd's meshes are too small for BLAS threads to pay (bench_state solvers:
/// factorisation 0.17 s with 1 and 0.16 s with 2 OpenBLAS threads on the torsion mesh),
/// and idle OpenMP threads spinning after an assembly compete with them for the cores.
/// Called by NewtonSolver's constructor; harmless with any other BLAS.
void limit_blas_threads();

}  // namespace softhd
