#include "indentsim/worker_threads.hpp"

#include <dlfcn.h>

#include <cstdlib>
#include <mutex>

namespace indentsim {

namespace {

template <class Function>
Function find(const char* name) {
  return reinterpret_cast<Function>(dlsym(RTLD_DEFAULT, name));
}

int apply_policy() {
  int blas_threads = 0;
  if (const char* asked = std::getenv("OPENBLAS_NUM_THREADS")) {
    blas_threads = std::atoi(asked);
  } else if (auto set = find<void (*)(int)>("openblas_set_num_threads")) {
    set(1);
    blas_threads = 1;
  }
  if (!std::getenv("OMP_NUM_THREADS"))
    if (auto set = find<void (*)(int)>("omp_set_num_threads")) set(1);
  return blas_threads;
}

}  // namespace

int limit_library_threads() {
  static std::once_flag once;
  static int blas_threads = 0;
  std::call_once(once, [] { blas_threads = apply_policy(); });
  return blas_threads;
}

}  // namespace indentsim
