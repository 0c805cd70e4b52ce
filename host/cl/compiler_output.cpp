// Capturing file descriptor 2 around kernel builds.
#include "cl/compiler_output.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <mutex>

namespace mipnerf::ocl {
namespace {

std::mutex& capture_mutex() {
  static std::mutex mutex;
  return mutex;
}

// One scratch file for the process (removed from the file system at once: std::tmpfile), emptied before each capture:
// a capture costs a few system calls, so CLBlast's calls, which compile on first use, can all go through one.
std::FILE* scratch_file() {
  static std::FILE* const file = std::tmpfile();
  return file;
}

thread_local int capture_depth = 0;

// Everything in `file` from its start, trailing newlines stripped.
std::string read_all(std::FILE* file) {
  std::string text;
  struct stat info {};
  if (fstat(fileno(file), &info) != 0 || info.st_size == 0) return text;
  std::rewind(file);
  char buffer[4096];
  size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof(buffer), file)) > 0) text.append(buffer, n);
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
  return text;
}

}  // namespace

std::string capture_stderr(const std::function<void()>& body) {
  if (capture_depth > 0) {  // inside another capture on this thread: it catches this body's output
    body();
    return {};
  }
  std::lock_guard<std::mutex> lock(capture_mutex());
  std::FILE* scratch = scratch_file();
  const int saved = scratch != nullptr ? dup(2) : -1;
  if (saved < 0 || ftruncate(fileno(scratch), 0) != 0) {  // nowhere to send it: run uncaptured rather than not at all
    if (saved >= 0) close(saved);
    body();
    return {};
  }
  std::fflush(stderr);
  dup2(fileno(scratch), 2);
  ++capture_depth;
  // Puts fd 2 back as it was, also when `body` throws.
  struct Restore {
    int saved;
    ~Restore() {
      --capture_depth;
      std::fflush(stderr);
      dup2(saved, 2);
      close(saved);
    }
  };
  {
    Restore restore{saved};
    body();
  }
  return read_all(scratch);
}

}  // namespace mipnerf::ocl
