// Atomic file output through a temporary file, fsync and rename.
#include "io/atomic_file.hpp"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <system_error>
#include <thread>

#include "core/error.hpp"

namespace mipnerf::io {
namespace fs = std::filesystem;
namespace {

std::string errno_text(int error) { return std::strerror(error); }

// fsync of an open-able path; `directory` opens it read-only as a folder.
int sync_path(const std::string& path, bool directory) {
  const int fd = ::open(path.c_str(), directory ? (O_RDONLY | O_DIRECTORY) : O_RDONLY);
  if (fd < 0) return errno;
  const int result = ::fsync(fd) == 0 ? 0 : errno;
  ::close(fd);
  return result;
}

std::string unique_temporary(const fs::path& target) {
  static std::atomic<unsigned long> counter{0};
  const std::string name = "." + target.filename().string() + "." + std::to_string(::getpid()) + "." +
                           std::to_string(counter++) + ".tmp";
  return (target.parent_path() / name).string();
}

// MIPNERF_TEST_PAUSE_IN_WRITE_MS: for tests only (tests/reliability), a pause halfway through every
// write_bytes_atomically, so that a test can kill the process inside a checkpoint write. Read once.
long pause_in_write_ms() {
  static const long ms = [] {
    const char* text = std::getenv("MIPNERF_TEST_PAUSE_IN_WRITE_MS");
    return text ? std::max(0L, std::strtol(text, nullptr, 10)) : 0L;
  }();
  return ms;
}

// The process id in an AtomicFile temporary's name ".<name>.<pid>.<n>.tmp"; 0 when `name` is not one.
pid_t temporary_owner(const std::string& name) {
  const std::string suffix = ".tmp";
  if (name.size() < 8 || name[0] != '.' || name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0) return 0;
  const std::string stem = name.substr(0, name.size() - suffix.size());
  const size_t counter_dot = stem.rfind('.');
  if (counter_dot == std::string::npos || counter_dot == 0) return 0;
  const size_t pid_dot = stem.rfind('.', counter_dot - 1);
  if (pid_dot == std::string::npos || pid_dot == 0) return 0;
  const std::string counter = stem.substr(counter_dot + 1), pid = stem.substr(pid_dot + 1, counter_dot - pid_dot - 1);
  const auto all_digits = [](const std::string& t) {
    return !t.empty() && t.size() < 10 && t.find_first_not_of("0123456789") == std::string::npos;
  };
  if (!all_digits(counter) || !all_digits(pid)) return 0;
  return static_cast<pid_t>(std::stol(pid));
}

}  // namespace

AtomicFile::AtomicFile(std::string path) : path_(std::move(path)) {
  const fs::path target(path_);
  if (target.filename().empty()) throw Error(path_ + ": not a file name (it ends in a folder separator)");
  if (target.has_parent_path()) {
    std::error_code ec;
    fs::create_directories(target.parent_path(), ec);
    if (ec || !fs::is_directory(target.parent_path())) {
      throw Error(path_ + ": cannot create its folder '" + target.parent_path().string() + "' (" +
                  (ec ? ec.message() : std::string("a file is in the way")) + ")");
    }
  }
  temporary_ = unique_temporary(target);
}

AtomicFile::~AtomicFile() {
  if (!committed_) {
    std::error_code ignored;
    fs::remove(temporary_, ignored);
  }
}

void AtomicFile::commit() {
  if (committed_) throw Error(path_ + ": already committed");
  std::error_code ec;
  if (!fs::is_regular_file(temporary_, ec)) {
    throw Error(path_ + ": the writer produced no file at its temporary '" + temporary_ + "'");
  }
  // Data reaches the disk before the name does: after a crash the destination holds the old file or the
  // whole new one, never a renamed but empty file.
  if (const int error = sync_path(temporary_, false)) {
    throw Error(path_ + ": cannot flush the written file to disk (" + errno_text(error) + "); is the disk full?");
  }
  fs::rename(temporary_, path_, ec);
  if (ec) throw Error(path_ + ": cannot replace the file (" + ec.message() + ")");
  committed_ = true;
  // The rename itself is made durable by flushing the folder; some file systems refuse that (EINVAL),
  // which costs durability after a power cut only, never atomicity, so it is not an error.
  const fs::path folder = fs::path(path_).has_parent_path() ? fs::path(path_).parent_path() : fs::path(".");
  sync_path(folder.string(), true);
}

void write_atomically(const std::string& path, const std::function<void(const std::string& temporary_path)>& produce) {
  AtomicFile file(path);
  produce(file.temporary_path());
  file.commit();
}

void write_bytes_atomically(const std::string& path, std::string_view bytes) {
  write_atomically(path, [&](const std::string& temporary) {
    std::FILE* out = std::fopen(temporary.c_str(), "wb");
    if (!out) throw Error(path + ": cannot write (" + errno_text(errno) + ")");
    // Written in two halves with the test-only pause between them (none unless the variable is set).
    const size_t half = bytes.size() / 2;
    bool written = std::fwrite(bytes.data(), 1, half, out) == half;
    if (written && pause_in_write_ms() > 0) {
      std::fflush(out);
      std::this_thread::sleep_for(std::chrono::milliseconds(pause_in_write_ms()));
    }
    written = written && std::fwrite(bytes.data() + half, 1, bytes.size() - half, out) == bytes.size() - half;
    const int write_error = errno;
    const bool closed = std::fclose(out) == 0;
    if (!written || !closed) {
      const int error = written ? errno : write_error;
      throw Error(path + ": write failed (" + errno_text(error) + (error == ENOSPC ? ": the disk is full" : "") + ")");
    }
  });
}

void remove_stale_temporaries(const std::string& folder, const LogFn& log) {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const pid_t owner = temporary_owner(entry.path().filename().string());
    // kill(pid, 0) asks whether the process exists without signalling it; ESRCH: it is gone.
    if (owner <= 0 || owner == ::getpid() || ::kill(owner, 0) == 0 || errno != ESRCH) continue;
    std::error_code removed;
    if (fs::remove(entry.path(), removed) && log) {
      log(LogLevel::info, "removed " + entry.path().string() + ", left by an interrupted write of process " +
                              std::to_string(owner));
    }
  }
}

}  // namespace mipnerf::io
