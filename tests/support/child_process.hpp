// A child process for tests that must kill a program or limit it: fork + exec with extra environment variables,
// output to files, an optional file-size limit; then wait, or SIGKILL it.
#pragma once

#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

namespace mipnerf::test {

struct ChildOptions {
  std::vector<std::string> environment;  // "NAME=value", added to (and overriding) this process's
  std::string output_file;               // stdout and stderr together; empty: inherited
  long long file_size_limit = -1;        // RLIMIT_FSIZE in bytes (writes past it fail with EFBIG); -1: none
};

class ChildProcess {
 public:
  ChildProcess(const std::vector<std::string>& argv, const ChildOptions& options) {
    // Everything the child needs is built before fork: between fork and exec only async-signal-safe calls.
    std::vector<std::string> env_strings = options.environment;
    for (char** e = environ; *e != nullptr; ++e) {
      const std::string entry = *e;
      const std::string name = entry.substr(0, entry.find('='));
      bool overridden = false;
      for (const auto& extra : options.environment) overridden |= extra.compare(0, name.size() + 1, name + "=") == 0;
      if (!overridden) env_strings.push_back(entry);
    }
    std::vector<char*> args, env;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    for (const auto& e : env_strings) env.push_back(const_cast<char*>(e.c_str()));
    env.push_back(nullptr);
    const int out = options.output_file.empty()
                        ? -1
                        : ::open(options.output_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    // A log that cannot be written would leave the checks of its text looking at nothing: never fall back.
    if (!options.output_file.empty() && out < 0) {
      throw std::runtime_error("cannot write the child's log " + options.output_file);
    }
    pid_ = ::fork();
    if (pid_ < 0) throw std::runtime_error("fork failed");
    if (pid_ == 0) {
      if (out >= 0) {
        ::dup2(out, 1);
        ::dup2(out, 2);
      }
      if (options.file_size_limit >= 0) {
        ::signal(SIGXFSZ, SIG_IGN);  // a write past the limit then fails with EFBIG instead of killing the process
        const rlimit limit{static_cast<rlim_t>(options.file_size_limit), static_cast<rlim_t>(options.file_size_limit)};
        ::setrlimit(RLIMIT_FSIZE, &limit);
      }
      ::execve(args[0], args.data(), env.data());
      ::_exit(127);
    }
    if (out >= 0) ::close(out);
  }
  ~ChildProcess() {
    if (pid_ > 0 && !reaped_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  pid_t pid() const { return pid_; }
  // True once the child has ended (reaped); its status is then in status().
  bool finished() {
    if (!reaped_ && ::waitpid(pid_, &status_, WNOHANG) == pid_) reaped_ = true;
    return reaped_;
  }
  // Waits for the end; the raw wait status.
  int wait() {
    if (!reaped_ && ::waitpid(pid_, &status_, 0) == pid_) reaped_ = true;
    return status_;
  }
  // SIGKILL now, then reap. True when the signal ended it (false: it had already exited by itself).
  bool kill_now() {
    if (finished()) return false;
    ::kill(pid_, SIGKILL);
    wait();
    return WIFSIGNALED(status_) && WTERMSIG(status_) == SIGKILL;
  }
  int status() const { return status_; }
  int exit_code() const { return WIFEXITED(status_) ? WEXITSTATUS(status_) : -1; }

 private:
  pid_t pid_ = -1;
  int status_ = 0;
  bool reaped_ = false;
};

}  // namespace mipnerf::test
