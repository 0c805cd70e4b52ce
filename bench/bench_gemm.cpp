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
#include <cblas.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "cl/buffer.hpp"
#include "cl/context.hpp"
#include "cl/error.hpp"
#include "mlp/clblast_check.hpp"
#include "mlp/gemm.hpp"
#include "mlp/gemm_tuning.hpp"
#include "mlp/mlp.hpp"

using namespace mipnerf;

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

struct Args {
  std::string device;
  size_t rows = 65536, reps = 5, rounds = 2;
  size_t mlp_rays = 512, mlp_samples = 128;  // the whole-network section; --mlp-rays 0 skips it
  std::vector<size_t> widths = {64, 128, 256};
  std::string tuning;
};

Args parse(int argc, char** argv) {
  Args args;
  if (const char* env = std::getenv("MIPNERF_DEVICE")) args.device = env;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    if (i + 1 >= argc) throw Error("bench_gemm: " + flag + " needs a value");
    const std::string value = argv[++i];
    if (flag == "--device") {
      args.device = value;
    } else if (flag == "--rows") {
      args.rows = std::stoul(value);
    } else if (flag == "--reps") {
      args.reps = std::max<size_t>(1, std::stoul(value));
    } else if (flag == "--rounds") {
      args.rounds = std::max<size_t>(1, std::stoul(value));
    } else if (flag == "--widths") {
      args.widths.clear();
      std::stringstream list(value);
      std::string item;
      while (std::getline(list, item, ',')) args.widths.push_back(std::stoul(item));
    } else if (flag == "--tuning") {
      args.tuning = value;
    } else if (flag == "--mlp-rays") {
      args.mlp_rays = std::stoul(value);
    } else if (flag == "--mlp-samples") {
      args.mlp_samples = std::max<size_t>(1, std::stoul(value));
    } else {
      throw Error("bench_gemm: unknown flag " + flag + " (use --device, --rows, --widths, --reps, --rounds, --tuning, --mlp-rays, --mlp-samples)");
    }
  }
  return args;
}

struct Shape {
  std::string kind;
  mlp::GemmShape s;
  double flops() const { return 2.0 * static_cast<double>(s.m) * s.n * s.k; }
  std::string label() const {
    return kind + " " + std::to_string(s.m) + "x" + std::to_string(s.n) + "x" + std::to_string(s.k);
  }
};

std::vector<Shape> shapes_for(const Args& args) {
  std::vector<Shape> shapes;
  for (size_t w : args.widths) {
    mlp::GemmShape f, d, g;
    f.m = d.m = args.rows;
    f.n = f.k = d.n = d.k = w;
    d.transpose_b = true;
    g.m = g.n = w;
    g.k = args.rows;
    g.transpose_a = true;
    shapes.push_back({"forward", f});
    shapes.push_back({"backward data", d});
    shapes.push_back({"backward weights", g});
  }
  return shapes;
}

struct Timings {
  std::vector<double> calls;
  double best() const { return *std::min_element(calls.begin(), calls.end()); }
  double median() const {
    auto sorted = calls;
    std::sort(sorted.begin(), sorted.end());
    return sorted[sorted.size() / 2];
  }
};

struct Buffers {
  std::vector<float> a, b, c;
  ocl::DeviceArray<float> a_dev, b_dev, c_dev;
};

double time_clblast(ocl::Context& ctx, Buffers& buf, const Shape& shape) {
  const auto& s = shape.s;
  const size_t lda = s.transpose_a ? s.m : s.k, ldb = s.transpose_b ? s.k : s.n;
  const auto start = Clock::now();
  mlp::gemm(ctx, s, 1.0f, mlp::view(buf.a_dev, lda), mlp::view(buf.b_dev, ldb), 0.0f, mlp::view(buf.c_dev, s.n),
            shape.label());
  ctx.finish();
  return seconds_since(start);
}

double time_openblas(Buffers& buf, const Shape& shape) {
  const auto& s = shape.s;
  const int lda = static_cast<int>(s.transpose_a ? s.m : s.k), ldb = static_cast<int>(s.transpose_b ? s.k : s.n);
  const auto start = Clock::now();
  cblas_sgemm(CblasRowMajor, s.transpose_a ? CblasTrans : CblasNoTrans, s.transpose_b ? CblasTrans : CblasNoTrans,
              static_cast<int>(s.m), static_cast<int>(s.n), static_cast<int>(s.k), 1.0f, buf.a.data(), lda,
              buf.b.data(), ldb, 0.0f, buf.c.data(), static_cast<int>(s.n));
  return seconds_since(start);
}

std::string gflops_cell(const Shape& shape, const Timings& t) {
  if (t.calls.empty()) return "—";
  char text[64];
  std::snprintf(text, sizeof(text), "%.1f (%.1f)", shape.flops() / t.best() * 1e-9, shape.flops() / t.median() * 1e-9);
  return text;
}

// The paper's network on one chunk (rays × samples rows): best of `reps` forward (training workspace),
// backward, and inference forward, each followed by clFinish. Seconds.
struct MlpTimes {
  double forward = 0, backward = 0, inference = 0;
};

MlpTimes time_mlp(ocl::Context& ctx, mlp::Mlp& net, size_t rays, size_t samples, size_t reps) {
  const size_t rows = rays * samples;
  const auto& c = net.config();
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> dist(-1.0f, 1.0f);
  auto random_array = [&](size_t n, const char* name) {
    std::vector<float> v(n);
    for (auto& x : v) x = dist(rng);
    ocl::DeviceArray<float> a(ctx, n, name);
    a.upload(ctx, v);
    return a;
  };
  auto features = random_array(rows * c.input_width, "features");
  auto view = random_array(rays * c.view_width, "view encoding");
  auto d_density = random_array(rows, "d_raw_density"), d_rgb = random_array(rows * 3, "d_raw_rgb");
  ocl::DeviceArray<float> density(ctx, rows, "raw_density"), rgb(ctx, rows * 3, "raw_rgb");
  auto train_ws = net.make_workspace(rows, rays, mlp::WorkspaceMode::training);
  auto infer_ws = net.make_workspace(rows, rays, mlp::WorkspaceMode::inference);
  const mlp::MlpInputs in{mlp::view(features, c.input_width), mlp::view(view, c.view_width), rays, samples};
  const mlp::MlpOutputs out{mlp::view(density, 1), mlp::view(rgb, 3)};
  const mlp::MlpOutputGradients d_out{mlp::view(d_density, 1), mlp::view(d_rgb, 3)};
  auto timed = [&](const std::function<void()>& work) {
    const auto start = Clock::now();
    work();
    ctx.finish();
    return seconds_since(start);
  };
  MlpTimes best{1e30, 1e30, 1e30};
  for (size_t r = 0; r <= reps; ++r) {  // the first pass builds programs
    const double f = timed([&] { net.forward(in, out, train_ws); });
    const double b = timed([&] { net.backward(train_ws, d_out); });
    const double i = timed([&] { net.forward(in, out, infer_ws); });
    if (r == 0) continue;
    best.forward = std::min(best.forward, f);
    best.backward = std::min(best.backward, b);
    best.inference = std::min(best.inference, i);
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) try {
  const Args args = parse(argc, argv);
  auto devices = ocl::list_devices();
  // A profiling queue costs nothing measurable here and lets POCL_TRACING=text time every kernel CLBlast runs.
  ocl::Context ctx(ocl::choose_device(devices, args.device), /*profiling=*/true);
  const auto shapes = shapes_for(args);

  const std::string tuning_path = args.tuning.empty() ? mlp::tuning_file_path(ctx.device_info()) : args.tuning;
  const auto tuning = mlp::read_tuning(tuning_path);

  size_t a_size = 0, b_size = 0, c_size = 0;
  for (const auto& shape : shapes) {
    a_size = std::max(a_size, shape.s.m * shape.s.k);
    b_size = std::max(b_size, shape.s.k * shape.s.n);
    c_size = std::max(c_size, shape.s.m * shape.s.n);
  }
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> dist(-1.0f, 1.0f);
  Buffers buf{std::vector<float>(a_size), std::vector<float>(b_size), std::vector<float>(c_size),
              ocl::DeviceArray<float>(ctx, a_size, "A"), ocl::DeviceArray<float>(ctx, b_size, "B"),
              ocl::DeviceArray<float>(ctx, c_size, "C")};
  for (auto& v : buf.a) v = dist(rng);
  for (auto& v : buf.b) v = dist(rng);
  buf.a_dev.upload(ctx, buf.a);
  buf.b_dev.upload(ctx, buf.b);

  std::vector<std::string> configs = {"CLBlast default"};
  if (tuning) configs.push_back("CLBlast tuned");
  configs.push_back("OpenBLAS");
  std::map<std::string, std::vector<Timings>> results;
  std::map<std::string, std::vector<double>> cold;  // first call of each configuration, per kind
  for (const auto& name : configs) results[name].resize(shapes.size());

  for (size_t round = 0; round < args.rounds; ++round) {
    for (const auto& name : configs) {
      if (name == "CLBlast default") mlp::clear_gemm_tuning(ctx);
      if (name == "CLBlast tuned") mlp::install_gemm_tuning(ctx, *tuning);
      for (size_t i = 0; i < shapes.size(); ++i) {
        const bool blas = name == "OpenBLAS";
        const double first = blas ? time_openblas(buf, shapes[i]) : time_clblast(ctx, buf, shapes[i]);
        if (round == 0 && i < 3) cold[name].push_back(first);  // the first shape of each kind compiles
        if (!blas) time_clblast(ctx, buf, shapes[i]);           // warm-up after a parameter switch
        for (size_t r = 0; r < args.reps; ++r) {
          results[name][i].calls.push_back(blas ? time_openblas(buf, shapes[i]) : time_clblast(ctx, buf, shapes[i]));
        }
        std::fprintf(stderr, "round %zu %-16s %-32s %s GFLOP/s\n", round + 1, name.c_str(), shapes[i].label().c_str(),
                     gflops_cell(shapes[i], results[name][i]).c_str());
      }
    }
  }
  mlp::clear_gemm_tuning(ctx);

  std::string openblas = OPENBLAS_VERSION;  // " OpenBLAS 0.3.21 "
  openblas.erase(0, openblas.find_first_not_of(' '));
  openblas.erase(openblas.find_last_not_of(' ') + 1);
  std::printf("## bench_gemm: %s, CLBlast %s, %s\n\n", ctx.device_info().name.c_str(), mlp::clblast_version().c_str(),
              openblas.c_str());
  std::printf("GFLOP/s, best call of %zu rounds × %zu (median in brackets); tuned parameters: %s\n\n", args.rounds,
              args.reps, tuning ? tuning_path.c_str() : "none found (run `mipnerf-cl tune`)");
  std::printf("| product | m×n×k |");
  for (const auto& name : configs) std::printf(" %s |", name.c_str());
  if (tuning) std::printf(" tuned / OpenBLAS |");
  std::printf("\n|---|---|");
  for (size_t c = 0; c < configs.size() + (tuning ? 1 : 0); ++c) std::printf("---|");
  std::printf("\n");
  for (size_t i = 0; i < shapes.size(); ++i) {
    const auto& s = shapes[i].s;
    std::printf("| %s%s | %zu×%zu×%zu |", shapes[i].kind.c_str(),
                s.transpose_a ? " (Aᵀ·B)" : (s.transpose_b ? " (A·Bᵀ)" : " (A·B)"), s.m, s.n, s.k);
    for (const auto& name : configs) std::printf(" %s |", gflops_cell(shapes[i], results[name][i]).c_str());
    if (tuning) {
      std::printf(" %.0f %% |", 100.0 * results["OpenBLAS"][i].best() / results["CLBlast tuned"][i].best());
    }
    std::printf("\n");
  }
  std::printf("\nFirst call (cold start, includes CLBlast's program build for each parameter set; %s):\n\n",
              std::getenv("POCL_KERNEL_CACHE") && std::string(std::getenv("POCL_KERNEL_CACHE")) == "0"
                  ? "PoCL's kernel cache off"
                  : "PoCL's on-disk kernel cache may serve it");
  for (const auto& name : configs) {
    std::printf("- %s:", name.c_str());
    const char* kinds[] = {"forward", "backward data", "backward weights"};
    for (size_t k = 0; k < cold[name].size(); ++k) std::printf(" %s %.2f s;", kinds[k], cold[name][k]);
    std::printf("\n");
  }

  if (args.mlp_rays > 0) {
    // The whole paper network (8×256, skip, view branch) on one chunk, GEMMs and mlp.cl kernels together.
    mlp::MlpConfig config;
    mlp::Mlp net(ctx, config);
    const size_t rows = args.mlp_rays * args.mlp_samples;
    const double flops_per_row = 2.0 * static_cast<double>(net.parameter_count());  // forward multiply-adds
    std::printf("\nThe paper's network on one chunk of %zu rays × %zu samples = %zu rows (best of %zu):\n\n",
                args.mlp_rays, args.mlp_samples, rows, args.reps);
    std::printf("| GEMM parameters | forward (training) | backward | forward (inference) | training rows/s |\n");
    std::printf("|---|---|---|---|---|\n");
    for (const auto& name : configs) {
      if (name == "OpenBLAS") continue;
      if (name == "CLBlast default") mlp::clear_gemm_tuning(ctx);
      if (name == "CLBlast tuned") mlp::install_gemm_tuning(ctx, *tuning);
      const MlpTimes t = time_mlp(ctx, net, args.mlp_rays, args.mlp_samples, args.reps);
      std::printf("| %s | %.0f ms (%.0f GFLOP/s) | %.0f ms | %.0f ms | %.0f |\n", name.c_str(), t.forward * 1e3,
                  flops_per_row * rows / t.forward * 1e-9, t.backward * 1e3, t.inference * 1e3,
                  rows / (t.forward + t.backward));
    }
    mlp::clear_gemm_tuning(ctx);
  }
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "bench_gemm: error: %s\n", e.what());
  return 1;
}
