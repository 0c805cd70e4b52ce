// Ctrl-C and SIGTERM as a clean stop request, for the commands that run until told to stop (train, view): while a
// StopOnInterrupt exists the first signal sets a flag the command polls; a second one ends the process at once.
#pragma once

#include <csignal>

namespace mipnerf::cli {

class StopOnInterrupt {
 public:
  StopOnInterrupt();   // clears the flag and installs the handlers
  ~StopOnInterrupt();  // restores the previous handlers
  StopOnInterrupt(const StopOnInterrupt&) = delete;
  StopOnInterrupt& operator=(const StopOnInterrupt&) = delete;
  static bool requested();

 private:
  void (*previous_int_)(int) = SIG_DFL;
  void (*previous_term_)(int) = SIG_DFL;
};

}  // namespace mipnerf::cli
