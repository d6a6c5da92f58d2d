#pragma once
// CHOLMOD's settings and workspace block, started and finished with its owner (private to the
// library).  Started quiet and without an error handler: failures come back as return values and
// `common.status`, which the owner turns into its own errors.  An owner that also holds CHOLMOD
// objects derives from it and frees them in its destructor, which runs before this one finishes
// the block.
#include <cholmod.h>

namespace indentsim {

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
