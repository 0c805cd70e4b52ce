// A progress line for long work (train, render, eval, tune): redrawn in place on a terminal, printed
// as plain lines (every few seconds) when stderr is a file or a pipe, so logs stay readable.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>

#include "core/duration.hpp"

namespace mipnerf::cli {

class Progress {
 public:
  // `what` prefixes the line ("train", "render val"); `total` is the number of units of work.
  Progress(std::string what, int64_t total);
  ~Progress();

  // Reports `done` units finished, with extra text (e.g. "loss 0.012 psnr 24.1 dB 1840 rays/s").
  void update(int64_t done, const std::string& detail = {});
  // Ends the line (keeps the last state on screen).
  void finish(const std::string& detail = {});
  // Ends the line at `done` units: work stopped before the end (an interrupt) shows where it stopped.
  void finish_at(int64_t done, const std::string& detail = {});

  // Prints `line` ("mipnerf-cl: " first) on a line of its own above the progress line, which is redrawn at the next
  // update; rank 0 only, as the progress line.
  void note(const std::string& line);

  double elapsed_seconds() const;
  // The units already done when this run started (0 for work counted from its start; by default the first update
  // is taken as one unit past the start, as a resumed run reports its first step).
  void begin_at(int64_t done) { start_done_ = done; }
  // Keeps `seconds` (other work meanwhile: scoring val views between steps) out of the rate the ETA is drawn from.
  void exclude_from_rate(double seconds) { excluded_seconds_ += seconds; }
  // Sets the number of units when it is known only once the work starts (a job that counts its own rays).
  void set_total(int64_t total) { total_ = total; }
  // A job's progress callback (eval::RenderJob::progress): each call sets the total and the units done.
  std::function<void(size_t done, size_t total, const std::string& detail)> job_callback() {
    return [this](size_t done, size_t total, const std::string& detail) {
      set_total(static_cast<int64_t>(total));
      update(static_cast<int64_t>(done), detail);
    };
  }

 private:
  void draw(int64_t done, const std::string& detail, bool force);

  std::string what_;
  int64_t total_;
  int64_t start_done_ = -1;  // units already done when this run started (resume)
  double excluded_seconds_ = 0.0;  // exclude_from_rate
  bool tty_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
};

// "1h02m", "3m07s", "12s": a duration for humans (the library's, host/core/duration.hpp).
using mipnerf::format_duration;

}  // namespace mipnerf::cli
