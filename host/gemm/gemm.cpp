// Row-major SGEMM through CLBlast or the host BLAS (the caller's backend), with shape checks that name the product.
#include "gemm/gemm.hpp"

#include <clblast.h>

#include "cl/compiler_output.hpp"
#include "cl/error.hpp"
#include "core/error.hpp"
#include "gemm/clblast_check.hpp"
#include "gemm/gemm_tuning.hpp"
#include "gemm/host_gemm.hpp"

namespace mipnerf::gemm {

void sgemm(ocl::Context& ctx, GemmBackend backend, const GemmShape& s, float alpha, const MatrixView& a,
           const MatrixView& b, float beta, const MatrixView& c, const std::string& what) {
  if (s.m == 0 || s.n == 0) return;
  const std::string where = "gemm(" + what + ")";
  ocl::require_matrix(a, s.transpose_a ? s.k : s.m, s.transpose_a ? s.m : s.k, "A", where);
  ocl::require_matrix(b, s.transpose_b ? s.n : s.k, s.transpose_b ? s.k : s.n, "B", where);
  ocl::require_matrix(c, s.m, s.n, "C", where);
  // Profiled under "gemm <kind>", with its FLOPs, so the report can give GFLOP/s and the GEMM-bound limit.
  ocl::StageScope stage(ctx, std::string("gemm ") + gemm_kind_name(gemm_kind(s)));
  ocl::StageProfiler* profiler = ctx.recording_profiler();
  if (profiler) profiler->add_flops(2.0 * static_cast<double>(s.m) * s.n * s.k);
  if (backend == GemmBackend::automatic) throw Error("gemm(" + what + "): resolve gemm_backend=auto before a product");
  if (backend == GemmBackend::host) {
    host_gemm(ctx, s, alpha, a, b, beta, c, what);
    return;
  }
  // Tuned parameters may differ per product kind (see gemm_tuning.hpp); a no-op when none are installed.
  select_gemm_kind(ctx, gemm_kind(s));
  using clblast::Transpose;
  cl_command_queue queue = ctx.raw_queue();
  // Profiling: CLBlast may enqueue several kernels (padding, transposes) and returns the last one's event, so the
  // product is timed from a marker before it to that event's end (in-order queue).
  const bool profile = profiler != nullptr;
  cl_event before = nullptr, after = nullptr;
  if (profile) {
    ocl::check(clEnqueueMarkerWithWaitList(queue, 0, nullptr, &before), "clEnqueueMarkerWithWaitList (profiling)");
  }
  // CLBlast compiles its kernels on a routine's first use, through the same in-process compiler as ours: what that
  // writes to stderr goes to the log (cl/compiler_output.hpp).
  clblast::StatusCode status = clblast::StatusCode::kSuccess;
  const std::string compiler_output = ocl::capture_stderr([&] {
    status = clblast::Gemm<float>(
        clblast::Layout::kRowMajor, s.transpose_a ? Transpose::kYes : Transpose::kNo,
        s.transpose_b ? Transpose::kYes : Transpose::kNo, s.m, s.n, s.k, alpha, a.array->raw(), a.offset, a.ld,
        b.array->raw(), b.offset, b.ld, beta, c.array->raw(), c.offset, c.ld, &queue, profile ? &after : nullptr);
  });
  if (!compiler_output.empty()) {
    ctx.log(LogLevel::debug, "the compiler's output in CLBlast's " + what + ": " + compiler_output);
  }
  if (profile) profiler->add_event_span(::cl::Event(before), ::cl::Event(after));  // takes both references
  check_clblast(status, "clblast::Gemm(" + what + ", m=" + std::to_string(s.m) + " n=" + std::to_string(s.n) +
                            " k=" + std::to_string(s.k) + ")");
}

}  // namespace mipnerf::gemm
