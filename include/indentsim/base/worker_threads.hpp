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

/// Applies the policy above: OpenBLAS's once per process, OpenMP's once per calling thread (its
/// settings are the thread's own; with one thread asked for, dynamic adjustment is switched on so
/// that CHOLMOD's regions with an explicit num_threads(4) get one thread too).  Returns the BLAS
/// threads the policy left in place (1, or what the environment asked for; 0 when unknown).
int limit_library_threads();

/// For a process with one thread of its own (the CLI), at its start: applies the policy and, when
/// it leaves OpenBLAS one thread, stops OpenBLAS's idle workers (blas_thread_shutdown_).  The
/// pthreads build starts them when it loads, and they spin on sched_yield for up to its timeout
/// waiting for work that one-thread BLAS never gives them: measured, 1.3 cores busy through a
/// 0.3 s elastic run, 0.96 without.  Not for a host whose other threads may be inside the BLAS
/// (Python with NumPy): a shutdown would take their workers away mid-call.  True if it stopped them.
bool stop_idle_blas_workers();

/// The cores this process may run on: its CPU affinity (what Slurm, taskset or a container's
/// cpuset grant), not the machine's count; at least 1.
int usable_cores();

}  // namespace indentsim
