#include "sparse_direct_solver.hpp"

#include <stdexcept>

namespace indentsim {

namespace {
SUNLinearSolver_Type direct_type(SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; }
int keep_analysis(SUNLinearSolver) { return SUNLS_SUCCESS; }
int free_shell_only(SUNLinearSolver s) {
  SUNLinSolFreeEmpty(s);
  return SUNLS_SUCCESS;
}
}  // namespace

sundials::LinearSolver make_direct_solver_shell(SUNContext context, void* content,
                                                SUNLinearSolver_ID (*id)(SUNLinearSolver),
                                                int (*setup)(SUNLinearSolver, SUNMatrix),
                                                int (*solve)(SUNLinearSolver, SUNMatrix, N_Vector, N_Vector, sundials::Real),
                                                sunindextype (*last_flag)(SUNLinearSolver)) {
  sundials::LinearSolver shell(SUNLinSolNewEmpty(context));
  if (!shell) throw std::runtime_error("SUNLinSolNewEmpty failed");
  SUNLinearSolver s = shell.get();
  s->content = content;
  s->ops->gettype = direct_type;
  s->ops->getid = id;
  s->ops->initialize = keep_analysis;
  s->ops->setup = setup;
  s->ops->solve = solve;
  s->ops->lastflag = last_flag;
  s->ops->free = free_shell_only;
  return shell;
}

}  // namespace indentsim
