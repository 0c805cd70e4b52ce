// Row-major SGEMM through CLBlast or the host BLAS (the context's backend), with shape checks that name the product.
#include "mlp/gemm.hpp"

#include <clblast.h>

#include "cl/error.hpp"
#include "core/error.hpp"
#include "mlp/clblast_check.hpp"
#include "mlp/gemm_tuning.hpp"
#include "mlp/host_gemm.hpp"

namespace mipnerf::mlp {
namespace {

// Elements a row-major rows×cols matrix with leading dimension ld spans from its offset.
size_t span(size_t rows, size_t cols, size_t ld) { return rows == 0 ? 0 : (rows - 1) * ld + cols; }

void require_fits(const MatrixView& v, size_t rows, size_t cols, const char* which, const std::string& what) {
  if (v.array == nullptr) throw Error("gemm(" + what + "): matrix " + which + " has no buffer");
  if (v.ld < cols) {
    throw Error("gemm(" + what + "): matrix " + which + " has leading dimension " + std::to_string(v.ld) +
                " < its " + std::to_string(cols) + " columns");
  }
  v.array->require_size(v.offset + span(rows, cols, v.ld), "gemm(" + what + ") matrix " + which);
}

}  // namespace

void gemm(ocl::Context& ctx, const GemmShape& s, float alpha, const MatrixView& a, const MatrixView& b, float beta,
          const MatrixView& c, const std::string& what) {
  if (s.m == 0 || s.n == 0) return;
  require_fits(a, s.transpose_a ? s.k : s.m, s.transpose_a ? s.m : s.k, "A", what);
  require_fits(b, s.transpose_b ? s.n : s.k, s.transpose_b ? s.k : s.n, "B", what);
  require_fits(c, s.m, s.n, "C", what);
  // Profiled under "gemm <kind>", with its FLOPs, so the report can give GFLOP/s and the GEMM-bound limit.
  ocl::StageScope stage(ctx, std::string("gemm ") + gemm_kind_name(gemm_kind(s)));
  ocl::StageProfiler* profiler = ctx.recording_profiler();
  if (profiler) profiler->add_flops(2.0 * static_cast<double>(s.m) * s.n * s.k);
  // The context's backend (mlp/gemm_backend.hpp): the host BLAS on mapped buffers, or CLBlast on the queue.
  if (ctx.gemm_on_host()) {
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
  const auto status = clblast::Gemm<float>(
      clblast::Layout::kRowMajor, s.transpose_a ? Transpose::kYes : Transpose::kNo,
      s.transpose_b ? Transpose::kYes : Transpose::kNo, s.m, s.n, s.k, alpha, a.array->raw(), a.offset, a.ld,
      b.array->raw(), b.offset, b.ld, beta, c.array->raw(), c.offset, c.ld, &queue, profile ? &after : nullptr);
  if (profile) profiler->add_event_span(::cl::Event(before), ::cl::Event(after));  // takes both references
  check_clblast(status, "clblast::Gemm(" + what + ", m=" + std::to_string(s.m) + " n=" + std::to_string(s.n) +
                            " k=" + std::to_string(s.k) + ")");
}

}  // namespace mipnerf::mlp
