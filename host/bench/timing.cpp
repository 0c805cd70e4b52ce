// Wall-clock timings, their summaries, and the process's peak memory.
#include "bench/timing.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <fstream>
#include <numeric>

namespace mipnerf::bench {

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

double time_call(const std::function<void()>& work) {
  const auto start = Clock::now();
  work();
  return seconds_since(start);
}

double Timings::best() const { return seconds.empty() ? 0.0 : *std::min_element(seconds.begin(), seconds.end()); }

double Timings::median() const {
  if (seconds.empty()) return 0.0;
  auto sorted = seconds;
  std::sort(sorted.begin(), sorted.end());
  return sorted[sorted.size() / 2];
}

double Timings::mean() const {
  if (seconds.empty()) return 0.0;
  return std::accumulate(seconds.begin(), seconds.end(), 0.0) / static_cast<double>(seconds.size());
}

size_t peak_rss_bytes() {
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0;
  return static_cast<size_t>(usage.ru_maxrss) * 1024;  // Linux reports kilobytes
}

bool reset_peak_rss() {
  std::ofstream clear_refs("/proc/self/clear_refs");
  if (!clear_refs) return false;
  clear_refs << "5";  // proc(5): resets the peak resident set size ("high water mark") to the current RSS
  clear_refs.close();
  return static_cast<bool>(clear_refs);
}

}  // namespace mipnerf::bench
