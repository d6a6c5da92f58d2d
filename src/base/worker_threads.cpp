#include "indentsim/base/worker_threads.hpp"

#include <dlfcn.h>
#include <sched.h>

#include <algorithm>
#include <cstdlib>
#include <mutex>
#include <thread>

namespace indentsim {

namespace {

template <class Function>
Function find(const char* name) {
  return reinterpret_cast<Function>(dlsym(RTLD_DEFAULT, name));
}

/// The thread count an environment variable asks for; 0 when unset or not a positive number.
int asked(const char* variable) {
  const char* text = std::getenv(variable);
  const int n = text ? std::atoi(text) : 0;
  return n > 0 ? n : 0;
}

// The environment's count is applied explicitly, not only left to the library: a library reads
// its variable once, when it is loaded, and a host process (Python with NumPy, a Dask worker)
// may have loaded it before setting the variable.  The BLAS thread count changes the rounding of
// CHOLMOD's supernodal updates, so it must be what the run reports.  OpenBLAS's count is the
// process's.
int apply_blas_policy() {
  const int blas_threads = asked("OPENBLAS_NUM_THREADS") ? asked("OPENBLAS_NUM_THREADS") : 1;
  const auto set_blas = find<void (*)(int)>("openblas_set_num_threads");
  if (set_blas) set_blas(blas_threads);
  return set_blas || asked("OPENBLAS_NUM_THREADS") ? blas_threads : 0;
}

// OpenMP's settings belong to the thread that makes them (its ICVs), so each thread that runs a
// simulation -- the caller's, a companion's, a Python thread's -- makes its own.  CHOLMOD's
// supernodal factorization opens parallel regions with an explicit num_threads(4) (they clear its
// workspace), which omp_set_num_threads does not bound; on a 2-core machine the three extra
// threads woke and slept through every factorization (a sixth of a CHOLMOD run in futex calls
// and context switches).  Dynamic adjustment bounds them: libgomp then gives a region at most
// nthreads-var threads, here one.  The regions only clear memory, so the rounding is the same.
void apply_openmp_policy() {
  const int threads = asked("OMP_NUM_THREADS") ? asked("OMP_NUM_THREADS") : 1;
  if (const auto set_omp = find<void (*)(int)>("omp_set_num_threads")) set_omp(threads);
  if (threads == 1)
    if (const auto set_dynamic = find<void (*)(int)>("omp_set_dynamic")) set_dynamic(1);
}

}  // namespace

int limit_library_threads() {
  static std::once_flag once;
  static int blas_threads = 0;
  std::call_once(once, [] { blas_threads = apply_blas_policy(); });
  thread_local const bool openmp_applied = (apply_openmp_policy(), true);
  (void)openmp_applied;
  return blas_threads;
}

bool stop_idle_blas_workers() {
  if (limit_library_threads() != 1) return false;
  const auto shutdown = find<int (*)()>("blas_thread_shutdown_");
  return shutdown && shutdown() == 0;
}

int usable_cores() {
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof(set), &set) == 0) return std::max(1, CPU_COUNT(&set));
  return std::max(1u, std::thread::hardware_concurrency());
}

}  // namespace indentsim
