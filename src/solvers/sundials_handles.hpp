#pragma once
// RAII ownership of every SUNDIALS object the solver uses, in the order SUNDIALS' own
// examples create them: context, vectors, matrix, linear solver, KINSOL memory.
// Private to the library (the public headers do not include SUNDIALS).
//
// The names SUNDIALS changed between its versions 6 and 7 are spelled in this file only, so that
// an upgrade touches this file alone: the real type (realtype went in 7; sunrealtype exists since
// 6.0), SUNContext_Create's communicator argument, and the error handler (KINSetErrHandlerFn in 6,
// SUNContext_PushErrHandler in 7).  Debian 12 ships 6.4.1, which the tests run; the 7 branches
// follow SUNDIALS 7's documentation and are not compiled here.
#include <memory>
#include <stdexcept>
#include <string>

#include <kinsol/kinsol.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_config.h>
#include <sundials/sundials_context.h>
#include <sunmatrix/sunmatrix_sparse.h>

namespace indentsim::sundials {

/// SUNDIALS' floating-point and boolean types, as every callback of ours spells them.
using Real = sunrealtype;
using Boolean = sunbooleantype;

inline void check(int flag, const char* call) {
  if (flag < 0) throw std::runtime_error(std::string(call) + " failed with flag " + std::to_string(flag));
}

class Context {
public:
#if SUNDIALS_VERSION_MAJOR >= 7
  Context() { check(SUNContext_Create(SUN_COMM_NULL, &ctx_), "SUNContext_Create"); }
#else
  Context() { check(SUNContext_Create(nullptr, &ctx_), "SUNContext_Create"); }
#endif
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

/// Where KINSOL's error messages go: `sink(message, data)` with "module/function: message".  The
/// route must outlive the KINSOL memory it is attached to.
struct ErrorRoute {
  void (*sink)(const std::string& message, void* data) = nullptr;
  void* data = nullptr;
};

inline void route_errors(void* kinsol_memory, SUNContext context, ErrorRoute* route) {
#if SUNDIALS_VERSION_MAJOR >= 7
  (void)kinsol_memory;
  auto handler = [](int, const char* function, const char*, const char* msg, SUNErrCode, void* data, SUNContext) {
    auto* r = static_cast<ErrorRoute*>(data);
    r->sink(std::string("KINSOL/") + function + ": " + msg, r->data);
  };
  check(SUNContext_PushErrHandler(context, handler, route), "SUNContext_PushErrHandler");
#else
  (void)context;
  auto handler = [](int, const char* module, const char* function, char* msg, void* data) {
    auto* r = static_cast<ErrorRoute*>(data);
    r->sink(std::string(module) + "/" + function + ": " + msg, r->data);
  };
  check(KINSetErrHandlerFn(kinsol_memory, handler, route), "KINSetErrHandlerFn");
#endif
}

}  // namespace indentsim::sundials
