// bench_gemm: GFLOP/s of the MLP's matrix products on one OpenCL device through CLBlast, with CLBlast's default
// parameters and with the parameters `mipnerf-cl tune` stored for the device, beside OpenBLAS (cblas_sgemm) on
// the same shapes, in one run.
//
//   bench_gemm [--device SELECTOR] [--rows R] [--widths 64,128,256] [--reps K] [--rounds N] [--tuning FILE]
//
// Products (row-major, R = 65,536 rows by default): forward Y = X·W (R×W·W×W), backward data dX = dY·Wᵀ, backward
// weights dW = Xᵀ·dY (W×R·R×W). Each configuration's first call is timed on its own ("cold": CLBlast builds its
// program then; PoCL's on-disk cache may serve it — POCL_KERNEL_CACHE=0 gives a true cold compile); then one
// warm-up call and K timed calls per shape, each followed by clFinish. The whole sequence (default, tuned,
// OpenBLAS) runs N rounds, so a noisy moment hits all columns alike; the table shows the best call over all
// rounds and, in brackets, the median. --tuning names a tuning file (default: the per-device file in the cache).
// Then the paper's whole network on one chunk (--mlp-rays × --mlp-samples rows; --mlp-rays 0 skips it): forward,
// backward and inference forward with default and tuned parameters. On PoCL, POCL_TRACING=text writes every
// kernel's start and end to pocl_trace_events.log (the queue has profiling on), to see where the time goes.
// The measuring is host/bench/gemm_bench (shared with `mipnerf-cl bench`); this front-end adds the OpenBLAS column.
#include <cblas.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "bench/gemm_bench.hpp"
#include "cl/context.hpp"
#include "core/error.hpp"
#include "gemm/clblast_check.hpp"
#include "gemm/gemm_tuning.hpp"
#include "mlp/network.hpp"

using namespace mipnerf;

namespace {

struct Args {
  std::string device;
  bench::GemmBenchOptions options;
  size_t mlp_rays = 512, mlp_samples = 128;  // the whole-network section; --mlp-rays 0 skips it
  std::string tuning;
};

Args parse(int argc, char** argv) {
  Args args;
  args.options.reps = 5;
  args.options.rounds = 2;
  if (const char* env = std::getenv("MIPNERF_DEVICE")) args.device = env;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (i + 1 >= argc) throw Error("bench_gemm: " + flag + " needs a value");
    const std::string value = argv[++i];
    if (flag == "--device") {
      args.device = value;
    } else if (flag == "--rows") {
      args.options.rows = std::stoul(value);
    } else if (flag == "--reps") {
      args.options.reps = std::max<size_t>(1, std::stoul(value));
    } else if (flag == "--rounds") {
      args.options.rounds = std::max<size_t>(1, std::stoul(value));
    } else if (flag == "--widths") {
      args.options.widths.clear();
      std::stringstream list(value);
      std::string item;
      while (std::getline(list, item, ',')) args.options.widths.push_back(std::stoul(item));
    } else if (flag == "--tuning") {
      args.tuning = value;
    } else if (flag == "--mlp-rays") {
      args.mlp_rays = std::stoul(value);
    } else if (flag == "--mlp-samples") {
      args.mlp_samples = std::max<size_t>(1, std::stoul(value));
    } else {
      throw Error("bench_gemm: unknown flag " + flag +
                  " (use --device, --rows, --widths, --reps, --rounds, --tuning, --mlp-rays, --mlp-samples)");
    }
  }
  return args;
}

// One cblas_sgemm on the operands' host copies, wall seconds.
double time_openblas(const bench::GemmProduct& product, bench::GemmOperands& operands) {
  const auto& s = product.shape;
  const int lda = static_cast<int>(s.transpose_a ? s.m : s.k), ldb = static_cast<int>(s.transpose_b ? s.k : s.n);
  return bench::time_call([&] {
    cblas_sgemm(CblasRowMajor, s.transpose_a ? CblasTrans : CblasNoTrans, s.transpose_b ? CblasTrans : CblasNoTrans,
                static_cast<int>(s.m), static_cast<int>(s.n), static_cast<int>(s.k), 1.0f, operands.a.data(), lda,
                operands.b.data(), ldb, 0.0f, operands.c.data(), static_cast<int>(s.n));
  });
}

std::string gflops_cell(const bench::GemmSeries& series, const bench::GemmProduct& product, size_t i) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.1f (%.1f)", series.gflops_best(product, i), series.gflops_median(product, i));
  return text;
}

void print_products(const ocl::Context& ctx, const bench::GemmBenchResult& r, bool tuned, const std::string& path) {
  std::string openblas = OPENBLAS_VERSION;  // " OpenBLAS 0.3.21 "
  openblas.erase(0, openblas.find_first_not_of(' '));
  openblas.erase(openblas.find_last_not_of(' ') + 1);
  std::printf("## bench_gemm: %s, CLBlast %s, %s\n\n", ctx.device_info().name.c_str(), gemm::clblast_version().c_str(),
              openblas.c_str());
  std::printf("GFLOP/s, best call of %zu rounds × %zu (median in brackets); tuned parameters: %s\n\n", r.options.rounds,
              r.options.reps, tuned ? path.c_str() : "none found (run `mipnerf-cl tune`)");
  std::printf("| product | m×n×k |");
  for (const auto& s : r.series) std::printf(" %s |", s.name.c_str());
  if (tuned) std::printf(" tuned / OpenBLAS |");
  std::printf("\n|---|---|");
  for (size_t c = 0; c < r.series.size() + (tuned ? 1 : 0); ++c) std::printf("---|");
  std::printf("\n");
  for (size_t i = 0; i < r.products.size(); ++i) {
    const auto& p = r.products[i];
    std::printf("| %s (%s) | %zu×%zu×%zu |", p.kind.c_str(), p.layout().c_str(), p.shape.m, p.shape.n, p.shape.k);
    for (const auto& s : r.series) std::printf(" %s |", gflops_cell(s, p, i).c_str());
    if (tuned) {  // series: default, tuned, OpenBLAS
      std::printf(" %.0f %% |", 100.0 * r.series[2].calls[i].best() / r.series[1].calls[i].best());
    }
    std::printf("\n");
  }
  std::printf("\nFirst call (cold start, includes CLBlast's program build for each parameter set; %s):\n\n",
              std::getenv("POCL_KERNEL_CACHE") && std::string(std::getenv("POCL_KERNEL_CACHE")) == "0"
                  ? "PoCL's kernel cache off"
                  : "PoCL's on-disk kernel cache may serve it");
  for (const auto& s : r.series) {
    std::printf("- %s:", s.name.c_str());
    for (size_t k = 0; k < std::min<size_t>(3, s.first_call_seconds.size()); ++k) {  // the first width's kinds
      std::printf(" %s %.2f s;", r.products[k].kind.c_str(), s.first_call_seconds[k]);
    }
    std::printf("\n");
  }
}

// The whole paper network (8×256, skip, view branch) on one chunk, GEMMs and mlp.cl kernels together.
void print_network(ocl::Context& ctx, const Args& args, const std::vector<bench::GemmConfig>& configs) {
  mlp::MlpConfig config;
  const auto device_network = mlp::make_network(ctx, config, gemm::GemmBackend::clblast);
  mlp::Network& net = *device_network;
  const size_t rows = args.mlp_rays * args.mlp_samples;
  const double flops_per_row = 2.0 * static_cast<double>(net.parameter_count());  // forward multiply-adds
  std::printf("\nThe paper's network on one chunk of %zu rays × %zu samples = %zu rows (best of %zu):\n\n",
              args.mlp_rays, args.mlp_samples, rows, args.options.reps);
  std::printf("| GEMM parameters | forward (training) | backward | forward (inference) | training rows/s |\n");
  std::printf("|---|---|---|---|---|\n");
  for (const auto& config : configs) {
    if (config.on_host()) continue;
    if (config.tuning) {
      gemm::install_gemm_tuning(ctx, *config.tuning);
    } else {
      gemm::clear_gemm_tuning(ctx);
    }
    const auto t = bench::time_mlp_chunk(ctx, net, args.mlp_rays, args.mlp_samples, args.options.reps);
    std::printf("| %s | %.0f ms (%.0f GFLOP/s) | %.0f ms | %.0f ms | %.0f |\n", config.name.c_str(), t.forward * 1e3,
                flops_per_row * rows / t.forward * 1e-9, t.backward * 1e3, t.inference * 1e3,
                t.training_rows_per_second());
  }
  gemm::clear_gemm_tuning(ctx);
  if (auto host = bench::host_backend_config(ctx)) {  // the same network with gemm_backend=host
    const auto host_network = mlp::make_network(ctx, config, gemm::GemmBackend::host);
    host_network->upload_params(net.download_params());
    const auto t = bench::time_mlp_chunk(ctx, *host_network, args.mlp_rays, args.mlp_samples, args.options.reps);
    std::printf("| %s | %.0f ms (%.0f GFLOP/s) | %.0f ms | %.0f ms | %.0f |\n", host->name.c_str(), t.forward * 1e3,
                flops_per_row * rows / t.forward * 1e-9, t.backward * 1e3, t.inference * 1e3,
                t.training_rows_per_second());
  }
}

}  // namespace

int main(int argc, char** argv) try {
  const Args args = parse(argc, argv);
  auto devices = ocl::list_devices();
  // A profiling queue costs nothing measurable here and lets POCL_TRACING=text time every kernel CLBlast runs.
  ocl::Context ctx(ocl::choose_device(devices, args.device), /*profiling=*/true);
  const std::string tuning_path = args.tuning.empty() ? gemm::tuning_file_path(ctx.device_info()) : args.tuning;
  const auto tuning = gemm::read_tuning(tuning_path);

  auto configs = bench::clblast_configs(tuning);
  configs.push_back({"OpenBLAS", std::nullopt, time_openblas});
  if (auto host = bench::host_backend_config(ctx)) configs.push_back(*host);  // OpenBLAS on the mapped device buffers
  const auto progress = [](const std::string& what, size_t, size_t) { std::fprintf(stderr, "%s\n", what.c_str()); };
  const auto result = bench::run_gemm_bench(ctx, args.options, configs, progress);
  print_products(ctx, result, tuning.has_value(), tuning_path);
  if (args.mlp_rays > 0) print_network(ctx, args, configs);
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "bench_gemm: error: %s\n", e.what());
  return 1;
}
