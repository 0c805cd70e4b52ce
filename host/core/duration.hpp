// Durations for people ("1h02m", "3m07s", "12s"): shared by the CLI's progress line and the library's
// messages (the GEMM tuner reports how long a step took through its log callback).
#pragma once

#include <string>

namespace mipnerf {

// Rounded to whole seconds; "?" for a negative or non-finite value (an unknown estimate).
std::string format_duration(double seconds);

}  // namespace mipnerf
