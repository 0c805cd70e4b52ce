// The machine's limits (see machine_probe.hpp).
#include "bench/machine_probe.hpp"

#include <cstdio>
#include <vector>

#include "gemm/cpu_sgemm.hpp"
#include "gemm/cpu_sgemm_timing.hpp"

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace mipnerf::bench {
namespace {

io::Json rate_json(const gemm::RateStats& s) { return {{"best", s.best}, {"median", s.median}}; }

// The key of `options` ({name: figure}) whose figure's "best" is highest; the figure is options[name][rate_key], or
// options[name] itself when rate_key is null.
std::string fastest_entry(const io::Json& options, const char* rate_key) {
  std::string fastest;
  double fastest_best = 0.0;
  for (const auto& [name, figure] : options.items()) {
    const double best = (rate_key ? figure.at(rate_key) : figure).value("best", 0.0);
    if (fastest.empty() || best > fastest_best) fastest = name, fastest_best = best;
  }
  return fastest;
}

#if defined(__x86_64__)
// 12 independent 8-wide FMA chains (enough to cover the FMA latency on two pipes), nothing from memory. Named
// variables, not an array: an array of __m256 is kept on the stack and every iteration would store and reload it.
__attribute__((target("avx2,fma"), noinline)) float fma_loop_8_wide(size_t iterations) {
  __m256 a0 = _mm256_set1_ps(0.00f), a1 = _mm256_set1_ps(0.01f), a2 = _mm256_set1_ps(0.02f),
         a3 = _mm256_set1_ps(0.03f), a4 = _mm256_set1_ps(0.04f), a5 = _mm256_set1_ps(0.05f),
         a6 = _mm256_set1_ps(0.06f), a7 = _mm256_set1_ps(0.07f), a8 = _mm256_set1_ps(0.08f),
         a9 = _mm256_set1_ps(0.09f), a10 = _mm256_set1_ps(0.10f), a11 = _mm256_set1_ps(0.11f);
  const __m256 x = _mm256_set1_ps(0.999999f), y = _mm256_set1_ps(1e-7f);
  for (size_t it = 0; it < iterations; ++it) {
    a0 = _mm256_fmadd_ps(a0, x, y), a1 = _mm256_fmadd_ps(a1, x, y), a2 = _mm256_fmadd_ps(a2, x, y);
    a3 = _mm256_fmadd_ps(a3, x, y), a4 = _mm256_fmadd_ps(a4, x, y), a5 = _mm256_fmadd_ps(a5, x, y);
    a6 = _mm256_fmadd_ps(a6, x, y), a7 = _mm256_fmadd_ps(a7, x, y), a8 = _mm256_fmadd_ps(a8, x, y);
    a9 = _mm256_fmadd_ps(a9, x, y), a10 = _mm256_fmadd_ps(a10, x, y), a11 = _mm256_fmadd_ps(a11, x, y);
    // No instruction: the compiler must assume the chains changed, so it can neither fold them into a closed
    // form nor hoist a whole call out of the caller's loop.
    asm volatile("" : "+x"(a0), "+x"(a1), "+x"(a2), "+x"(a3), "+x"(a4), "+x"(a5), "+x"(a6), "+x"(a7), "+x"(a8),
                 "+x"(a9), "+x"(a10), "+x"(a11));
  }
  const __m256 sum = _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(a0, a1), _mm256_add_ps(a2, a3)),
                                   _mm256_add_ps(_mm256_add_ps(_mm256_add_ps(a4, a5), _mm256_add_ps(a6, a7)),
                                                 _mm256_add_ps(_mm256_add_ps(a8, a9), _mm256_add_ps(a10, a11))));
  float out[8];
  _mm256_storeu_ps(out, sum);
  return out[0] + out[7];
}

// The same 12 chains 16 wide (AVX-512): on a CPU with it, a BLAS built for it (OpenBLAS's SkylakeX kernels,
// oneDNN, libxsmm) runs up to twice the 8-wide peak, so an 8-wide probe alone would put the products above "the
// peak". "+v": any of the 32 vector registers (zmm16-31 included).
__attribute__((target("avx512f"), noinline)) float fma_loop_16_wide(size_t iterations) {
  __m512 a0 = _mm512_set1_ps(0.00f), a1 = _mm512_set1_ps(0.01f), a2 = _mm512_set1_ps(0.02f),
         a3 = _mm512_set1_ps(0.03f), a4 = _mm512_set1_ps(0.04f), a5 = _mm512_set1_ps(0.05f),
         a6 = _mm512_set1_ps(0.06f), a7 = _mm512_set1_ps(0.07f), a8 = _mm512_set1_ps(0.08f),
         a9 = _mm512_set1_ps(0.09f), a10 = _mm512_set1_ps(0.10f), a11 = _mm512_set1_ps(0.11f);
  const __m512 x = _mm512_set1_ps(0.999999f), y = _mm512_set1_ps(1e-7f);
  for (size_t it = 0; it < iterations; ++it) {
    a0 = _mm512_fmadd_ps(a0, x, y), a1 = _mm512_fmadd_ps(a1, x, y), a2 = _mm512_fmadd_ps(a2, x, y);
    a3 = _mm512_fmadd_ps(a3, x, y), a4 = _mm512_fmadd_ps(a4, x, y), a5 = _mm512_fmadd_ps(a5, x, y);
    a6 = _mm512_fmadd_ps(a6, x, y), a7 = _mm512_fmadd_ps(a7, x, y), a8 = _mm512_fmadd_ps(a8, x, y);
    a9 = _mm512_fmadd_ps(a9, x, y), a10 = _mm512_fmadd_ps(a10, x, y), a11 = _mm512_fmadd_ps(a11, x, y);
    asm volatile("" : "+v"(a0), "+v"(a1), "+v"(a2), "+v"(a3), "+v"(a4), "+v"(a5), "+v"(a6), "+v"(a7), "+v"(a8),
                 "+v"(a9), "+v"(a10), "+v"(a11));
  }
  const __m512 sum = _mm512_add_ps(_mm512_add_ps(_mm512_add_ps(a0, a1), _mm512_add_ps(a2, a3)),
                                   _mm512_add_ps(_mm512_add_ps(_mm512_add_ps(a4, a5), _mm512_add_ps(a6, a7)),
                                                 _mm512_add_ps(_mm512_add_ps(a8, a9), _mm512_add_ps(a10, a11))));
  float out[16];
  _mm512_storeu_ps(out, sum);
  return out[0] + out[15];
}

// One FMA loop's rates, on one thread and on all: {"one_thread", "all_threads"}.
io::Json fma_rates(const MachineProbeSettings& s, float (*loop)(size_t), int floats_per_vector) {
  constexpr size_t kIterations = 1 << 16;
  const double gflop = 2.0 * floats_per_vector * 12 * kIterations * 1e-9;
  std::vector<float> sinks(static_cast<size_t>(s.threads), 0.0f);
  auto body = [&](int t, size_t reps) {
    for (size_t r = 0; r < reps; ++r) sinks[static_cast<size_t>(t)] += loop(kIterations);
  };
  return {{"one_thread", rate_json(gemm::measure_rate(1, gflop, s.rounds, s.batch_seconds, body))},
          {"all_threads", rate_json(gemm::measure_rate(s.threads, gflop, s.rounds, s.batch_seconds, body))}};
}
#endif

// The peak is the widest vector FMA the CPU runs (on some CPUs 16-wide FMAs issue on one pipe only and reach no
// more than 8-wide ones on two: both are timed there and the faster is the peak); "vector" says which, "by_vector"
// keeps each.
io::Json fma_peak(const MachineProbeSettings& s) {
#if defined(__x86_64__)
  if (!__builtin_cpu_supports("fma") || !__builtin_cpu_supports("avx2")) return {{"skipped", "no AVX2 + FMA"}};
  io::Json by_vector = {{"avx2_8_floats", fma_rates(s, fma_loop_8_wide, 8)}};
  if (__builtin_cpu_supports("avx512f")) by_vector["avx512_16_floats"] = fma_rates(s, fma_loop_16_wide, 16);
  const std::string fastest = fastest_entry(by_vector, "all_threads");
  io::Json j = by_vector[fastest];
  j["vector"] = fastest;
  j["by_vector"] = by_vector;
  return j;
#else
  return {{"skipped", "the FMA probe is written for x86-64 (AVX2 + FMA)"}};
#endif
}

io::Json triad(const MachineProbeSettings& s) {
  const size_t n = s.triad_floats;
  std::vector<float> a(n, 0.0f), b(n, 1.0f), c(n, 2.0f);
  auto body_for = [&](int threads) {
    return [&, threads](int t, size_t reps) {
      const size_t begin = n * static_cast<size_t>(t) / static_cast<size_t>(threads);
      const size_t end = n * static_cast<size_t>(t + 1) / static_cast<size_t>(threads);
      for (size_t r = 0; r < reps; ++r) {
        for (size_t i = begin; i < end; ++i) a[i] = b[i] + 0.5f * c[i];
      }
    };
  };
  const double gigabytes = 3.0 * sizeof(float) * static_cast<double>(n) * 1e-9;  // STREAM's count: 3 arrays
  return {{"one_thread", rate_json(gemm::measure_rate(1, gigabytes, s.rounds, s.batch_seconds, body_for(1)))},
          {"all_threads", rate_json(gemm::measure_rate(s.threads, gigabytes / s.threads, s.rounds, s.batch_seconds,
                                                       body_for(s.threads)))}};
}

// One large forward product on every CPU GEMM library built in; the fastest is the machine's large-sgemm rate (the
// rate a well-shaped product reaches here: on a CPU with AVX-512 oneDNN or libxsmm may beat OpenBLAS, and a
// products' figure against a slower library's rate would overstate how close to the limit they run).
io::Json large_sgemm(const MachineProbeSettings& s) {
  const auto& libraries = gemm::cpu_sgemm_libraries();
  if (libraries.empty()) return {{"skipped", "no CPU BLAS built in"}};
  const int m = 65536, n = 256, k = 256;
  std::vector<float> a(size_t{m} * k, 0.5f), b(size_t{k} * n, 0.25f), c(size_t{m} * n, 0.0f);
  io::Json by_library = io::Json::object();
  for (const gemm::CpuSgemmLibrary& blas : libraries) {
    blas.set_threads(s.threads);
    const gemm::RateStats rate = gemm::measure_rate(1, 2.0 * m * n * k * 1e-9, s.rounds, s.batch_seconds,
                                                    [&](int, size_t reps) {
                                                      for (size_t r = 0; r < reps; ++r) {
                                                        blas.sgemm(false, false, m, n, k, a.data(), k, b.data(), n,
                                                                   0.0f, c.data(), n);
                                                      }
                                                    });
    blas.set_threads(1);
    by_library[blas.name] = rate_json(rate);
  }
  const std::string fastest = fastest_entry(by_library, nullptr);
  io::Json j = by_library[fastest];
  j["library"] = fastest;
  j["shape"] = "65536x256x256 forward";
  j["by_library"] = by_library;
  return j;
}

}  // namespace

io::Json probe_machine(const MachineProbeSettings& settings) {
  io::Json j;
  j["what"] = "FMA peak: 12 chains of the widest vector FMA, 8 or 16 floats (GFLOP/s); triad a = b + s*c over 3 arrays of " +
              std::to_string(settings.triad_floats * sizeof(float) >> 20) +
              " MiB (GB/s, STREAM's count); one large sgemm on all threads, the fastest CPU GEMM library's (GFLOP/s); best and median of " +
              std::to_string(settings.rounds);
  j["threads"] = settings.threads;
  j["fma_peak_gflops"] = fma_peak(settings);
  j["triad_gbs"] = triad(settings);
  j["large_sgemm_gflops"] = large_sgemm(settings);
  return j;
}

std::string machine_summary(const io::Json& p) {
  if (!p.is_object() || !p.contains("fma_peak_gflops")) return "";
  auto best = [&](const io::Json& part, const char* key) -> double {
    const io::Json& x = key ? part.value(key, io::Json::object()) : part;
    return x.value("best", 0.0);
  };
  const io::Json& fma = p["fma_peak_gflops"];
  const io::Json& sgemm = p.value("large_sgemm_gflops", io::Json::object());
  char text[320];
  std::snprintf(text, sizeof(text),
                "FMA peak %.1f GFLOP/s (%d threads, %s), triad %.1f GB/s, large sgemm %.1f GFLOP/s (%s)",
                best(fma, "all_threads"), p.value("threads", 0), fma.value("vector", "not probed").c_str(),
                best(p["triad_gbs"], "all_threads"), best(sgemm, nullptr), sgemm.value("library", "none").c_str());
  return text;
}

}  // namespace mipnerf::bench
