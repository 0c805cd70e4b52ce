// What every benchmark measures with: wall-clock seconds of repeated calls summarised as best and median, the
// process's peak memory, and a progress callback (the library never prints; the CLI draws the progress line).
#pragma once

#include <chrono>
#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace mipnerf::bench {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start);

// Wall seconds of one call of `work` (which must wait for its device work itself, e.g. with ctx.finish()).
double time_call(const std::function<void()>& work);

// The timed calls of one measurement. best() is robust to other processes on a shared machine (a busy moment only
// slows calls down); median() shows how much they did. Both are 0 when nothing was timed.
struct Timings {
  std::vector<double> seconds;  // one entry per timed call, in call order

  void add(double s) { seconds.push_back(s); }
  bool empty() const { return seconds.empty(); }
  size_t count() const { return seconds.size(); }
  double best() const;
  double median() const;  // the upper median (sorted[n/2]), as the benchmarks have always reported it
  double mean() const;
};

// Peak resident set size of this process, in bytes (getrusage's ru_maxrss): on a CPU OpenCL device (PoCL) this
// includes every device buffer.
size_t peak_rss_bytes();

// Restarts the kernel's peak-RSS mark at the current RSS (Linux: "5" written to /proc/self/clear_refs), so that
// peak_rss_bytes() afterwards is the peak of what follows. False where the system does not allow it (then the
// peak is the process's since it started).
bool reset_peak_rss();

// Progress of a long measurement: what is being measured now, and how much of the section is done.
using ProgressFn = std::function<void(const std::string& what, size_t done, size_t total)>;

}  // namespace mipnerf::bench
