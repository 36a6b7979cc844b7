#include "softhd/parallel.hpp"

#include <dlfcn.h>

#include "softhd/error.hpp"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace softhd {

void set_threads(int threads) {
  if (threads < 0) throw InvalidArgument("threads must be >= 0");
#ifdef _OPENMP
  if (threads > 0) omp_set_num_threads(threads);
#endif
  limit_blas_threads();
}

int max_threads() {
#ifdef _OPENMP
  return omp_get_max_threads();
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
