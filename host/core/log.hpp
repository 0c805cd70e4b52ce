// The library never prints: it reports through this callback, which the CLI (or a test) installs.
#pragma once

#include <functional>
#include <string>

namespace mipnerf {

enum class LogLevel { debug, info, warning };

using LogFn = std::function<void(LogLevel, const std::string&)>;

}  // namespace mipnerf
