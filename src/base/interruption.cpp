#include "indentsim/base/interruption.hpp"

#include <csignal>

namespace indentsim {

namespace {
volatile std::sig_atomic_t requested_signal = 0;
}

void request_interruption(int signal) noexcept { requested_signal = signal; }
int interruption_requested() noexcept { return requested_signal; }
void clear_interruption() noexcept { requested_signal = 0; }

}  // namespace indentsim
