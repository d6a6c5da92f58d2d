#pragma once
// CHOLMOD's settings and workspace block, started and finished with its owner (private to the
// library).  Started quiet and without an error handler: failures come back as return values and
// `common.status`, which the owner turns into its own errors.  An owner that also holds CHOLMOD
// objects derives from it and frees them in its destructor, which runs before this one finishes
// the block.
#include <mutex>

#include <cholmod.h>

namespace indentsim {

/// cholmod_l_analyze, one thread at a time.  CHOLMOD's orderings call METIS (nested dissection
/// always, its default strategy where AMD leaves much fill), and METIS keeps its random generator
/// in globals: two analyses at once in two threads -- runs in Python threads, a run and its
/// error estimate's companions -- interleave it, the orderings come out differently from one
/// process to the next, and so does the rounding of every factorization after them (measured:
/// P differing by 2e-14 between two runs of power_law.toml in two threads and the same run
/// alone).  Serialized, each analysis reseeds METIS and gets the ordering it gets alone.
inline cholmod_factor* analyze_serialized(cholmod_sparse* matrix, cholmod_common* common) {
  static std::mutex metis;
  const std::lock_guard<std::mutex> lock(metis);
  return cholmod_l_analyze(matrix, common);
}

struct CholmodCommon {
  cholmod_common common;

  CholmodCommon() {
    cholmod_l_start(&common);
    common.print = 0;
    common.error_handler = nullptr;
  }
  ~CholmodCommon() { cholmod_l_finish(&common); }
  CholmodCommon(const CholmodCommon&) = delete;
  CholmodCommon& operator=(const CholmodCommon&) = delete;
};

}  // namespace indentsim
