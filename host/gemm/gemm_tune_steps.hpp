// The steps of the GEMM tune (mlp/gemm_tuner.hpp): the JSON that describes one piece of device work, and
// the function that does it on a context. The spec and the result are JSON so that a step can cross a process
// boundary (`mipnerf-cl tune` runs each in a child process) as easily as run in-process (tests).
//
// Three kinds of step:
//   kernel tuner  one of CLBlast's tuners (TuneXgemm, TuneXgemmDirect, TuneCopy, TunePad, TuneTranspose,
//                 TunePadtranspose) → {"parameters": the kernel's full set}
//   evaluate      a candidate set timed through the real routine (mlp::gemm) on the MLP's products, results
//                 checked → {"seconds": [...], "error_ratio": [...], "probe_error_ratio": x}
//   crossover     the forward product at several row counts, forced through the indirect and the direct
//                 kernel → {"indirect": [...], "direct": [...]}
// Every result also holds "wall_seconds", the step's own duration.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "cl/context.hpp"
#include "core/log.hpp"
#include "io/json.hpp"
#include "gemm/gemm_tuning.hpp"

namespace mipnerf::gemm {

// `tuner` is the name without "Tune" ("Xgemm", "Copy", ...); k = 0 for the tuners that take no k.
io::Json kernel_tuner_step(const std::string& tuner, size_t m, size_t n, size_t k, double fraction);
// Each of `problems` timed as the best of `reps` after a warm-up.
io::Json evaluate_step(const ParameterSet& set, const std::vector<GemmProblem>& problems, int reps);
// The forward product rows × width · width × width for each of `rows`.
io::Json crossover_step(const ParameterSet& set, size_t width, const std::vector<size_t>& rows);

// Does the step on `ctx` and returns its result. `log` receives what a person may want from the step's
// output (GFLOP/s per product, the correctness probe's ratio). Throws mipnerf::Error when CLBlast fails or
// the spec is not one of the above.
io::Json run_tune_step(ocl::Context& ctx, const io::Json& spec, const LogFn& log);

// Error ratios of a product: |computed − exact| / (2·k·u·Σ|a·b|), twice the worst-case float32 dot-product
// bound (u = 2^-24), so a correct result stays below 1 (≈ 0.01 in practice); a non-finite error counts 1e30.
// The step results' "error_ratio" and "probe_error_ratio" hold the worst of these.
double gemm_error_ratio(double computed, double exact, double magnitude, size_t k);

// A parameter set as the steps' JSON (kernel → parameter name → value), and back.
io::Json parameter_set_json(const ParameterSet& set);
ParameterSet parameter_set_from_json(const io::Json& json);

}  // namespace mipnerf::gemm
