// Timing a CPU GEMM library on one product in the host MLP's thread arrangement (see cpu_sgemm_timing.hpp).
#include "gemm/cpu_sgemm_timing.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <random>
#include <sstream>
#include <thread>
#include <vector>

#include "core/error.hpp"

namespace mipnerf::gemm {
namespace {

using Clock = std::chrono::steady_clock;

struct Operands {
  std::vector<float> a, b, c;
};

Operands operands_for(const HostProductShape& s, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  Operands o;
  o.a.resize(s.m * s.k);
  o.b.resize(s.k * s.n);
  o.c.assign(s.m * s.n, 0.0f);
  for (float& x : o.a) x = u(rng);
  for (float& x : o.b) x = u(rng);
  return o;
}

void call(const CpuSgemmLibrary& library, const HostProductShape& s, float beta, Operands& o) {
  library.sgemm(s.trans_a, s.trans_b, static_cast<int>(s.m), static_cast<int>(s.n), static_cast<int>(s.k), o.a.data(),
                static_cast<int>(s.trans_a ? s.m : s.k), o.b.data(), static_cast<int>(s.trans_b ? s.k : s.n), beta,
                o.c.data(), static_cast<int>(s.n));
}

// "" when `library` computes what `reference` does on the shape (beta = 0), else why not.
std::string disagreement(const CpuSgemmLibrary& library, const CpuSgemmLibrary& reference, const HostProductShape& s) {
  Operands mine = operands_for(s, 7), theirs = operands_for(s, 7);
  try {
    call(library, s, 0.0f, mine);
  } catch (const Error& e) {
    return e.what();
  }
  call(reference, s, 0.0f, theirs);
  const double bound = 2.0 * static_cast<double>(s.k) * static_cast<double>(s.k) * std::ldexp(1.0, -24);
  double worst = 0;
  for (size_t i = 0; i < mine.c.size(); ++i) {
    const double d = std::abs(static_cast<double>(mine.c[i]) - theirs.c[i]);
    worst = std::isnan(d) ? INFINITY : std::max(worst, d);
  }
  if (worst <= bound) return "";
  std::ostringstream why;
  why << "differs from " << reference.name << " by up to " << worst << " (bound " << bound << ")";
  return why.str();
}

// Wall seconds of body(thread, reps) on `threads` threads released together (the timing thread blocks in join).
double timed_parallel(int threads, size_t reps, const std::function<void(int, size_t)>& body) {
  std::atomic<int> ready{0};
  std::atomic<bool> go{false};
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) {
    pool.emplace_back([&, t] {
      ready.fetch_add(1);
      while (!go.load()) std::this_thread::yield();
      body(t, reps);
    });
  }
  while (ready.load() < threads) std::this_thread::yield();
  const auto begin = Clock::now();
  go.store(true);
  for (auto& thread : pool) thread.join();
  return std::chrono::duration<double>(Clock::now() - begin).count();
}

}  // namespace

RateStats measure_rate(int threads, double units_per_rep, int rounds, double batch_seconds,
                       const std::function<void(int, size_t)>& body) {
  size_t reps = 1;
  timed_parallel(threads, 1, body);  // warm: JIT, first touches, thread start-up
  while (timed_parallel(threads, reps, body) < batch_seconds && reps < (size_t{1} << 24)) reps *= 2;
  std::vector<double> rates;
  for (int r = 0; r < std::max(1, rounds); ++r) {
    rates.push_back(units_per_rep * threads * static_cast<double>(reps) / timed_parallel(threads, reps, body));
  }
  std::sort(rates.begin(), rates.end());
  return {rates.back(), rates[rates.size() / 2]};
}

HostProductTiming time_host_product(const CpuSgemmLibrary& library, const CpuSgemmLibrary& reference,
                                   const HostProductShape& shape, const HostProductTimingSettings& settings) {
  HostProductTiming timing;
  timing.skipped = disagreement(library, reference, shape);
  if (!timing.skipped.empty()) return timing;
  std::vector<Operands> per_thread;
  for (int t = 0; t < settings.threads; ++t) per_thread.push_back(operands_for(shape, 11 + t));
  const float beta = shape.trans_a ? 1.0f : 0.0f;
  const double gflop = 2.0 * shape.m * shape.n * shape.k * 1e-9;
  const RateStats rate = measure_rate(settings.threads, gflop, settings.rounds, settings.batch_seconds,
                                      [&](int t, size_t reps) {
                                        library.set_threads(1);
                                        for (size_t r = 0; r < reps; ++r) call(library, shape, beta, per_thread[t]);
                                      });
  timing.gflops_best = rate.best;
  timing.gflops_median = rate.median;
  return timing;
}

}  // namespace mipnerf::gemm
