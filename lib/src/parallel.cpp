#include "softhd/parallel.hpp"

#include <dlfcn.h>

#include <algorithm>
#include <string>

#include "softhd/error.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace softhd {

void check_threads(int threads) {
  if (threads < 0 || threads > kMaxThreads)
    throw InvalidArgument("threads must be from 0 to " + std::to_string(kMaxThreads) +
                          " (0: OMP_NUM_THREADS, else all cores), got " + std::to_string(threads));
}

void set_threads(int threads) {
  check_threads(threads);
#ifdef _OPENMP
  if (threads > 0) omp_set_num_threads(threads);
#endif
  limit_blas_threads();
}

int max_threads() {
#ifdef _OPENMP
  return std::min(omp_get_max_threads(), kMaxThreads);
#else
  return 1;
#endif
}

int thread_id() {
#ifdef _OPENMP
  return omp_get_thread_num();
#else
  return 0;
#endif
}

int resolve_threads(int threads) {
  check_threads(threads);
#ifdef _OPENMP
  return threads > 0 ? threads : max_threads();
#else
  return 1;
#endif
}

void limit_blas_threads() {
  // Looked up at run time: the BLAS behind libblas.so.3 is chosen by the system.
  using SetThreads = void (*)(int);
  static const auto set =
      reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
  if (set) set(1);
}

}  // namespace softhd
