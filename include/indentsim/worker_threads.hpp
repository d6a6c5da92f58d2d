#pragma once
// The threads of the libraries under the solver.
//
// A run is one thread of indentsim's own.  The BLAS that CHOLMOD and LAPACK call (Debian's
// OpenBLAS, pthreads build) and the OpenMP runtime that SuiteSparse pulls in start worker threads
// that spin-wait (sched_yield) between calls: on a 2-core machine they took 0.25 s of CPU in a
// 0.37 s elastic run for a wall-time gain within the noise, and with two runs side by side (a
// sweep's two workers) each run's spinning threads steal the other's core.  So indentsim asks
// both for one thread, unless the user's environment sets OPENBLAS_NUM_THREADS or OMP_NUM_THREADS
// (then theirs is applied, whenever it was set: a Python host may set it after loading OpenBLAS).  The calls are looked up at run time: a build against another BLAS has
// nothing to set.
namespace indentsim {

/// Applies the policy above (once per process; later calls do nothing).  Returns the BLAS
/// threads the policy left in place (1, or what the environment asked for; 0 when unknown).
int limit_library_threads();

}  // namespace indentsim
