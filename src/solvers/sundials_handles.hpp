#pragma once
// RAII ownership of every SUNDIALS object the solver uses, in the order SUNDIALS' own
// examples create them: context, vectors, matrix, linear solver, KINSOL memory.
// Private to the library (the public headers do not include SUNDIALS).
#include <memory>
#include <stdexcept>
#include <string>

#include <kinsol/kinsol.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunmatrix/sunmatrix_sparse.h>

namespace indentsim::sundials {

inline void check(int flag, const char* call) {
  if (flag < 0) throw std::runtime_error(std::string(call) + " failed with flag " + std::to_string(flag));
}

class Context {
public:
  Context() { check(SUNContext_Create(nullptr, &ctx_), "SUNContext_Create"); }
  ~Context() { SUNContext_Free(&ctx_); }
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
  operator SUNContext() const { return ctx_; }

private:
  SUNContext ctx_ = nullptr;
};

struct VectorDeleter {
  void operator()(N_Vector v) const { N_VDestroy(v); }
};
using Vector = std::unique_ptr<std::remove_pointer_t<N_Vector>, VectorDeleter>;

inline Vector make_serial_vector(sunindextype length, SUNContext ctx) {
  Vector v(N_VNew_Serial(length, ctx));
  if (!v) throw std::runtime_error("N_VNew_Serial failed");
  return v;
}

struct MatrixDeleter {
  void operator()(SUNMatrix m) const { SUNMatDestroy(m); }
};
using Matrix = std::unique_ptr<std::remove_pointer_t<SUNMatrix>, MatrixDeleter>;

struct LinearSolverDeleter {
  void operator()(SUNLinearSolver s) const { SUNLinSolFree(s); }
};
using LinearSolver = std::unique_ptr<std::remove_pointer_t<SUNLinearSolver>, LinearSolverDeleter>;

class KinsolMemory {
public:
  explicit KinsolMemory(SUNContext ctx) : mem_(KINCreate(ctx)) {
    if (!mem_) throw std::runtime_error("KINCreate failed");
  }
  ~KinsolMemory() { KINFree(&mem_); }
  KinsolMemory(const KinsolMemory&) = delete;
  KinsolMemory& operator=(const KinsolMemory&) = delete;
  operator void*() const { return mem_; }

private:
  void* mem_ = nullptr;
};

}  // namespace indentsim::sundials
