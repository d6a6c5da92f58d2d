#pragma once
// Stopping a run from outside (SIGINT, SIGTERM) within an increment: a signal handler records the
// request; the Newton solver's residual callback sees it and aborts KINSOL; the simulation puts
// itself back to the last converged (reported) increment and throws Interrupted, so that the
// caller can checkpoint exactly that increment.
#include <exception>

namespace indentsim {

/// Records a request to stop (async-signal-safe: meant to be called from a signal handler).
void request_interruption(int signal) noexcept;
/// The signal of a pending request, or 0.
int interruption_requested() noexcept;
/// Forgets a request (a caller that handled it and goes on, e.g. a test).
void clear_interruption() noexcept;

/// Thrown by Simulation::advance_to/run when a stop was requested; the simulation is then at its
/// last reported increment.
class Interrupted : public std::exception {
public:
  explicit Interrupted(int signal) : signal_(signal) {}
  int signal() const { return signal_; }
  const char* what() const noexcept override { return "interrupted by a signal"; }

private:
  int signal_;
};

}  // namespace indentsim
