// The stop request Ctrl-C and SIGTERM raise.
#include "interrupt.hpp"

#include <atomic>
#include <unistd.h>

namespace mipnerf::cli {
namespace {

std::atomic<bool> g_stop_requested{false};

extern "C" void on_interrupt(int) {
  if (g_stop_requested.exchange(true)) _exit(130);  // a second Ctrl-C stops at once
}

}  // namespace

StopOnInterrupt::StopOnInterrupt() {
  g_stop_requested = false;
  previous_int_ = std::signal(SIGINT, on_interrupt);
  // A scheduler's (or mpirun's) SIGTERM: the same clean stop.
  previous_term_ = std::signal(SIGTERM, on_interrupt);
}

StopOnInterrupt::~StopOnInterrupt() {
  std::signal(SIGINT, previous_int_);
  std::signal(SIGTERM, previous_term_);
}

bool StopOnInterrupt::requested() { return g_stop_requested.load(); }

}  // namespace mipnerf::cli
