// The progress line of long-running commands.
#include "progress.hpp"

#include "parallel/world.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <iostream>

namespace mipnerf::cli {

Progress::Progress(std::string what, int64_t total)
    : what_(std::move(what)),
      total_(total),
      tty_(isatty(STDERR_FILENO) != 0),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_ - std::chrono::hours(1)) {}

Progress::~Progress() {
  if (!finished_ && tty_) std::cerr << "\n";
}

double Progress::elapsed_seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void Progress::update(int64_t done, const std::string& detail) {
  if (start_done_ < 0) start_done_ = done > 0 ? done - 1 : 0;
  draw(done, detail, false);
}

void Progress::finish(const std::string& detail) { finish_at(total_, detail); }

void Progress::finish_at(int64_t done, const std::string& detail) {
  if (finished_) return;
  draw(done, detail, true);
  if (tty_ && parallel::world().is_root()) std::cerr << "\n";
  finished_ = true;
}

void Progress::note(const std::string& line) {
  if (!parallel::world().is_root()) return;
  std::cerr << (tty_ ? "\r\033[K" : "") << "mipnerf-cl: " << line << "\n" << std::flush;
  last_draw_ = start_ - std::chrono::hours(1);  // the bar comes back at the next update
}

void Progress::draw(int64_t done, const std::string& detail, bool force) {
  if (!parallel::world().is_root()) return;  // under mpirun the ranks progress together: rank 0 shows it
  const auto now = std::chrono::steady_clock::now();
  // A terminal is redrawn ~5 times a second; a log file gets a line every 10 seconds.
  const auto interval = tty_ ? std::chrono::milliseconds(200) : std::chrono::milliseconds(10000);
  if (!force && now - last_draw_ < interval) return;
  last_draw_ = now;
  const double fraction = total_ > 0 ? static_cast<double>(done) / static_cast<double>(total_) : 1.0;
  const double elapsed = elapsed_seconds();
  const int64_t done_here = done - std::max<int64_t>(start_done_, 0);
  const double working = std::max(0.0, elapsed - excluded_seconds_);
  const double eta = done_here > 0 ? working / static_cast<double>(done_here) * static_cast<double>(total_ - done) : -1;
  constexpr int kBarWidth = 24;
  const int filled = static_cast<int>(std::round(std::min(1.0, std::max(0.0, fraction)) * kBarWidth));
  std::string bar = std::string(static_cast<size_t>(filled), '#') + std::string(static_cast<size_t>(kBarWidth - filled), '.');
  char head[160];
  std::snprintf(head, sizeof(head), "%s [%s] %lld/%lld %3.0f%% %s elapsed, eta %s", what_.c_str(), bar.c_str(),
                static_cast<long long>(done), static_cast<long long>(total_), 100.0 * fraction,
                format_duration(elapsed).c_str(), format_duration(eta).c_str());
  std::string line = head;
  if (!detail.empty()) line += "  " + detail;
  if (tty_) {
    std::cerr << "\r\033[K" << line << std::flush;
  } else {
    std::cerr << line << "\n";
  }
}

}  // namespace mipnerf::cli
