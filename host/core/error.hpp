// The one exception type of the library: a failed OpenCL/CLBlast call, a failed kernel build, or bad input.
// It lives on the ground floor so that readers of outside data (PNG, JSON, datasets) throw it without
// compiling against the OpenCL headers; cl/error.hpp turns OpenCL statuses into it.
#pragma once

#include <stdexcept>
#include <string>

namespace mipnerf {

// Every failure the library reports. what() is one line a person can act on (the CLI prints it as is);
// details() holds what does not fit on a line, e.g. a kernel's full build log.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message, std::string details = {}, int status = 0)
      : std::runtime_error(one_line(message)), details_(std::move(details)), status_(status) {}

  // `text` with its control characters written out (\n, \r, \t, \xNN): a message quotes text from outside (a file
  // name, a key or value read from a file), which may hold any byte, and must stay one line on a terminal.
  static std::string one_line(const std::string& text) {
    static const char kHex[] = "0123456789abcdef";
    std::string out;
    out.reserve(text.size());
    for (const char c : text) {
      const auto byte = static_cast<unsigned char>(c);
      if (byte >= 0x20 && byte != 0x7f) {
        out += c;
      } else if (c == '\n') {
        out += "\\n";
      } else if (c == '\r') {
        out += "\\r";
      } else if (c == '\t') {
        out += "\\t";
      } else {
        out += "\\x";
        out += kHex[byte >> 4];
        out += kHex[byte & 0xf];
      }
    }
    return out;
  }

  const std::string& details() const { return details_; }
  // The OpenCL or CLBlast status code, 0 for errors that did not come from a call.
  int status() const { return status_; }

 private:
  std::string details_;
  int status_;
};

}  // namespace mipnerf
